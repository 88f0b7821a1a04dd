//! Instanced parts in the frame loop: a part placed k times (bolts, nuts, screws) has k
//! patches per face, all on one shared surface with different placements. Its tessellation
//! at a level depends only on the surface, the level's ε and how much the placement scales
//! lengths ([`shared_surface`]), so it is made once, in the surface's own coordinates, and
//! each placement gets an [`Instance`] of it ([`placed`]): the placement and the errors, no
//! vertices of its own — its world-space copy ([`PatchMesh::world`]) is the same mesh,
//! vertex for vertex, that tessellating the patch itself gives (tested in
//! `tests/frame_loop_scale.rs`). The loop then holds each shared tessellation once, however
//! many placements draw it, and re-tessellating a placement costs no copy.
//!
//! Bézier files (`.bpt`) have no placements, but a model made of copies of one part (the
//! teapot grid of issue 19) repeats the same control points, translated. Bézier patches whose
//! control points agree after translation (to within [`TRANSLATION_TOLERANCE`] × the model's
//! diagonal, checked exactly after grouping) share too: a copy is an instance of the first
//! patch's tessellation, translated, and its error grows by the largest control-point difference —
//! a bound, since the difference of two Bézier patches is the Bézier patch of their control
//! points' differences (convex hull property).
//!
//! Shared tessellations are kept while some placement asks for them: an entry unused for
//! [`KEEP_FRAMES`] frames is dropped. Mesh patches are never shared.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use rayon::prelude::*;

use super::Levels;
use crate::model::Scene;
use crate::mt::CutState;
use crate::tessellate::{Instance, PatchMesh, Tessellators, instance_of, placed, shared_surface};

/// Frames a shared tessellation is kept without being asked for.
pub const KEEP_FRAMES: u64 = 16;

/// Bézier patches whose translated control points differ by at most this fraction of the
/// model's diagonal share a tessellation.
pub const TRANSLATION_TOLERANCE: f64 = 1e-9;

/// What placements share: a surface placed with a scale ([`shared_surface`]), or a class of
/// Bézier patches equal up to translation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum SurfaceKey {
    Placed(usize, u64),
    Translated(u32),
}

/// How patch `i` gets its mesh from its class's tessellation: moved by its placement, or
/// translated from the class's first patch (`delta`, world units) with `deviation` added to
/// its error.
#[derive(Clone, Copy, Debug)]
struct Share {
    key: SurfaceKey,
    /// The patch whose tessellation the class shares (the first of its class).
    source: u32,
    delta: glam::DVec3,
    deviation: f64,
}

/// The shared tessellations of one frame loop (per-view state, like the rest of it).
#[derive(Debug, Default)]
pub(super) struct SharedTessellations {
    /// Per patch: what it shares, when at least one other patch shares it.
    keys: Vec<Option<Share>>,
    /// Unplaced tessellations by surface and level, with the frame they were last asked for.
    meshes: HashMap<(SurfaceKey, i32), (Arc<PatchMesh>, u64)>,
    frame: u64,
    /// Patches that got a copy instead of a tessellation of their own, since the start.
    pub(super) saved: u64,
    /// Tessellations made for shared surfaces, since the start.
    pub(super) made: u64,
}

impl SharedTessellations {
    /// Finds the shared surfaces of `scene` (none unless `enabled`).
    pub(super) fn new(scene: &Scene, enabled: bool) -> SharedTessellations {
        if !enabled {
            return SharedTessellations {
                keys: vec![None; scene.patches.len()],
                ..Default::default()
            };
        }
        let mut keys: Vec<Option<Share>> = scene
            .patches
            .iter()
            .map(|p| {
                shared_surface(p).map(|(a, s)| Share {
                    key: SurfaceKey::Placed(a, s),
                    source: p.id,
                    delta: glam::DVec3::ZERO,
                    deviation: 0.0,
                })
            })
            .collect();
        translated_classes(scene, &mut keys);
        let mut count: HashMap<SurfaceKey, u32> = HashMap::new();
        for k in keys.iter().flatten() {
            *count.entry(k.key).or_default() += 1;
        }
        let keys = keys
            .into_iter()
            .map(|k| k.filter(|k| count[&k.key] > 1))
            .collect();
        SharedTessellations {
            keys,
            ..Default::default()
        }
    }

    /// Patches whose surface another patch shares.
    pub(super) fn shared_patches(&self) -> usize {
        self.keys.iter().filter(|k| k.is_some()).count()
    }

