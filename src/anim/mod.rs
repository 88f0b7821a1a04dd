//! Implosion and explosion animations (Balázs, Guthe and Klein, "Fat Borders", §5: the
//! wheel-rim implosion, where patches change neighbours every frame and no precomputed
//! stitching could hold).
//!
//! Every group — a placed part of an assembly, or every single patch — moves along a straight
//! path from an exploded position to its assembled one: its offset at full explosion points
//! from the model's centre to the group's centre (a fixed spread of directions for a group at
//! the centre), and grows with the group's distance from the centre, so outer parts fly
//! farther and nothing swaps sides: `offset = dir · R · distance · (½ + |c_g − c| / R)` with R
//! the model's radius. Frames follow a cubic ease-in-out.
//!
//! Patches are tessellated where they are assembled (their surfaces never change, so the LOD
//! frame loop's cached tessellations stay valid) with the ε of where they are drawn (their
//! bounding spheres are moved: `moved_scene`), and translated when uploaded
//! ([`translated`]; a translation keeps every error). Fat borders are recomputed from each
//! frame's meshes, so they hold whichever neighbours a patch has in that frame.

use glam::DVec3;

use crate::model::{Scene, Sphere};
use crate::tessellate::PatchMesh;

/// What moves as one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GroupBy {
    /// Every placed part of an assembly (a part placed twice moves as two groups).
    #[default]
    Parts,
    /// Every patch on its own.
    Patches,
}

impl std::str::FromStr for GroupBy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "parts" => Ok(GroupBy::Parts),
            "patches" => Ok(GroupBy::Patches),
            _ => Err(format!("expected parts or patches, got {s:?}")),
        }
    }
}

/// Offsets of every patch at full explosion.
#[derive(Clone, Debug, PartialEq)]
pub struct Explosion {
    /// Per patch (indexed like the scene's patches).
    pub offsets: Vec<DVec3>,
    /// Number of groups that move.
    pub groups: usize,
}

