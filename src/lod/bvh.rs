//! A bounding-volume hierarchy over the patches' bounding spheres, so that frustum culling
//! visits the patches inside the frustum (and the few nodes around them), not every patch of
//! the scene: the per-frame CPU cost of [`super::FrameLoop::update`] follows what the view
//! sees (issue 19; Balázs et al. §4.2 cull before they queue).
//!
//! Built once per frame loop, top-down: a node's patches are split at the median of their
//! centres along the longest axis of the centres' box, down to `LEAF_SIZE` patches. Every
//! node keeps a sphere around its patches' spheres. A query tests a node's sphere and skips
//! the whole subtree when it misses the frustum, takes the whole subtree untested when the
//! sphere lies wholly inside it (the common case of a view over the whole model); otherwise,
//! down to the leaves, every patch is tested on its own sphere with the same test as before,
//! so the patches found are exactly those a linear scan finds (tested in `tests`).

use glam::DVec3;

use crate::model::Sphere;
use crate::view::Frustum;

/// Most patches in a leaf.
pub(crate) const LEAF_SIZE: usize = 8;

/// One node: a sphere around its patches, and either two children or a range of
/// [`Bvh::order`].
#[derive(Clone, Copy, Debug)]
struct Node {
    sphere: Sphere,
    /// Leaf: `[first, first + count)` of `order`; inner node: `first` is the right child
    /// (the left child follows the node) and `count` is 0.
    first: u32,
    count: u32,
    /// The subtree's patches: `[start, end)` of `order`.
    start: u32,
    end: u32,
}

/// The hierarchy (see the module doc).
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    /// Patch indices, leaf by leaf.
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the hierarchy over `spheres` (indexed like the scene's patches).
    pub fn new(spheres: &[Sphere]) -> Bvh {
        let mut order: Vec<u32> = (0..spheres.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * spheres.len() / LEAF_SIZE + 1);
        if !spheres.is_empty() {
            build(spheres, &mut order, 0, &mut nodes);
        }
        Bvh { nodes, order }
    }

    /// Appends to `out` every patch whose sphere (`sphere(i)`, the spheres it was built on)
    /// the frustum sees, in no particular order.
    pub(crate) fn visit_seen<'a>(
        &self,
        sphere: impl Fn(usize) -> &'a Sphere,
        frustum: &Frustum,
        out: &mut Vec<u32>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            if !frustum.sees(&node.sphere) {
                continue;
            }
            if frustum.contains(&node.sphere) {
                // Every patch sphere of the subtree lies inside the node's, so inside the
                // (convex) frustum: each one would pass the test.
                out.extend_from_slice(&self.order[node.start as usize..node.end as usize]);
            } else if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                out.extend(
                    self.order[range]
                        .iter()
                        .filter(|&&i| frustum.sees(sphere(i as usize))),
                );
            } else {
                stack.push(node.first);
                stack.push(n + 1);
            }
        }
    }
}

/// Builds the subtree over `order` (patches `offset..offset + order.len()` of the final
/// order) at the end of `nodes`.
fn build(spheres: &[Sphere], order: &mut [u32], offset: u32, nodes: &mut Vec<Node>) {
    let me = nodes.len();
    nodes.push(Node {
        sphere: enclosing(order.iter().map(|&i| spheres[i as usize])),
        first: offset,
        count: order.len() as u32,
        start: offset,
        end: offset + order.len() as u32,
    });
    if order.len() <= LEAF_SIZE {
        return;
    }
    let (lo, hi) = order.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &i| {
            let c = spheres[i as usize].center;
            (lo.min(c), hi.max(c))
        },
    );
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        spheres[a as usize].center[axis].total_cmp(&spheres[b as usize].center[axis])
    });
    let (left, right) = order.split_at_mut(mid);
    build(spheres, left, offset, nodes);
    let right_node = nodes.len() as u32;
    build(spheres, right, offset + mid as u32, nodes);
    nodes[me].first = right_node;
    nodes[me].count = 0;
}

