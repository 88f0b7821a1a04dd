//! View-dependent level of detail with a load-balanced re-tessellation queue.
//!
//! After Balázs, Guthe and Klein, "Fat Borders" (2004), §4.2: per frame, only patches visible
//! in the previous frame (patch-ID buffer) and inside the frustum are considered; those whose
//! current tessellation error ε_c is off the error the view now wants, ε_w, go into a priority
//! queue, and are re-tessellated from the top until the frame's time budget (default 40 ms,
//! as in the paper) is spent, by the rayon workers, which take the jobs in queue order. Fat
//! borders always use each patch's *current* ε_c, so the picture stays crack-free while the
//! queue catches up.
//!
//! **Order** (`priority`). The paper weighs a patch by (ε_c/ε_w)² when too coarse and by
//! ε_w/ε_c when too fine, so a patch far too fine could go before one slightly too coarse,
//! and a tiny patch before a large one. Here the queue takes the patches that are too coarse
//! first, by what their error shows: screen error (pixels, γ·ε_c/ε_w) × screen area
//! (pixels², the bounding sphere's disc, π(γ·r/ε_w)²), so a frame the budget cuts short still
//! fixes what is most visible; the patches that are only too fine (no visible error, only
//! triangles to save) come after all of them, the most wasteful first.
//!
//! **Ahead on a still camera.** Hidden patches in the frustum that are too coarse are not
//! queued (the paper's rule), but when the view is the last frame's they take what the
//! visible queue leaves of the budget, in the same order: after a jump the first frame
//! discovers what is visible from the new place and the next one refines it, so whatever the
//! refined surfaces uncover, or the jump's frame showed for the first time behind them, is
//! ready without waiting a frame more to be seen (`UpdateStats::ahead`).
//!
//! **Reuse within ε.** A trimmed face's tessellation made at level ε_m may hold a finer level
//! too: a plane bounded by lines is exact at every ε. When its measured errors (surface
//! samples within `REFINE_TARGET`·ε, trim chords within ε/2: the standard a fresh
//! tessellation is made to) hold the wanted level, the patch keeps its triangles, relabelled
//! to that level's ε (fat borders as wide as the new ε), instead of tessellating again.
//!
//! **Levels and hysteresis** (Pajon, "LOD overview", on avoiding flicker between levels):
//! tessellations are made only at discrete errors ε_k = unit · √2^k, the largest one ≤ ε_w,
//! so a fresh tessellation has ε_w/√2 < ε_c ≤ ε_w. A patch is too coarse as soon as
//! ε_c > ε_w, but too fine only once ε_c < ε_w / [`LodOptions::coarsen_factor`] (default 2):
//! a camera moving back and forth within that band never re-tessellates. Each patch keeps its
//! last few levels ([`LodOptions::cache_levels`]); going back to a cached level costs nothing.
//! The cached levels of all patches together stay within [`LodOptions::cache_bytes`], least
//! recently used evicted first (`lod::cache`).
//!
//! **Frame-rate target** (Pajon, after Funkhouser and Séquin's benefit/cost): see
//! `PixelErrorController`.

pub mod bvh;
mod cache;
mod shared;

use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::model::{PatchSurface, Scene};
use crate::mt::CutState;
use crate::tessellate::PatchMesh;
use crate::view::View;
use cache::{Free, Keep, LevelCache, PatchLod, arc_bytes};

/// Ratio between consecutive tessellation levels.
pub(crate) const LEVEL_RATIO: f64 = std::f64::consts::SQRT_2;

use crate::tessellate::trimmed::REFINE_TARGET;

/// Queue weight of a patch of bounding radius `radius` with current error `current` when the
/// view wants `wanted` (object units, > 0) at `pixel_error` (module doc): when too coarse, its
/// screen error (pixels) × its screen area (pixels², > 0); when too fine, −ε_c/ε_w (in
/// (−1, 0): after every patch that is too coarse, the finest first).
pub(crate) fn priority(current: f64, wanted: f64, radius: f64, pixel_error: f64) -> f64 {
    if current > wanted {
        let error_px = pixel_error * current / wanted;
        let r_px = pixel_error * radius / wanted;
        // (At least a pixel's area: a point-sized patch still shows its error.)
        let area_px = (std::f64::consts::PI * r_px * r_px).max(1.0);
        error_px * area_px
    } else {
        -(current / wanted)
    }
}

