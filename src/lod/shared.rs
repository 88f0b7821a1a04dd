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
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::prelude::*;

use super::Levels;
use crate::model::Scene;
use crate::mt::CutState;
use crate::tessellate::{Instance, PatchMesh, Tessellators, instance_of, placed, shared_surface};
use crate::util::IntMap;

/// Frames a shared tessellation is kept without being asked for.
pub(crate) const KEEP_FRAMES: u64 = 16;

/// Bézier patches whose translated control points differ by at most this fraction of the
/// model's diagonal share a tessellation.
pub(crate) const TRANSLATION_TOLERANCE: f64 = 1e-9;

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
    meshes: IntMap<(SurfaceKey, i32), (Arc<PatchMesh>, u64)>,
    frame: u64,
    /// Patches that got a copy instead of a tessellation of their own, since the start.
    pub(super) saved: u64,
    /// Tessellations made for shared surfaces, since the start.
    pub(super) made: u64,
    /// Every (surface or patch, level) tessellated since the start: a second tessellation
    /// of one of them is redone work (its result was made and dropped).
    done: HashSet<(WorkKey, i32)>,
    /// What the last [`SharedTessellations::tessellate`] made.
    pub(super) last: WorkStats,
}

/// What was tessellated: a shared surface, or one patch's own surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum WorkKey {
    Surface(SurfaceKey),
    Patch(u32),
}

