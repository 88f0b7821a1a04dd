//! Each patch's ε levels in the frame loop: the current tessellation and a few cached ones,
//! bounded per patch by count and over the whole loop by bytes, least recently used evicted
//! first.
//!
//! Balázs, Guthe and Klein (2004, §4.2) re-tessellate a patch whenever its level changes; a
//! camera moving back to where it was would redo the same work. A patch therefore keeps its
//! last levels ([`PatchLod::cache`]): going back to one is free ([`PatchLod::switch_free`]).
//! Two bounds keep that cache in hand:
//!
//! - **per patch**, at most [`super::LodOptions::cache_levels`] tessellations (the current one
//!   included); past it the cached level farthest from the current one is dropped (the one a
//!   camera moving smoothly is least likely to need next);
//! - **over the loop**, at most [`super::LodOptions::cache_bytes`] bytes of cached (not
//!   current) levels, whatever the scene's size: past it the least recently used cached
//!   level of any patch is evicted first — LRU replacement (Mattson, Gecsei, Slutz and
//!   Traiger, "Evaluation techniques for storage hierarchies", IBM Systems Journal 9(2),
//!   1970). A level is in use while it is current; its use time is the moment it stopped
//!   being current (a stamp from one counter per loop, so ties cannot happen). Nothing is
//!   kept in order while the cache is under budget (a frame of the 32 k teapot grid caches
//!   thousands of levels: a queue or heap of them cost more than the rest of the
//!   accounting); once over it, the cached levels are gathered with their stamps, sorted, and
//!   the oldest evicted until the bytes are down to [`LOW_WATER`] of the budget, so the next
//!   frames do not gather again at once.
//!
//! **Bytes.** A cached level counts what it holds: its own [`PatchMesh::mem_bytes`] and the
//! `Arc`'s two counters ([`arc_bytes`]), as [`super::FrameLoop::memory`] counts a level. A
//! placement of a tessellation shared by several patches (an [`crate::tessellate::Instance`],
//! `lod::shared`) holds no vertices of its own; the shared tessellation it points to is
//! counted once however many cached levels point to it (a reference count per shared `Arc`),
//! and only while one does. Whether a current level or `lod::shared` also holds it is not
//! asked: the figure bounds the bytes reachable from the cache, which evicting every cached
//! level would free at most.
//!
//! Not done: current tessellations are never evicted (they are drawn) and are outside the
//! budget; the shared tessellations `lod::shared` keeps between frames are bounded by their
//! own rule (`KEEP_FRAMES`), not by this budget.

use std::mem::size_of;
use std::sync::Arc;

use super::{Levels, finest_held};
use crate::mt::CutState;
use crate::tessellate::PatchMesh;
use crate::util::IntMap;

/// Eviction brings the cached bytes down to this fraction of the budget.
pub(super) const LOW_WATER: f64 = 0.875;

/// Bytes of a tessellation held through an `Arc`: its own ([`PatchMesh::mem_bytes`], an
/// instance's shared mesh not included) and the `Arc`'s counters.
pub(super) fn arc_bytes(m: &PatchMesh) -> usize {
    2 * size_of::<usize>() + m.mem_bytes()
}

/// A cached level of one patch.
#[derive(Clone, Debug)]
pub(super) struct Cached {
    pub(super) level: i32,
    pub(super) mesh: Arc<PatchMesh>,
    /// When it stopped being current (the LRU's clock).
    stamp: u64,
    /// Its own bytes and the shared tessellation it points to ([`Held`]).
    pub(super) held: Held,
}

/// What a tessellation holds, noted while it is current (then in cache, so a level cached
/// long ago is counted without reading it again): its own bytes ([`arc_bytes`]) and, for an
/// instance, the address and bytes of its shared tessellation.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Held {
    bytes: usize,
    shared: Option<(usize, usize)>,
}