/// Sorts queue entries `(weight, patch)` by weight, largest first (ties by patch index, so
/// the order is the same on every run).
pub(crate) fn order_queue(queue: &mut [(f64, usize)]) {
    queue.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
}

/// The finest level a trimmed face's tessellation `m` holds by its own measured errors: its
/// surface samples within [`REFINE_TARGET`]·ε, its trim chords within ε/2 (what a fresh
/// tessellation at ε is refined to), its border within ε; `None` when it cannot stand for
/// another level (failed, stopped short, a mesh patch's cut).
pub(crate) fn finest_held(levels: &Levels, m: &PatchMesh) -> Option<i32> {
    if m.failure.is_some() || m.stopped.is_some() || m.arcs.is_some() {
        return None;
    }
    let need = (m.error / REFINE_TARGET)
        .max(2.0 * m.trim_error)
        .max(m.border_error.unwrap_or(0.0));
    if !need.is_finite() {
        return None;
    }
    let k = levels.level_for(need);
    Some(if levels.eps(k) < need { k + 1 } else { k })
}

/// What a patch at error `current` needs when the view wants `wanted`, with hysteresis
/// factor `coarsen_factor` (≥ 1).
pub(crate) fn needs_update(current: f64, wanted: f64, coarsen_factor: f64) -> bool {
    current > wanted || current * coarsen_factor < wanted
}

/// Tessellation levels of a scene: ε_k = unit · √2^k.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Levels {
    pub unit: f64,
}

impl Levels {
    /// Levels for a scene of bounding-box diagonal `diagonal`: level 0 is 10⁻⁷ of it.
    pub(crate) fn for_diagonal(diagonal: f64) -> Levels {
        let unit = if diagonal.is_finite() && diagonal > 0.0 {
            diagonal * 1e-7
        } else {
            1e-7
        };
        Levels { unit }
    }

    /// The coarsest level whose error is at most `wanted` (level 0 for anything finer).
    pub fn level_for(&self, wanted: f64) -> i32 {
        if wanted.is_nan() || wanted <= self.unit {
            return 0;
        }
        let k = ((wanted / self.unit).ln() / LEVEL_RATIO.ln()).floor() as i32;
        // Guard the rounding of ln at exact powers.
        if self.eps(k) > wanted { k - 1 } else { k }
    }

    pub fn eps(&self, level: i32) -> f64 {
        self.unit * LEVEL_RATIO.powi(level)
    }
}

/// Default [`LodOptions::cache_bytes`]: 256 MiB.
pub const DEFAULT_CACHE_BYTES: usize = 256 << 20;

/// Settings of the frame loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodOptions {
    /// Screen-space error wanted, pixels.
    pub pixel_error: f64,
    /// Time per frame for re-tessellation.
    pub budget: Duration,
    /// A patch is re-tessellated coarser only once its error is this factor below the wanted
    /// one (hysteresis, ≥ 1).
    pub coarsen_factor: f64,
    /// Tessellations kept per patch (current one included).
    pub cache_levels: usize,
    /// Bytes of cached (not current) levels kept over all patches, least recently used
    /// evicted first (`lod::cache`: a tessellation shared by placements counted once).
    pub cache_bytes: usize,
    /// Placements of one surface share its tessellation per level (instanced parts).
    pub instancing: bool,
}

impl Default for LodOptions {
    fn default() -> Self {
        LodOptions {
            pixel_error: crate::view::DEFAULT_PIXEL_ERROR,
            budget: Duration::from_millis(40),
            coarsen_factor: 2.0,
            cache_levels: 3,
            cache_bytes: DEFAULT_CACHE_BYTES,
            instancing: true,
        }
    }
}