/// The work one call of [`SharedTessellations::tessellate`] did (mesh patches' cuts left
/// out: they move, nothing is redone).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct WorkStats {
    /// Tessellations made (a shared surface's counted once, however many placements).
    pub made: usize,
    /// Worker time they took, summed over the workers (seconds).
    pub made_secs: f64,
    /// Their triangles.
    pub made_triangles: usize,
    /// Of `made`, those made before in this loop at the same level: redone work.
    pub redone: usize,
    pub redone_secs: f64,
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

    /// Tessellates patch `i` at level `l` for every `(i, l)` of `jobs`, taken in order by
    /// the rayon workers until `deadline` ([`pull`]): shared surfaces once per level (or not
    /// at all when kept from an earlier frame), the others on their own (mesh patches moving
    /// their cut in `cuts`, one per job). Per job its mesh, or `None` when the deadline came
    /// first (its cut is then left as it was). A placement's mesh is an instance of its
    /// class's tessellation made here, on the calling thread: a few hundred bytes each, where
    /// handing thousands of them to the workers cost more than it saved on a busy machine
    /// (the waits for both workers to be scheduled).
    pub(super) fn tessellate(
        &mut self,
        scene: &Scene,
        levels: &Levels,
        jobs: &[(usize, i32)],
        cuts: &mut [Option<CutState>],
        deadline: Option<Instant>,
    ) -> Vec<Option<Arc<PatchMesh>>> {
        /// One piece of work: a shared surface's tessellation at a level (from its class's
        /// first patch), or job `k`'s own tessellation with its cut.
        enum Work {
            Shared((SurfaceKey, i32), usize),
            Own(usize, Mutex<Option<CutState>>),
        }
        /// Where a job's mesh comes from: a shared tessellation kept from an earlier frame
        /// (placed), or a piece of work.
        enum From {
            Kept(Arc<PatchMesh>),
            Work(usize),
        }
        let frame = self.frame;
        let mut work = Vec::new();
        let mut asked: IntMap<(SurfaceKey, i32), usize> = IntMap::default();
        let mut from = Vec::with_capacity(jobs.len());
        for (k, &(i, level)) in jobs.iter().enumerate() {
            match self.keys.get(i).copied().flatten() {
                Some(share) => {
                    let key = (share.key, level);
                    match self.meshes.get_mut(&key) {
                        Some(entry) => {
                            entry.1 = frame;
                            from.push(From::Kept(entry.0.clone()));
                        }
                        None => {
                            let w = *asked.entry(key).or_insert_with(|| {
                                work.push(Work::Shared(key, share.source as usize));
                                work.len() - 1
                            });
                            from.push(From::Work(w));
                        }
                    }
                }
                None => {
                    work.push(Work::Own(k, Mutex::new(cuts[k].take())));
                    from.push(From::Work(work.len() - 1));
                }
            }
        }
        let made = pull(work.len(), deadline, |t, w| {
            let started = Instant::now();
            let mut mesh = PatchMesh::default();
            match &work[w] {
                Work::Shared((key, level), i) => {
                    let (patch, eps) = (&scene.patches[*i], levels.eps(*level));
                    match key {
                        SurfaceKey::Placed(..) => t.unplaced(patch, eps, &mut mesh),
                        SurfaceKey::Translated(_) => t.patch(patch, eps, &mut mesh),
                    }
                }
                Work::Own(k, cut) => {
                    let (i, level) = jobs[*k];
                    let mut cut = cut.lock().unwrap_or_else(|e| e.into_inner());
                    t.patch_from(&scene.patches[i], levels.eps(level), &mut cut, &mut mesh);
                }
            }
            (mesh, started.elapsed().as_secs_f64())
        });
        // Per piece of work its mesh: a shared tessellation (kept for the placements) or a
        // job's own.
        let mut results: Vec<Option<Arc<PatchMesh>>> = Vec::with_capacity(work.len());
        let mut made_shared = 0u64;
        self.last = WorkStats::default();
        for (w, made) in work.into_iter().zip(made) {
            let mesh = made.map(|(mesh, secs)| {
                let done = match &w {
                    Work::Shared((key, level), _) => Some((WorkKey::Surface(*key), *level)),
                    Work::Own(k, _) => {
                        let (i, level) = jobs[*k];
                        let mesh_patch = matches!(
                            scene.patches[i].surface,
                            crate::model::PatchSurface::Mesh(_)
                        );
                        (!mesh_patch).then_some((WorkKey::Patch(i as u32), level))
                    }
                };
                if let Some(done) = done {
                    self.last.made += 1;
                    self.last.made_secs += secs;
                    self.last.made_triangles += mesh.triangle_count();
                    if !self.done.insert(done) {
                        self.last.redone += 1;
                        self.last.redone_secs += secs;
                    }
                }
                Arc::new(mesh)
            });
            match w {
                Work::Shared(key, _) => {
                    if let Some(mesh) = &mesh {
                        made_shared += 1;
                        self.meshes.insert(key, (mesh.clone(), frame));
                    }
                }
                Work::Own(k, cut) => {
                    cuts[k] = cut.into_inner().unwrap_or_else(|e| e.into_inner());
                }
            }
            results.push(mesh);
        }
        // The placements: an instance each of its class's tessellation, when there is one.
        let mut copies = 0u64;
        let out = from
            .into_iter()
            .zip(jobs)
            .map(|(from, &(i, _))| {
                let share = self.keys.get(i).copied().flatten();
                let shared = match from {
                    From::Kept(shared) => shared,
                    From::Work(w) => {
                        let mesh = results[w].clone()?;
                        if share.is_none() {
                            return Some(mesh);
                        }
                        mesh
                    }
                };
                let share = share?;
                copies += 1;
                let patch = &scene.patches[i];
                Some(Arc::new(match share.key {
                    SurfaceKey::Placed(..) => placed(&shared, patch),
                    SurfaceKey::Translated(_) => translated(&shared, patch, &share),
                }))
            })
            .collect();
        self.made += made_shared;
        self.saved += copies.saturating_sub(made_shared);
        out
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

/// Runs `f(scratch, k)` for `k` in `0..n`, in order of `k`, on every rayon worker: each takes
/// the next `k` until all are taken or `deadline` has passed — after its first one, so a
/// frame always makes progress. One parallel dispatch per call, and the top of the queue is
/// done first: a budget cuts the end of the list, not the end of each worker's share of it.
/// Per `k`, what `f` made, or `None` when the deadline came first.
pub(super) fn pull<T: Send>(
    n: usize,
    deadline: Option<Instant>,
    f: impl Fn(&mut Tessellators, usize) -> T + Sync,
) -> Vec<Option<T>> {
    let mut out: Vec<Option<T>> = (0..n).map(|_| None).collect();
    if n == 0 {
        return out;
    }
    let next = AtomicUsize::new(0);
    let workers = rayon::current_num_threads().clamp(1, n);
    let done: Vec<Vec<(usize, T)>> = (0..workers)
        .into_par_iter()
        .with_max_len(1)
        .map(|_| {
            let mut scratch = Tessellators::new();
            let mut made = Vec::new();
            loop {
                if !made.is_empty() && deadline.is_some_and(|d| Instant::now() >= d) {
                    break made;
                }
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= n {
                    break made;
                }
                made.push((k, f(&mut scratch, k)));
            }
        })
        .collect();
    for (k, v) in done.into_iter().flatten() {
        out[k] = Some(v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Without a deadline every job is done; with one already past, each worker does one
    /// job, from the top.
    #[test]
    fn pull_does_all_or_the_top_of_the_list() {
        let all = pull(1000, None, |_, k| k * 2);
        assert!(all.iter().enumerate().all(|(k, v)| *v == Some(2 * k)));
        let past = Instant::now() - Duration::from_millis(1);
        let some = pull(1000, Some(past), |_, k| k);
        let done: Vec<usize> = some.iter().flatten().copied().collect();
        let workers = rayon::current_num_threads();
        assert!(!done.is_empty() && done.len() <= workers, "{done:?}");
        assert!(done.iter().all(|&k| k < workers), "{done:?}");
    }

    /// Cut by a deadline mid-way, the jobs done are the top of the list (up to one job in
    /// flight per worker): the budget cuts the end of the queue, not each worker's half.
    #[test]
    fn a_deadline_cuts_the_end_of_the_list() {
        let deadline = Instant::now() + Duration::from_millis(30);
        let out = pull(100_000, Some(deadline), |_, k| {
            std::thread::sleep(Duration::from_micros(200));
            k
        });
        let done: Vec<usize> = out.iter().flatten().copied().collect();
        let n = done.len();
        assert!(n > 0 && n < 100_000, "{n} done");
        let workers = rayon::current_num_threads();
        assert!(done.iter().all(|&k| k < n + workers), "{done:?}");
    }
}
