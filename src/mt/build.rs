//! Building an MT hierarchy by half-edge collapses (Holst and Schumann, the
//! `holst-reduced-mt-hierarchy` paper, section 2): collapses ordered by Garland–Heckbert
//! quadric error, with heavily weighted constraint planes along the patch border (borders
//! collapse along themselves; corners turning by more than 45° stay), the link condition and
//! no flipped or degenerate triangles. One node per collapse; node error = sampled two-sided
//! Hausdorff distance between the collapse's fan and the original triangles its region covers,
//! maxed with the errors of the nodes whose triangles it removes (monotone along the DAG).
//!
//! It does not reduce the hierarchy (that is [`super::reduce`]) nor cut it ([`super::cut`]).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DMat4, DVec3, DVec4, Vec3};

use super::{MtHierarchy, NEVER};
use crate::geom::point_triangle_distance;
use crate::util::IntMap;

/// A symmetric 4×4 quadric.
#[derive(Clone, Copy, Debug, Default)]
struct Quadric(DMat4);

impl Quadric {
    fn plane(n: DVec3, p: DVec3, weight: f64) -> Quadric {
        let v = DVec4::new(n.x, n.y, n.z, -n.dot(p));
        Quadric(DMat4::from_cols(v * v.x, v * v.y, v * v.z, v * v.w) * weight)
    }
    fn eval(&self, p: DVec3) -> f64 {
        let v = p.extend(1.0);
        v.dot(self.0 * v).max(0.0)
    }
    fn add(&mut self, o: &Quadric) {
        self.0 += o.0;
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Candidate {
    cost: f64,
    from: u32,
    to: u32,
    stamp: (u32, u32),
}
impl Eq for Candidate {}
impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap on cost; ties by vertex ids for reproducibility.
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| (o.from, o.to).cmp(&(self.from, self.to)))
    }
}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Sample points of a triangle: corners, edge midpoints, centroid.
pub(super) fn samples(a: DVec3, b: DVec3, c: DVec3) -> [DVec3; 7] {
    [
        a,
        b,
        c,
        (a + b) * 0.5,
        (b + c) * 0.5,
        (c + a) * 0.5,
        (a + b + c) / 3.0,
    ]
}

impl MtHierarchy {
    /// Builds the hierarchy of a patch (`positions`, `triangles`), collapsing until no valid
    /// collapse is left.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> MtHierarchy {
        Builder::new(positions, triangles).run()
    }
}

struct Builder {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    created_by: Vec<u32>,
    removed_by: Vec<u32>,
    node_error: Vec<f64>,
    /// Original triangles each live triangle stands for.
    covers: Vec<Vec<u32>>,
    /// Live triangles around each vertex.
    around: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    /// Border vertices: the two border neighbours (fixed when it has other than two).
    border: Vec<Option<Vec<u32>>>,
    stamp: Vec<u32>,
    vertex_removed_by: Vec<u32>,
    vertex_target: Vec<u32>,
}