    /// Tessellates patch `i` at level `l` for every `(i, l)` of `jobs`, in parallel: shared
    /// surfaces once per level (or not at all when kept from an earlier frame), the others
    /// on their own (mesh patches moving their cut in `cuts`, one per job).
    pub(super) fn tessellate(
        &mut self,
        scene: &Scene,
        levels: &Levels,
        jobs: &[(usize, i32)],
        cuts: &mut [Option<CutState>],
    ) -> Vec<PatchMesh> {
        let frame = self.frame;
        let mut missing = Vec::new();
        let mut asked = HashSet::new();
        let mut copies = 0u64;
        for &(i, level) in jobs {
            let Some(share) = self.keys.get(i).copied().flatten() else {
                continue;
            };
            copies += 1;
            let key = (share.key, level);
            match self.meshes.get_mut(&key) {
                Some(entry) => entry.1 = frame,
                None => {
                    if asked.insert(key) {
                        missing.push((key, share.source as usize));
                    }
                }
            }
        }
        let made: Vec<PatchMesh> = missing
            .par_iter()
            .map_init(Tessellators::new, |t, &((key, level), i)| {
                let mut mesh = PatchMesh::default();
                match key {
                    SurfaceKey::Placed(..) => {
                        t.unplaced(&scene.patches[i], levels.eps(level), &mut mesh)
                    }
                    SurfaceKey::Translated(_) => {
                        t.patch(&scene.patches[i], levels.eps(level), &mut mesh)
                    }
                }
                mesh
            })
            .collect();
        self.made += made.len() as u64;
        self.saved += copies - made.len() as u64;
        for ((key, _), mesh) in missing.into_iter().zip(made) {
            self.meshes.insert(key, (Arc::new(mesh), frame));
        }
        let (keys, meshes) = (&self.keys, &self.meshes);
        jobs.par_iter()
            .zip(cuts.par_iter_mut())
            .map_init(Tessellators::new, |t, (&(i, level), cut)| {
                let patch = &scene.patches[i];
                match keys.get(i).copied().flatten() {
                    Some(share) => {
                        let shared = &meshes[&(share.key, level)].0;
                        match share.key {
                            SurfaceKey::Placed(..) => placed(shared, patch),
                            SurfaceKey::Translated(_) => translated(shared, patch, &share),
                        }
                    }
                    None => {
                        let mut mesh = PatchMesh::default();
                        t.patch_from(patch, levels.eps(level), cut, &mut mesh);
                        mesh
                    }
                }
            })
            .collect()
    }

    /// Bytes of the shared tessellations kept but not in `used` (addresses of those an
    /// instance holds), as [`super::FrameLoop::memory`] counts them.
    pub(super) fn unused_bytes(&self, used: &HashSet<*const PatchMesh>) -> usize {
        self.meshes
            .values()
            .map(|(m, _)| m)
            .filter(|m| !used.contains(&Arc::as_ptr(m)))
            .map(|m| 2 * std::mem::size_of::<usize>() + m.mem_bytes())
            .sum()
    }

    /// Ends a frame: drops the shared tessellations nobody asked for in [`KEEP_FRAMES`].
    pub(super) fn end_frame(&mut self) {
        let frame = self.frame;
        self.meshes
            .retain(|_, (_, used)| *used + KEEP_FRAMES > frame);
        self.frame += 1;
    }
}

/// `patch`'s mesh from `source` (the tessellation of the first patch of `share`'s class):
/// an [`Instance`] of `source` translated by `share.delta`, its error raised by
/// `share.deviation` (no geometry of its own, [`PatchMesh::world`]); a failed `source` is
/// copied as it is.
fn translated(source: &Arc<PatchMesh>, patch: &crate::model::Patch, share: &Share) -> PatchMesh {
    if source.failure.is_some() {
        return PatchMesh {
            patch_id: patch.id,
            color: patch.color,
            ..PatchMesh::clone(source)
        };
    }
    instance_of(
        source,
        Instance {
            shared: source.clone(),
            transform: glam::DMat4::from_translation(share.delta),
            error_added: share.deviation,
        },
        patch,
    )
}

/// Groups the Bézier patches of `scene` whose control points agree after translation (module
/// doc) and marks them in `keys`: the first of each class is its source.
fn translated_classes(scene: &Scene, keys: &mut [Option<Share>]) {
    use crate::model::PatchSurface;
    let quantum = (scene.bbox_diagonal() * TRANSLATION_TOLERANCE).max(f64::MIN_POSITIVE);
    let mut classes: HashMap<(usize, usize, Vec<i64>), (u32, u32)> = HashMap::new();
    for (i, p) in scene.patches.iter().enumerate() {
        let PatchSurface::Bezier(b) = &p.surface else {
            continue;
        };
        let cps = b.control_points();
        let origin = cps[0];
        let shape: Vec<i64> = cps
            .iter()
            .flat_map(|c| (*c - origin).to_array())
            .map(|x| (x / quantum).round() as i64)
            .collect();
        let (du, dv) = b.degree();
        let next = classes.len() as u32;
        let &mut (class, source) = classes.entry((du, dv, shape)).or_insert((next, i as u32));
        let deviation = match &scene.patches[source as usize].surface {
            PatchSurface::Bezier(s) => {
                let s_origin = s.control_points()[0];
                cps.iter()
                    .zip(s.control_points())
                    .map(|(c, sc)| ((*c - origin) - (*sc - s_origin)).length())
                    .fold(0.0, f64::max)
            }
            _ => 0.0,
        };
        let delta = origin
            - match &scene.patches[source as usize].surface {
                PatchSurface::Bezier(s) => s.control_points()[0],
                _ => origin,
            };
        keys[i] = Some(Share {
            key: SurfaceKey::Translated(class),
            source,
            delta,
            deviation,
        });
    }
}