/// A sphere containing every sphere of `spheres` (centred on their centres' box; not the
/// smallest, but enclosing: culling stays conservative).
fn enclosing(spheres: impl Iterator<Item = Sphere> + Clone) -> Sphere {
    let (lo, hi) = spheres.clone().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), s| (lo.min(s.center), hi.max(s.center)),
    );
    if !lo.is_finite() || !hi.is_finite() {
        // Non-finite bounds: a sphere that every frustum sees, so nothing is culled wrongly.
        return Sphere {
            center: DVec3::ZERO,
            radius: f64::INFINITY,
        };
    }
    let center = (lo + hi) * 0.5;
    let radius = spheres
        .map(|s| center.distance(s.center) + s.radius)
        .fold(0.0, f64::max);
    // Round-off: make sure every child sphere is inside.
    Sphere {
        center,
        radius: radius * (1.0 + 1e-12) + f64::MIN_POSITIVE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::View;

    fn grid(n: usize) -> Vec<Sphere> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..3 {
                    out.push(Sphere {
                        center: DVec3::new(i as f64 * 3.0, j as f64 * 3.0, k as f64 * 0.5),
                        radius: 0.3 + 0.1 * ((i * 7 + j * 3 + k) % 5) as f64,
                    });
                }
            }
        }
        out
    }

    /// The BVH finds exactly the patches a linear scan finds, for views inside, beside and
    /// far from the patches.
    #[test]
    fn finds_what_a_linear_scan_finds() {
        let spheres = grid(30);
        let bvh = Bvh::new(&spheres);
        let model = Sphere {
            center: DVec3::new(45.0, 45.0, 0.5),
            radius: 70.0,
        };
        let eyes = [
            (DVec3::new(45.0, 45.0, 120.0), DVec3::new(45.0, 45.0, 0.0)),
            (DVec3::new(10.0, 10.0, 3.0), DVec3::new(60.0, 30.0, 0.0)),
            (DVec3::new(-20.0, 45.0, 2.0), DVec3::new(0.0, 45.0, 1.0)),
            (DVec3::new(45.0, 45.0, 2.0), DVec3::new(45.0, 45.0, 50.0)),
        ];
        let mut some_culled = false;
        for (eye, target) in eyes {
            let view = View::new(eye, target, DVec3::Z, 0.8, (640, 480), &model);
            let f = view.frustum();
            let mut found = Vec::new();
            bvh.visit_seen(|i| &spheres[i], &f, &mut found);
            found.sort_unstable();
            let linear: Vec<u32> = (0..spheres.len() as u32)
                .filter(|&i| view.sees_sphere(&spheres[i as usize]))
                .collect();
            assert_eq!(found, linear, "eye {eye}");
            some_culled |= linear.len() < spheres.len();
        }
        assert!(some_culled, "the views should cull something");
    }

    /// Every patch sits in exactly one leaf, and inside the sphere of every node above it:
    /// what makes skipping a missed subtree safe.
    #[test]
    fn every_patch_sits_in_one_leaf_inside_its_ancestors() {
        let spheres = grid(12);
        let bvh = Bvh::new(&spheres);
        let mut seen = vec![0u32; spheres.len()];
        for &i in &bvh.order {
            seen[i as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1));
        /// The patches under node `n`, each checked against the spheres of `ancestors`.
        fn check(bvh: &Bvh, spheres: &[Sphere], n: usize, ancestors: &mut Vec<Sphere>) {
            let node = bvh.nodes[n];
            ancestors.push(node.sphere);
            if node.count > 0 {
                assert!(node.count as usize <= LEAF_SIZE);
                let r = node.first as usize..(node.first + node.count) as usize;
                for &i in &bvh.order[r] {
                    let s = spheres[i as usize];
                    for a in ancestors.iter() {
                        assert!(a.center.distance(s.center) + s.radius <= a.radius);
                    }
                }
            } else {
                check(bvh, spheres, n + 1, ancestors);
                check(bvh, spheres, node.first as usize, ancestors);
            }
            ancestors.pop();
        }
        check(&bvh, &spheres, 0, &mut Vec::new());
    }
}