/// What one [`FrameLoop::update`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UpdateStats {
    /// Patches inside the frustum.
    pub in_frustum: usize,
    /// Patches queued (visible last frame, off their wanted error).
    pub queued: usize,
    /// Patches re-tessellated this frame.
    pub retessellated: usize,
    /// Of those, patches the last frame did not show, tessellated ahead on a still camera
    /// with the budget the visible ones left.
    pub ahead: usize,
    /// Patches switched to a cached level (no tessellation).
    pub from_cache: usize,
    /// Trimmed faces whose current tessellation holds the wanted level by its measured
    /// errors: relabelled, not tessellated (module doc).
    pub reused: usize,
    /// Of the re-tessellated patches, those given a moved copy of a tessellation their
    /// surface's other placements share (instanced parts: no tessellation of their own).
    pub copied: usize,
    /// Queued patches left for later frames.
    pub queue_left: usize,
    /// Of the queued patches left, the trimmed faces.
    pub trimmed_left: usize,
    /// Tessellations made this frame (a surface shared by placements counted once; mesh
    /// patches' cuts left out), the worker time they took summed over the workers, and
    /// their triangles.
    pub made: usize,
    pub made_cpu: Duration,
    pub made_triangles: usize,
    /// Of `made`, those this loop had made before at the same level and dropped since
    /// (redone work), and their worker time.
    pub redone: usize,
    pub redone_cpu: Duration,
    /// Wall time spent re-tessellating.
    pub tessellation: Duration,
    /// Triangles of the patches in the frustum.
    pub triangles: usize,
    /// Cached levels evicted for [`LodOptions::cache_bytes`] (least recently used first).
    pub evicted: usize,
}

/// Bytes a [`FrameLoop`] holds (see [`FrameLoop::memory`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LodMemory {
    /// The per-patch state structs (levels, errors, flags, cache lists, cut states' inline
    /// part).
    pub state: usize,
    /// The current tessellations ([`PatchMesh::mem_bytes`] and the `Arc`'s counters).
    pub current: usize,
    /// The cached levels other than the current one (each its own bytes; the shared
    /// tessellations an instance points to are in `shared`).
    pub cached: usize,
    /// The shared tessellations the placements of instanced parts draw (each once, however
    /// many placements hold it; a placement itself holds no vertices).
    pub shared: usize,
}

impl LodMemory {
    pub fn total(&self) -> usize {
        self.state + self.current + self.cached + self.shared
    }
}

/// The frame loop's state: every patch's current tessellation, error and visibility.
#[derive(Debug)]
pub struct FrameLoop {
    pub options: LodOptions,
    levels: Levels,
    patches: Vec<PatchLod>,
    /// Changes whenever the set of meshes to draw changes (re-upload only then).
    generation: u64,
    /// Hierarchy over the patches' bounds, and the scene it was built for (address and patch
    /// count: an animation passes a moved scene each frame, which gets its own).
    bvh: bvh::Bvh,
    bvh_for: (usize, usize),
    /// The patches' bounding spheres as that scene has them, side by side (the cull reads
    /// these, not the scene's patches, which are ~10× as large apart).
    bounds: Vec<crate::model::Sphere>,
    /// The patches inside the frustum, ascending (what [`FrameLoop::meshes`] draws).
    seen: Vec<u32>,
    /// Scratch for the next frame's `seen`, and a bit per patch to put it in order.
    seen_next: Vec<u32>,
    seen_bits: Vec<u64>,
    /// The order and bytes of the cached levels (`lod::cache`).
    lru: LevelCache,
    /// Tessellations shared by the placements of one surface (instanced parts).
    shared: shared::SharedTessellations,
    /// The view of the last update (or of the first tessellation): a frame with the same one
    /// is a still camera.
    last_view: View,
}

/// How much instanced parts saved ([`FrameLoop::instancing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InstancingStats {
    /// Patches whose surface at least one other patch shares (placed parts).
    pub shared_patches: usize,
    /// Tessellations made for shared surfaces since the loop started.
    pub made: u64,
    /// Patches that got a moved copy instead of a tessellation of their own: the
    /// tessellations saved.
    pub saved: u64,
}