/// Evenly spread unit directions (a Fibonacci sphere), for groups at the model's centre.
fn spread(i: usize, n: usize) -> DVec3 {
    let n = n.max(1) as f64;
    let z = 1.0 - 2.0 * (i as f64 + 0.5) / n;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

impl Explosion {
    /// Groups the patches of `scene` and gives each group its offset; `distance` scales the
    /// offsets (× the model's radius; 1 moves a group at the centre by one radius).
    pub fn new(scene: &Scene, by: GroupBy, distance: f64) -> Explosion {
        let n = scene.patches.len();
        // Group of every patch.
        let mut keys: Vec<(u32, [u64; 16])> = Vec::new();
        let group: Vec<usize> = scene
            .patches
            .iter()
            .enumerate()
            .map(|(i, p)| match by {
                GroupBy::Patches => i,
                GroupBy::Parts => {
                    let key = (p.part, p.transform.to_cols_array().map(f64::to_bits));
                    match keys.iter().position(|k| *k == key) {
                        Some(g) => g,
                        None => {
                            keys.push(key);
                            keys.len() - 1
                        }
                    }
                }
            })
            .collect();
        let groups = match by {
            GroupBy::Patches => n,
            GroupBy::Parts => keys.len(),
        };
        let mut spheres: Vec<Vec<Sphere>> = vec![Vec::new(); groups];
        for (p, &g) in scene.patches.iter().zip(&group) {
            spheres[g].push(p.bounds);
        }
        let centre = scene.bounds.center;
        let radius = scene.bounds.radius.max(1e-300);
        let group_offsets: Vec<DVec3> = spheres
            .iter()
            .enumerate()
            .map(|(g, s)| {
                let c = Sphere::union(s).center;
                let away = c - centre;
                let dir = if away.length() > 1e-3 * radius {
                    away.normalize()
                } else {
                    spread(g, groups)
                };
                dir * radius * distance * (0.5 + away.length() / radius)
            })
            .collect();
        Explosion {
            offsets: group.iter().map(|&g| group_offsets[g]).collect(),
            groups,
        }
    }

    /// Offsets when the explosion is `amount` done (0 = assembled, 1 = fully exploded).
    pub fn at(&self, amount: f64) -> Vec<DVec3> {
        self.offsets.iter().map(|o| *o * amount).collect()
    }

    /// A sphere holding every patch at every amount of the explosion (for framing).
    pub fn bounds(&self, scene: &Scene) -> Sphere {
        let mut all: Vec<Sphere> = scene.patches.iter().map(|p| p.bounds).collect();
        all.extend(
            scene
                .patches
                .iter()
                .zip(&self.offsets)
                .map(|(p, o)| Sphere {
                    center: p.bounds.center + *o,
                    radius: p.bounds.radius,
                }),
        );
        Sphere::union(&all)
    }
}

/// Cubic ease-in-out on [0, 1].
pub fn ease(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    if t < 0.5 {
        4.0 * t * t * t
    } else {
        1.0 - (-2.0 * t + 2.0).powi(3) / 2.0
    }
}

/// How far exploded frame `k` of `n` is: an implosion runs from 1 (exploded) to 0
/// (assembled), an explosion the other way; both eased.
pub fn amount(k: usize, n: usize, explode: bool) -> f64 {
    let t = if n <= 1 {
        1.0
    } else {
        k as f64 / (n - 1) as f64
    };
    let e = ease(t);
    if explode { e } else { 1.0 - e }
}

/// `scene` with every patch's bounding sphere moved by its offset (the surfaces stay where
/// they are assembled): ε and culling for where the patches are drawn.
pub(crate) fn moved_scene(scene: &Scene, offsets: &[DVec3]) -> Scene {
    let mut s = scene.clone();
    for (p, o) in s.patches.iter_mut().zip(offsets) {
        p.bounds.center += *o;
    }
    let spheres: Vec<Sphere> = s.patches.iter().map(|p| p.bounds).collect();
    s.bounds = Sphere::union(&spheres);
    s
}

/// Copies of `meshes` (with their patch indices) translated by their patch's offset. Moved
/// mesh-patch cuts are marked [`CutRanges::moved`](crate::tessellate::CutRanges::moved): the
/// static buffers hold the assembled positions, so they are uploaded (as triangles, or with
/// their multiresolution / repaired strips at the cut's level).
pub fn translated<'a>(
    meshes: impl IntoIterator<Item = (usize, &'a PatchMesh)>,
    offsets: &[DVec3],
) -> Vec<PatchMesh> {
    meshes
        .into_iter()
        .map(|(i, m)| {
            let o = offsets.get(i).copied().unwrap_or(DVec3::ZERO);
            if o == DVec3::ZERO {
                return m.clone();
            }
            let o = o.as_vec3();
            let mut moved = m.clone();
            for p in moved.positions.iter_mut() {
                *p += o;
            }
            if let Some(cut) = moved.arcs.as_mut() {
                cut.moved = true;
            }
            moved
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn easing_starts_and_ends_at_rest() {
        assert_eq!(ease(0.0), 0.0);
        assert_eq!(ease(1.0), 1.0);
        assert!((ease(0.5) - 0.5).abs() < 1e-12);
        // Slow at both ends, monotone.
        assert!(ease(0.05) < 0.05 && ease(0.95) > 0.95);
        let mut last = 0.0;
        for k in 0..=100 {
            let e = ease(k as f64 / 100.0);
            assert!(e >= last);
            last = e;
        }
        assert_eq!(amount(0, 10, false), 1.0);
        assert_eq!(amount(9, 10, false), 0.0);
        assert_eq!(amount(0, 10, true), 0.0);
        assert_eq!(amount(9, 10, true), 1.0);
    }

    #[test]
    fn spread_directions_are_unit_and_distinct() {
        let d: Vec<DVec3> = (0..20).map(|i| spread(i, 20)).collect();
        for (i, a) in d.iter().enumerate() {
            assert!((a.length() - 1.0).abs() < 1e-9);
            for b in &d[i + 1..] {
                assert!(a.distance(*b) > 0.1);
            }
        }
    }
}