impl Builder {
    fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Builder {
        let pos: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
        let n = pos.len();
        let mut around = vec![Vec::new(); n];
        let mut quadric = vec![Quadric::default(); n];
        let mut edge_uses: IntMap<(u32, u32), u32> = IntMap::default();
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let cross = (b - a).cross(c - a);
            let area = cross.length() * 0.5;
            let normal = cross.normalize_or_zero();
            for k in 0..3 {
                around[tri[k] as usize].push(t as u32);
                quadric[tri[k] as usize].add(&Quadric::plane(normal, a, area));
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                *edge_uses.entry((u.min(v), u.max(v))).or_default() += 1;
            }
        }
        // Border edges: constraint planes through the edge, perpendicular to the surface,
        // weighted heavily so the border keeps its line.
        let mut border: Vec<Option<Vec<u32>>> = vec![None; n];
        for tri in triangles {
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                if edge_uses[&(u.min(v), u.max(v))] != 1 {
                    continue;
                }
                let (pu, pv) = (pos[u as usize], pos[v as usize]);
                let along = pv - pu;
                let side = along.cross(normal).normalize_or_zero();
                let q = Quadric::plane(side, pu, 1e3 * along.length_squared().max(1e-30));
                for (x, y) in [(u, v), (v, u)] {
                    quadric[x as usize].add(&q);
                    border[x as usize].get_or_insert_with(Vec::new).push(y);
                }
            }
        }
        let m = triangles.len();
        Builder {
            pos,
            tris: triangles.to_vec(),
            created_by: vec![0; m],
            removed_by: vec![NEVER; m],
            node_error: vec![0.0],
            covers: (0..m as u32).map(|t| vec![t]).collect(),
            around,
            quadric,
            border,
            stamp: vec![0; n],
            vertex_removed_by: vec![NEVER; n],
            vertex_target: (0..n as u32).collect(),
        }
    }

    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut out: Vec<u32> = self.around[v as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&w| w != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Cost of moving `from` onto `to`, or `None` when the collapse is not allowed.
    fn candidate(&self, from: u32, to: u32) -> Option<Candidate> {
        let (f, t) = (from as usize, to as usize);
        // Border vertices move only along the border, onto a border neighbour; border
        // vertices with other than two border edges (corners, non-manifold) stay.
        if let Some(nb) = &self.border[f] {
            if nb.len() != 2 || !nb.contains(&to) {
                return None;
            }
            // Corners (the border turns by more than 45°) stay.
            let (a, b) = (self.pos[nb[0] as usize], self.pos[nb[1] as usize]);
            let (d0, d1) = (
                (self.pos[f] - a).normalize_or_zero(),
                (b - self.pos[f]).normalize_or_zero(),
            );
            if d0.dot(d1) < std::f64::consts::FRAC_1_SQRT_2 {
                return None;
            }
        }
        // An interior vertex may not move onto the border (it would pinch the patch).
        if self.border[f].is_none() && self.border[t].is_some() {
            return None;
        }
        // Link condition: the common neighbours are exactly the apexes of the shared edge.
        let shared: Vec<u32> = self.around[f]
            .iter()
            .copied()
            .filter(|&tr| self.tris[tr as usize].contains(&to))
            .collect();
        if shared.is_empty() {
            return None;
        }
        let nf = self.neighbours(from);
        let nt = self.neighbours(to);
        let common = nf.iter().filter(|w| nt.binary_search(w).is_ok()).count();
        if common != shared.len() {
            return None;
        }
        // No triangle may flip or degenerate.
        for &tr in &self.around[f] {
            let tri = self.tris[tr as usize];
            if tri.contains(&to) {
                continue;
            }
            let [a, b, c] = tri.map(|i| self.pos[i as usize]);
            let before = (b - a).cross(c - a);
            let moved = tri.map(|i| {
                if i == from {
                    self.pos[t]
                } else {
                    self.pos[i as usize]
                }
            });
            let after = (moved[1] - moved[0]).cross(moved[2] - moved[0]);
            if after.length_squared() <= 1e-24 * before.length_squared().max(1e-300)
                || after.normalize_or_zero().dot(before.normalize_or_zero()) < 0.2
            {
                return None;
            }
        }
        let mut q = self.quadric[f];
        q.add(&self.quadric[t]);
        Some(Candidate {
            cost: q.eval(self.pos[t]),
            from,
            to,
            stamp: (self.stamp[f], self.stamp[t]),
        })
    }

    fn run(mut self) -> MtHierarchy {
        let mut heap = BinaryHeap::new();
        for v in 0..self.pos.len() as u32 {
            for w in self.neighbours(v) {
                if let Some(c) = self.candidate(v, w) {
                    heap.push(c);
                }
            }
        }
        while let Some(c) = heap.pop() {
            if c.stamp != (self.stamp[c.from as usize], self.stamp[c.to as usize]) {
                continue;
            }
            // Re-validate (neighbourhoods changed since it was queued without a stamp bump
            // of these two vertices only if untouched; stamps guard that).
            let Some(c) = self.candidate(c.from, c.to) else {
                continue;
            };
            self.collapse(c.from, c.to);
            let touched = self.neighbours(c.to);
            for &w in touched.iter().chain(std::iter::once(&c.to)) {
                self.stamp[w as usize] += 1;
            }
            // Every edge at a touched vertex, once, both directions.
            let mut edges: Vec<(u32, u32)> = Vec::new();
            for &w in touched.iter().chain(std::iter::once(&c.to)) {
                edges.extend(self.neighbours(w).into_iter().map(|x| (w.min(x), w.max(x))));
            }
            edges.sort_unstable();
            edges.dedup();
            for (a, b) in edges {
                for (x, y) in [(a, b), (b, a)] {
                    if let Some(c) = self.candidate(x, y) {
                        heap.push(c);
                    }
                }
            }
        }
        let mut h = MtHierarchy {
            triangles: self.tris,
            created_by: self.created_by,
            removed_by: self.removed_by,
            node_error: self.node_error,
            vertex_removed_by: self.vertex_removed_by,
            vertex_target: self.vertex_target,
            ..Default::default()
        };
        h.layout();
        h
    }

    /// Moves `from` onto `to`: one node of the hierarchy.
    fn collapse(&mut self, from: u32, to: u32) {
        let node = self.node_error.len() as u32;
        let removed: Vec<u32> = self.around[from as usize].clone();
        self.vertex_removed_by[from as usize] = node;
        self.vertex_target[from as usize] = to;
        let mut region: Vec<u32> = Vec::new();
        let mut inherited = 0.0f64;
        for &t in &removed {
            self.removed_by[t as usize] = node;
            inherited = inherited.max(self.node_error[self.created_by[t as usize] as usize]);
            region.append(&mut self.covers[t as usize]);
            for v in self.tris[t as usize] {
                self.around[v as usize].retain(|&x| x != t);
            }
        }
        let mut fan = Vec::new();
        for &t in &removed {
            let tri = self.tris[t as usize];
            if tri.contains(&to) {
                continue;
            }
            let new = tri.map(|i| if i == from { to } else { i });
            let id = self.tris.len() as u32;
            self.tris.push(new);
            self.created_by.push(node);
            self.removed_by.push(NEVER);
            self.covers.push(Vec::new());
            for v in new {
                self.around[v as usize].push(id);
            }
            fan.push(id);
        }
        let q = self.quadric[from as usize];
        self.quadric[to as usize].add(&q);
        if let Some(nb) = self.border[from as usize].take() {
            // `to` takes over `from`'s other border neighbour.
            let other = nb.iter().copied().find(|&x| x != to);
            if let (Some(other), Some(tb)) = (other, self.border[to as usize].as_mut()) {
                for x in tb.iter_mut() {
                    if *x == from {
                        *x = other;
                    }
                }
                if let Some(ob) = self.border[other as usize].as_mut() {
                    for x in ob.iter_mut() {
                        if *x == from {
                            *x = to;
                        }
                    }
                }
            }
        }
        let error = self.hausdorff(&fan, &region);
        // Assign every covered original triangle to the nearest triangle of the fan.
        for o in region {
            let c = self.centroid(self.tris[o as usize]);
            let best = fan
                .iter()
                .copied()
                .min_by(|&a, &b| self.dist(c, a).total_cmp(&self.dist(c, b)));
            if let Some(b) = best {
                self.covers[b as usize].push(o);
            }
        }
        self.node_error.push(error.max(inherited));
    }

    fn centroid(&self, t: [u32; 3]) -> DVec3 {
        t.map(|i| self.pos[i as usize]).iter().sum::<DVec3>() / 3.0
    }

    fn dist(&self, p: DVec3, t: u32) -> f64 {
        let [a, b, c] = self.tris[t as usize].map(|i| self.pos[i as usize]);
        point_triangle_distance(p, a, b, c)
    }

    /// Sampled two-sided Hausdorff distance between the triangles `fan` and the original
    /// triangles `region`. A sample stops scanning as soon as it finds a triangle no farther
    /// than the worst distance so far (it cannot raise the maximum): exact, and most samples
    /// stop at once.
    fn hausdorff(&self, fan: &[u32], region: &[u32]) -> f64 {
        let mut worst = 0.0f64;
        let farthest = |from: &[u32], to: &[u32], worst: &mut f64| {
            for &t in from {
                let [a, b, c] = self.tris[t as usize].map(|i| self.pos[i as usize]);
                for s in samples(a, b, c) {
                    let mut best = f64::INFINITY;
                    for &o in to {
                        best = best.min(self.dist(s, o));
                        if best <= *worst {
                            break;
                        }
                    }
                    if best.is_finite() {
                        *worst = worst.max(best);
                    }
                }
            }
        };
        farthest(fan, region, &mut worst);
        farthest(region, fan, &mut worst);
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{bumpy, edges_used, sampled_hausdorff};
    use super::*;
    use crate::model::mesh::border_loops;

    #[test]
    fn errors_are_monotone_along_the_dag() {
        let m = bumpy(12);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        assert!(h.node_count() > 100, "{} nodes", h.node_count());
        for t in 0..h.triangles.len() {
            let (c, r) = (h.created_by[t], h.removed_by[t]);
            if r != NEVER {
                assert!(c < r, "arc goes back in time");
                assert!(h.node_error[c as usize] <= h.node_error[r as usize]);
            }
        }
    }

    #[test]
    fn every_cut_is_a_triangulation_of_the_patch_within_its_error() {
        let m = bumpy(12);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        let original_border: f64 = 12.0 * 4.0 * 0.25; // perimeter of the 3 × 3 square
        let mut errors: Vec<f64> = h.node_error.clone();
        errors.sort_by(f64::total_cmp);
        let mut cut = Vec::new();
        for q in [0.0, 0.1, 0.3, 0.6, 0.9, 1.0] {
            let eps = errors[((errors.len() - 1) as f64 * q) as usize];
            let achieved = h.cut(eps, &mut cut);
            assert!(achieved <= eps);
            // No overlaps, no holes: every edge used once (border) or twice (inside), and
            // exactly one border loop around the square.
            let uses = edges_used(&cut);
            assert!(uses.values().all(|&u| u <= 2), "overlap at ε {eps}");
            let loops = border_loops(&cut);
            assert_eq!(loops.len(), 1, "ε {eps}: {} border loops", loops.len());
            // Corners stay, so the border keeps the square's outline: same length.
            let ring = &loops[0];
            let len: f64 = (0..ring.len())
                .map(|k| {
                    let a = m.positions[ring[k] as usize].as_dvec3();
                    let b = m.positions[ring[(k + 1) % ring.len()] as usize].as_dvec3();
                    a.distance(b)
                })
                .sum();
            assert!(
                (len - original_border).abs() < 0.05 * original_border,
                "border length {len} at ε {eps}"
            );
            // Area is kept (a hole would lose some).
            let area: f64 = cut
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                    let n = (b - a).cross(c - a);
                    0.5 * DVec3::new(0.0, 0.0, 1.0).dot(n).abs()
                })
                .sum();
            assert!(
                (area - 9.0).abs() < 0.02,
                "projected area {area} at ε {eps}"
            );
        }
        // The coarsest cut is much smaller than the original.
        let coarsest = h.cut(f64::INFINITY, &mut cut);
        assert!(
            cut.len() * 10 < m.triangles.len(),
            "{} triangles",
            cut.len()
        );
        assert!(coarsest >= 0.0);
    }

    #[test]
    fn cut_triangles_hold_the_hausdorff_bound() {
        let m = bumpy(10);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
        let mut cut = Vec::new();
        for eps in [0.002, 0.01, 0.05] {
            let achieved = h.cut(eps, &mut cut);
            let worst = sampled_hausdorff(&pos, &cut, &m.triangles);
            assert!(
                worst <= eps + 1e-9,
                "ε {eps}: Hausdorff {worst} (achieved {achieved})"
            );
        }
    }
}