impl FrameLoop {
    /// Tessellates every patch for `view` (no budget: the first frame must show something)
    /// and marks every patch visible.
    pub fn new(scene: &Scene, view: &View, options: LodOptions) -> FrameLoop {
        let levels = Levels::for_diagonal(scene.bbox_diagonal());
        let frustum = view.frustum();
        let mut shared = shared::SharedTessellations::new(scene, options.instancing);
        let jobs: Vec<(usize, i32)> = scene
            .patches
            .par_iter()
            .enumerate()
            .map(|(i, patch)| {
                let wanted = view.eps_obj(&patch.bounds, options.pixel_error);
                (i, levels.level_for(wanted))
            })
            .collect();
        let mut cuts: Vec<Option<CutState>> = jobs.iter().map(|_| None).collect();
        let meshes = shared.tessellate(scene, &levels, &jobs, &mut cuts, None);
        shared.end_frame();
        let patches: Vec<PatchLod> = scene
            .patches
            .iter()
            .zip(jobs)
            .zip(meshes.into_iter().zip(cuts))
            .map(|((patch, (_, level)), (mesh, cut))| PatchLod {
                wanted: view.eps_obj(&patch.bounds, options.pixel_error),
                in_frustum: frustum.sees(&patch.bounds),
                visible: true,
                cut,
                // (No deadline: every job is done.)
                ..PatchLod::new(level, mesh.unwrap_or_default(), &levels)
            })
            .collect();
        let seen = (0..patches.len() as u32)
            .filter(|&i| patches[i as usize].in_frustum)
            .collect();
        FrameLoop {
            options,
            levels,
            patches,
            generation: 0,
            bounds: scene.patches.iter().map(|p| p.bounds).collect(),
            bvh: bvh_of(scene),
            bvh_for: scene_key(scene),
            seen,
            seen_next: Vec::new(),
            seen_bits: Vec::new(),
            lru: LevelCache::default(),
            shared,
            last_view: *view,
        }
    }

    /// What sharing tessellations between the placements of a part saved so far.
    pub fn instancing(&self) -> InstancingStats {
        InstancingStats {
            shared_patches: self.shared.shared_patches(),
            made: self.shared.made,
            saved: self.shared.saved,
        }
    }

    /// Records which patches showed in the last frame drawn (indexed like the scene's
    /// patches, e.g. from [`crate::render::Frame::visible_ids`]).
    pub fn set_visible(&mut self, visible: &[bool]) {
        for (p, v) in self.patches.iter_mut().zip(visible) {
            p.visible = *v;
        }
    }

    /// Bytes held: per-patch state, current and cached tessellations (capacities, see
    /// [`PatchMesh::mem_bytes`]; a mesh patch's cut state counted by its inline size only),
    /// and the shared tessellations their instances draw, each once.
    pub fn memory(&self) -> LodMemory {
        use std::mem::size_of;
        let arc = |m: &Arc<PatchMesh>| arc_bytes(m);
        let mut mem = LodMemory {
            state: self.patches.capacity() * size_of::<PatchLod>()
                + (self.seen.capacity() + self.seen_next.capacity()) * size_of::<u32>()
                + self.seen_bits.capacity() * size_of::<u64>()
                + self.bounds.capacity() * size_of::<crate::model::Sphere>()
                + self.lru.own_bytes(),
            ..LodMemory::default()
        };
        let mut shared = std::collections::HashSet::new();
        for p in &self.patches {
            mem.state += p.cache.capacity() * size_of::<cache::Cached>();
            mem.current += arc(&p.mesh);
            mem.cached += p.cache.iter().map(|c| arc(&c.mesh)).sum::<usize>();
            let held = std::iter::once(&p.mesh).chain(p.cache.iter().map(|c| &c.mesh));
            for inst in held.filter_map(|m| m.instance.as_ref()) {
                if shared.insert(Arc::as_ptr(&inst.shared)) {
                    mem.shared += arc(&inst.shared);
                }
            }
        }
        mem.shared += self.shared.unused_bytes(&shared);
        mem
    }

    /// Bytes of the cached levels as [`LodOptions::cache_bytes`] bounds them: each level's
    /// own bytes, each shared tessellation they point to once (`lod::cache`).
    pub fn cached_bytes(&self) -> usize {
        self.lru.bytes()
    }

    /// Cached levels evicted for [`LodOptions::cache_bytes`] since the loop started.
    pub fn evicted(&self) -> u64 {
        self.lru.evicted
    }

    /// Number of patches whose tessellation is held (current, and cached levels).
    pub fn tessellations(&self) -> (usize, usize) {
        let cached = self.patches.iter().map(|p| p.cache.len()).sum();
        (self.patches.len(), cached)
    }

    /// Changes whenever [`FrameLoop::meshes`] would give a different set of meshes.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The meshes to draw: patches inside the frustum at their current tessellation. A
    /// placement of a shared tessellation is an instance holding no vertices of its own
    /// ([`PatchMesh::world`] gives its world-space copy).
    pub fn meshes(&self) -> impl Iterator<Item = &PatchMesh> {
        self.meshes_with_index().map(|(_, m)| m)
    }