impl Held {
    fn of(m: &PatchMesh) -> Held {
        Held {
            bytes: arc_bytes(m),
            shared: m
                .instance
                .as_ref()
                .map(|i| (Arc::as_ptr(&i.shared) as usize, arc_bytes(&i.shared))),
        }
    }
}

/// Per-patch state.
#[derive(Clone, Debug, Default)]
pub(super) struct PatchLod {
    /// Current level and tessellation, the level's ε and the tessellation's triangles.
    pub(super) level: i32,
    pub(super) eps: f64,
    pub(super) mesh: Arc<PatchMesh>,
    pub(super) triangles: usize,
    /// What the current tessellation holds.
    pub(super) held: Held,
    /// The level the current tessellation was made at (coarser than `level` when it holds
    /// that level too and was relabelled, `lod` module doc).
    pub(super) made: i32,
    /// Other tessellations kept.
    pub(super) cache: Vec<Cached>,
    /// Error the current view wants.
    pub(super) wanted: f64,
    pub(super) in_frustum: bool,
    /// Showed in the patch-ID buffer of the last frame drawn.
    pub(super) visible: bool,
    /// A mesh patch's last cut of its hierarchy, moved from there to the next level (Holst
    /// §3): per-view state, kept here rather than in the scene.
    pub(super) cut: Option<CutState>,
}

/// What installing a level needs besides the patch: the loop's levels, the per-patch bound
/// and the loop's LRU.
pub(super) struct Keep<'a> {
    pub(super) levels: &'a Levels,
    pub(super) cache_levels: usize,
    pub(super) lru: &'a mut LevelCache,
}

/// How a patch got a level without tessellating ([`PatchLod::switch_free`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Free {
    /// A cached tessellation made at that level.
    Cached,
    /// The current tessellation, which holds that level by its measured errors.
    Reused,
}

impl PatchLod {
    /// A patch whose current tessellation is `mesh`, made at `level`.
    pub(super) fn new(level: i32, mesh: Arc<PatchMesh>, levels: &Levels) -> PatchLod {
        PatchLod {
            level,
            eps: levels.eps(level),
            triangles: mesh.triangle_count(),
            held: Held::of(&mesh),
            mesh,
            made: level,
            ..PatchLod::default()
        }
    }

    /// Makes `mesh` (made at `level`) current, caching the old one (the LRU's newest
    /// entry); drops the cached level farthest from the current one past
    /// `cache_levels` tessellations in all.
    pub(super) fn install(&mut self, level: i32, mesh: Arc<PatchMesh>, keep: &mut Keep<'_>) {
        let held = Held::of(&mesh);
        let old = std::mem::replace(&mut self.mesh, mesh);
        let old_held = std::mem::replace(&mut self.held, held);
        self.cache.push(keep.lru.add(self.level, old, old_held));
        self.level = level;
        self.eps = keep.levels.eps(level);
        self.made = level;
        self.triangles = self.mesh.triangle_count();
        while self.cache.len() + 1 > keep.cache_levels.max(1) {
            let Some(k) =
                (0..self.cache.len()).max_by_key(|&k| (self.cache[k].level - level).unsigned_abs())
            else {
                break;
            };
            let dropped = self.cache.swap_remove(k);
            keep.lru.remove(&dropped);
        }
    }

