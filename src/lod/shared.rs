//! Instanced parts in the frame loop: a part placed k times (bolts, nuts, screws) has k
//! patches per face, all on one shared surface with different placements. Its tessellation
//! at a level depends only on the surface, the level's ε and how much the placement scales
//! lengths ([`shared_surface`]), so it is made once, in the surface's own coordinates, and
//! each placement gets a moved copy ([`placed`]) — the same mesh, vertex for vertex, that
//! tessellating the patch itself gives (tested in `tests/lod.rs`).
//!
//! Shared tessellations are kept while some placement asks for them: an entry unused for
//! [`KEEP_FRAMES`] frames is dropped. Mesh and Bézier patches are never shared.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use rayon::prelude::*;

use super::Levels;
use crate::model::Scene;
use crate::mt::CutState;
use crate::tessellate::{PatchMesh, Tessellators, placed, shared_surface};

/// Frames a shared tessellation is kept without being asked for.
pub const KEEP_FRAMES: u64 = 16;

/// A shared surface and its placement's scale ([`shared_surface`]).
type SurfaceKey = (usize, u64);

/// The shared tessellations of one frame loop (per-view state, like the rest of it).
#[derive(Debug, Default)]
pub(super) struct SharedTessellations {
    /// Per patch: its surface, when at least one other patch shares it.
    keys: Vec<Option<SurfaceKey>>,
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
        let keys: Vec<Option<SurfaceKey>> = scene
            .patches
            .iter()
            .map(|p| shared_surface(p).filter(|_| enabled))
            .collect();
        let mut count: HashMap<SurfaceKey, u32> = HashMap::new();
        for k in keys.iter().flatten() {
            *count.entry(*k).or_default() += 1;
        }
        let keys = keys
            .into_iter()
            .map(|k| k.filter(|k| count[k] > 1))
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
            let Some(k) = self.keys.get(i).copied().flatten() else {
                continue;
            };
            copies += 1;
            let key = (k, level);
            match self.meshes.get_mut(&key) {
                Some(entry) => entry.1 = frame,
                None => {
                    if asked.insert(key) {
                        missing.push((key, i));
                    }
                }
            }
        }
        let made: Vec<PatchMesh> = missing
            .par_iter()
            .map_init(Tessellators::new, |t, &((_, level), i)| {
                let mut mesh = PatchMesh::default();
                t.unplaced(&scene.patches[i], levels.eps(level), &mut mesh);
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
                    Some(k) => placed(&meshes[&(k, level)].0, patch),
                    None => {
                        let mut mesh = PatchMesh::default();
                        t.patch_from(patch, levels.eps(level), cut, &mut mesh);
                        mesh
                    }
                }
            })
            .collect()
    }

    /// Ends a frame: drops the shared tessellations nobody asked for in [`KEEP_FRAMES`].
    pub(super) fn end_frame(&mut self) {
        let frame = self.frame;
        self.meshes
            .retain(|_, (_, used)| *used + KEEP_FRAMES > frame);
        self.frame += 1;
    }
}