    /// One frame: culls, queues and re-tessellates within the budget (see module doc).
    pub fn update(&mut self, scene: &Scene, view: &View) -> UpdateStats {
        let start = Instant::now();
        let opts = self.options;
        let mut stats = UpdateStats::default();
        let mut queue: Vec<(f64, usize)> = Vec::new();
        let mut hidden: Vec<(f64, usize)> = Vec::new();
        let still = *view == self.last_view;
        self.last_view = *view;
        // Culling through the hierarchy: only the patches inside the frustum are visited.
        if scene_key(scene) != self.bvh_for {
            self.bounds = scene.patches.iter().map(|p| p.bounds).collect();
            self.bvh = bvh::Bvh::new(&self.bounds);
            self.bvh_for = scene_key(scene);
        }
        let frustum = view.frustum();
        let eps_of = view.eps_of(opts.pixel_error);
        let mut seen = std::mem::take(&mut self.seen_next);
        seen.clear();
        self.bvh
            .visit_seen(|i| &self.bounds[i], &frustum, &mut seen);
        ascending(&mut seen, &mut self.seen_bits, scene.patches.len());
        let frustum_changed = seen != self.seen;
        for &i in &self.seen {
            self.patches[i as usize].in_frustum = false;
        }
        for &i in &seen {
            let (i, bounds) = (i as usize, &self.bounds[i as usize]);
            let p = &mut self.patches[i];
            p.in_frustum = true;
            p.wanted = eps_of.eps(bounds);
            stats.in_frustum += 1;
            let current = p.eps;
            // (At the finest level there is nothing better to do: not queued.)
            if needs_update(current, p.wanted, opts.coarsen_factor)
                && self.levels.level_for(p.wanted) != p.level
            {
                if p.visible {
                    let radius = bounds.radius;
                    queue.push((priority(current, p.wanted, radius, opts.pixel_error), i));
                } else if current > p.wanted {
                    let radius = bounds.radius;
                    hidden.push((priority(current, p.wanted, radius, opts.pixel_error), i));
                }
            }
        }
        self.seen_next = std::mem::replace(&mut self.seen, seen);
        stats.queued = queue.len();
        order_queue(&mut queue);
        // Cached levels first, and tessellations that hold the wanted level: free.
        let levels = self.levels;
        let mut keep = Keep {
            levels: &levels,
            cache_levels: opts.cache_levels,
            lru: &mut self.lru,
        };
        let mut todo: Vec<(usize, i32)> = Vec::with_capacity(queue.len());
        for &(_, i) in &queue {
            let level = levels.level_for(self.patches[i].wanted);
            let trimmed = matches!(scene.patches[i].surface, PatchSurface::Trimmed(_));
            match self.patches[i].switch_free(level, trimmed, &mut keep) {
                Some(Free::Cached) => stats.from_cache += 1,
                Some(Free::Reused) => stats.reused += 1,
                None => todo.push((i, level)),
            }
        }
        // Hidden patches too coarse for the view (not queued: the paper spends no work on
        // what the last frame did not show) still take what costs nothing, so a patch that
        // shows up after a jump is not drawn coarser than it need be. On a still camera they
        // also take what the visible queue leaves of the budget, in the same order
        // (`UpdateStats::ahead`): what the refined surfaces in front will uncover, or what a
        // jump's first frame showed for the first time, is then ready a frame earlier.
        let visible_jobs = todo.len();
        if still {
            order_queue(&mut hidden);
        }
        for &(_, i) in &hidden {
            let level = levels.level_for(self.patches[i].wanted);
            let trimmed = matches!(scene.patches[i].surface, PatchSurface::Trimmed(_));
            match self.patches[i].switch_free(level, trimmed, &mut keep) {
                Some(Free::Cached) => stats.from_cache += 1,
                Some(Free::Reused) => stats.reused += 1,
                None if still => todo.push((i, level)),
                None => {}
            }
        }
        // Then tessellate from the top of the queue until the budget is spent: the workers
        // take the jobs in queue order (one dispatch per frame, `shared::pull`).
        let mut cuts: Vec<Option<CutState>> = todo
            .iter()
            .map(|&(i, _)| self.patches[i].cut.take())
            .collect();
        let saved = self.shared.saved;
        let deadline = start + opts.budget;
        let results = self
            .shared
            .tessellate(scene, &levels, &todo, &mut cuts, Some(deadline));
        stats.copied += (self.shared.saved - saved) as usize;
        let mut keep = Keep {
            levels: &levels,
            cache_levels: opts.cache_levels,
            lru: &mut self.lru,
        };
        for (k, ((&(i, level), cut), mesh)) in todo.iter().zip(cuts).zip(results).enumerate() {
            self.patches[i].cut = cut;
            match mesh {
                Some(mesh) => {
                    self.patches[i].install(level, mesh, &mut keep);
                    stats.retessellated += 1;
                    stats.ahead += usize::from(k >= visible_jobs);
                }
                // (A hidden patch left is not behind: nothing asked for it.)
                None if k >= visible_jobs => {}
                None => {
                    stats.queue_left += 1;
                    if matches!(
                        scene.patches[i].surface,
                        crate::model::PatchSurface::Trimmed(_)
                    ) {
                        stats.trimmed_left += 1;
                    }
                }
            }
        }
        let work = self.shared.last;
        stats.made = work.made;
        stats.made_cpu = Duration::from_secs_f64(work.made_secs);
        stats.made_triangles = work.made_triangles;
        stats.redone = work.redone;
        stats.redone_cpu = Duration::from_secs_f64(work.redone_secs);
        self.shared.end_frame();
        stats.evicted = self.lru.evict(&mut self.patches, opts.cache_bytes);
        stats.tessellation = start.elapsed();
        if stats.retessellated + stats.from_cache + stats.reused > 0 || frustum_changed {
            self.generation += 1;
        }
        stats.triangles = self
            .seen
            .iter()
            .map(|&i| self.patches[i as usize].triangles)
            .sum();
        stats
    }