    /// Switches to `level` when that costs no tessellation: a cached tessellation
    /// made at it, or (a trimmed face's, `trimmed`) the current one when its measured errors
    /// hold `level` and `level` is no coarser than the one it was made at — the same
    /// triangles, relabelled with `level`'s ε (fat borders as wide as it). `None`: it needs
    /// work.
    pub(super) fn switch_free(
        &mut self,
        level: i32,
        trimmed: bool,
        keep: &mut Keep<'_>,
    ) -> Option<Free> {
        if let Some(k) = self.cache.iter().position(|c| c.level == level) {
            let cached = self.cache.swap_remove(k);
            keep.lru.remove(&cached);
            self.install(cached.level, cached.mesh, keep);
            return Some(Free::Cached);
        }
        let levels = keep.levels;
        let holds = trimmed
            && level != self.level
            && level <= self.made
            && finest_held(levels, &self.mesh).is_some_and(|f| level >= f);
        if !holds {
            return None;
        }
        // A placement of a shared tessellation keeps its mesh, and its fat borders the ε it
        // was made at (wider, so they still cover): the renderer draws the shared mesh with
        // the shared mesh's ε, and a relabelled copy per placement would part them.
        if self.mesh.instance.is_none() {
            let eps = levels.eps(level).max(self.mesh.error);
            self.mesh = Arc::new(PatchMesh {
                eps_target: eps,
                ..PatchMesh::clone(&self.mesh)
            });
            self.held = Held::of(&self.mesh);
        }
        self.level = level;
        self.eps = levels.eps(level);
        Some(Free::Reused)
    }
}

/// The loop's accounting of cached levels: their bytes, and the clock of their use
/// (module doc).
#[derive(Debug, Default)]
pub(super) struct LevelCache {
    clock: u64,
    /// Bytes of the cached levels, each shared tessellation once.
    bytes: usize,
    /// Shared tessellations the cached levels point to: address → cached levels pointing to
    /// it.
    shared: IntMap<usize, u32>,
    /// Scratch for eviction: (stamp, patch) of every cached level.
    order: Vec<(u64, u32)>,
    /// Cached levels evicted for the budget since the start.
    pub(super) evicted: u64,
}

impl LevelCache {
    /// Bytes of the cached levels (module doc).
    pub(super) fn bytes(&self) -> usize {
        self.bytes
    }

    /// Bytes of the accounting itself (the shared counts, the eviction scratch).
    pub(super) fn own_bytes(&self) -> usize {
        self.shared.capacity() * (size_of::<(usize, u32)>() + 1)
            + self.order.capacity() * size_of::<(u64, u32)>()
    }

    /// Counts `mesh` (level `level`, holding `held`) as cached now: the newest level.
    fn add(&mut self, level: i32, mesh: Arc<PatchMesh>, held: Held) -> Cached {
        self.clock += 1;
        self.bytes += held.bytes;
        if let Some((key, bytes)) = held.shared {
            let users = self.shared.entry(key).or_insert(0);
            if *users == 0 {
                self.bytes += bytes;
            }
            *users += 1;
        }
        Cached {
            level,
            mesh,
            stamp: self.clock,
            held,
        }
    }

    /// Counts `cached` as no longer cached (taken back or dropped).
    fn remove(&mut self, cached: &Cached) {
        self.bytes -= cached.held.bytes;
        if let Some((key, bytes)) = cached.held.shared
            && let Some(users) = self.shared.get_mut(&key)
        {
            *users -= 1;
            if *users == 0 {
                self.bytes -= bytes;
                self.shared.remove(&key);
            }
        }
    }

    /// When the cached levels of `patches` take more than `budget` bytes, evicts the least
    /// recently used ones until they take at most [`LOW_WATER`] of it; returns how many were
    /// evicted.
    pub(super) fn evict(&mut self, patches: &mut [PatchLod], budget: usize) -> usize {
        if self.bytes <= budget {
            return 0;
        }
        let low = (budget as f64 * LOW_WATER) as usize;
        let mut order = std::mem::take(&mut self.order);
        order.clear();
        for (p, patch) in patches.iter().enumerate() {
            order.extend(patch.cache.iter().map(|c| (c.stamp, p as u32)));
        }
        order.sort_unstable();
        let mut evicted = 0;
        for &(stamp, p) in &order {
            if self.bytes <= low {
                break;
            }
            let cache = &mut patches[p as usize].cache;
            if let Some(k) = cache.iter().position(|c| c.stamp == stamp) {
                let gone = cache.swap_remove(k);
                self.remove(&gone);
                evicted += 1;
            }
        }
        self.order = order;
        self.evicted += evicted as u64;
        evicted
    }
}