    /// Screen-space error of every patch (pixels): pixel error × ε_c / ε_w.
    pub fn patch_errors_px(&self) -> Vec<f64> {
        self.patches
            .iter()
            .map(|p| self.options.pixel_error * p.eps / p.wanted.max(1e-300))
            .collect()
    }

    /// Patch `i`'s current tessellation (inside the frustum or not).
    pub fn mesh(&self, i: usize) -> Option<&PatchMesh> {
        self.patches.get(i).map(|p| p.mesh.as_ref())
    }

    /// As [`FrameLoop::meshes`], with each patch's index in the scene.
    pub fn meshes_with_index(&self) -> impl Iterator<Item = (usize, &PatchMesh)> {
        self.seen
            .iter()
            .map(|&i| (i as usize, self.patches[i as usize].mesh.as_ref()))
    }

    /// As [`FrameLoop::meshes_with_index`], each mesh as the `Arc` the loop holds: a new
    /// `Arc` exactly when the patch's tessellation changed (resident GPU geometry uploads
    /// only those).
    pub fn shared_meshes(&self) -> impl Iterator<Item = (usize, &Arc<PatchMesh>)> {
        self.seen
            .iter()
            .map(|&i| (i as usize, &self.patches[i as usize].mesh))
    }

    /// Largest and 99th-percentile screen-space error (pixels) over the patches visible in
    /// the last frame and inside the frustum: pixel error × ε_c / ε_w.
    pub fn screen_errors(&self) -> (f64, f64) {
        let mut e: Vec<f64> = self
            .seen
            .iter()
            .map(|&i| &self.patches[i as usize])
            .filter(|p| p.visible && p.wanted > 0.0)
            .map(|p| self.options.pixel_error * p.eps / p.wanted)
            .collect();
        if e.is_empty() {
            return (0.0, 0.0);
        }
        // Order statistics by selection, not a sort of every visible patch's error.
        let max = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let k = ((e.len() - 1) as f64 * 0.99).round() as usize;
        let (_, p99, _) = e.select_nth_unstable_by(k, f64::total_cmp);
        (max, *p99)
    }
}

/// Puts `ids` (distinct, below `n`) in ascending order through a bit per id (`bits`,
/// scratch): linear in `n / 64` plus the ids, where a sort of the ~30 000 patches a view of
/// the 32 k grid sees took a fair part of a still frame's update.
fn ascending(ids: &mut Vec<u32>, bits: &mut Vec<u64>, n: usize) {
    bits.clear();
    bits.resize(n.div_ceil(64), 0);
    for &i in ids.iter() {
        bits[i as usize >> 6] |= 1 << (i & 63);
    }
    ids.clear();
    for (w, &word) in bits.iter().enumerate() {
        let mut b = word;
        while b != 0 {
            ids.push(((w as u32) << 6) | b.trailing_zeros());
            b &= b - 1;
        }
    }
}

/// The culling hierarchy over a scene's patch bounds.
fn bvh_of(scene: &Scene) -> bvh::Bvh {
    let spheres: Vec<_> = scene.patches.iter().map(|p| p.bounds).collect();
    bvh::Bvh::new(&spheres)
}

/// Which scene a hierarchy was built for: the address of its patches and their count (a
/// frame loop is driven with the scene it was made for, or with a moved copy of it made for
/// one frame, which gets a hierarchy of its own).
fn scene_key(scene: &Scene) -> (usize, usize) {
    (scene.patches.as_ptr() as usize, scene.patches.len())
}

/// Frame-rate target (Pajon §3, after Funkhouser and Séquin): picks the pixel error of the
/// next frame so that the predicted triangle load fits the target frame time.
///
/// Cost model: frame time ≈ a + b · triangles (a, b fitted by exponentially weighted least
/// squares over the frames seen); triangles of a surface tessellated to ε scale as 1/ε, so
/// the pixel error that fits is γ' = γ · triangles / triangle_budget, with triangle_budget =
/// max(target − a, target/10) / b. γ' is clamped to `[min, max]` and moves at most ×2 per frame. When the
/// fit finds no cost per triangle (b ≤ 0: the frame is fill- or overhead-bound), the finest
/// pixel error is used: coarsening could not buy time.
#[derive(Clone, Debug)]
pub(crate) struct PixelErrorController {
    pub target: Duration,
    pub min: f64,
    pub max: f64,
    pixel_error: f64,
    // Weighted sums for the fit t = a + b n.
    sw: f64,
    sn: f64,
    st: f64,
    snn: f64,
    snt: f64,
}

impl PixelErrorController {
    #[cfg(test)]
    pub(crate) fn pixel_error(&self) -> f64 {
        self.pixel_error
    }

    pub fn new(target: Duration, min: f64, max: f64) -> Self {
        PixelErrorController {
            target,
            min,
            max,
            pixel_error: min,
            sw: 0.0,
            sn: 0.0,
            st: 0.0,
            snn: 0.0,
            snt: 0.0,
        }
    }

    /// Records a frame (its triangles and time) and returns the pixel error for the next one.
    pub(crate) fn observe(&mut self, triangles: usize, frame: Duration) -> f64 {
        let (n, t) = (triangles as f64, frame.as_secs_f64());
        let decay = 0.9;
        self.sw = self.sw * decay + 1.0;
        self.sn = self.sn * decay + n;
        self.st = self.st * decay + t;
        self.snn = self.snn * decay + n * n;
        self.snt = self.snt * decay + n * t;
        let var = self.snn * self.sw - self.sn * self.sn;
        let target = self.target.as_secs_f64();
        let wanted = if var > 1e-9 * self.snn * self.sw && self.sw > 2.0 {
            let b = (self.snt * self.sw - self.sn * self.st) / var;
            let a = (self.st - b * self.sn) / self.sw;
            if b <= 0.0 {
                // Triangles do not cost (fill- or overhead-bound, as on a software
                // rasterizer): coarser tessellation would lose detail for nothing.
                self.min
            } else {
                // If the fixed cost alone exceeds the target, the target cannot be met by
                // LOD: triangles still get a tenth of it rather than none.
                let budget = ((target - a).max(0.1 * target) / b).max(1.0);
                self.pixel_error * n.max(1.0) / budget
            }
        } else {
            // Too few frames for a fit: assume the whole frame is triangle cost.
            self.pixel_error * t / target
        };
        self.pixel_error = wanted
            .clamp(self.pixel_error * 0.5, self.pixel_error * 2.0)
            .clamp(self.min, self.max);
        self.pixel_error
    }
}

#[cfg(test)]
mod tests;
