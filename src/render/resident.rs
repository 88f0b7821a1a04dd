//! Resident patch geometry: every patch's surface and fat-border geometry kept in a few large
//! GPU buffers between frames, so a frame uploads only the patches whose tessellation changed.
//!
//! Balázs, Guthe and Klein, "Fat Borders" (2004), §4.2: per frame only a budgeted handful of
//! the visible patches is re-tessellated (the `lod` queue), and every patch is drawn with its
//! own current ε; the geometry of the others does not change. Uploading all of it again
//! whenever one patch changes (what [`Renderer::upload`] does) makes the frame cost follow
//! the scene; here it follows what changed.
//!
//! **Design.** Four streams (surface vertices, surface list indices, strip indices, fat-border
//! points — one [`super::BorderPoint`] per border vertex, expanded in the vertex shader), each
//! a `pool::Pool`: one `wgpu::Buffer` suballocated by an `Allocator` (first fit over a
//! coalesced free list). The four pools form an **arena**; a patch's streams all live in one
//! arena (its indices refer to that arena's vertices). A pool that runs out of free units
//! grows by reallocation: a new buffer at least 1.5× larger, the old contents copied on the
//! GPU (`copy_buffer_to_buffer`), every range where it was — up to the device's largest
//! buffer (for the points: its largest storage binding); a patch that fits no arena opens a
//! new one, so a scene larger than one buffer still draws ([`RenderError::TooLarge`] only
//! for one patch larger than an empty arena). When the free units suffice but no free range
//! is long enough (fragmentation), or when a quarter of a pool is free in many small ranges,
//! the pool is compacted: its live ranges packed into a new buffer in patch order, and the
//! patches whose vertices moved get their index streams written again (indices are stored
//! already offset by the patch's vertex base, so a moved vertex range invalidates them).
//!
//! Per scene patch a slot holds its arena, its ranges and the `Arc<PatchMesh>` it was built
//! from (held, so the identity cannot be reused by another mesh). [`ResidentGeometry::update`]
//! walks the patches in the frustum only when the frame loop's generation changed; a patch
//! whose mesh is the one its slot holds uploads nothing. The changed ones are built on the
//! CPU in parallel (rayon: surface vertices, list indices or strips, the [`BorderGeometry`]
//! of that one patch), `BATCH` patches at a time so the CPU copies stay bounded, their old
//! ranges freed, new ones allocated and written: the contiguous ranges of one pool in one
//! `write_buffer`; the CPU copies are dropped once written. Patches leaving the frustum stay
//! resident (at most one tessellation per patch, as the frame loop keeps on the CPU).
//!
//! **Draws.** The draw list is rebuilt from the patches in the frustum (cost ∝ patches drawn)
//! when the generation changed: per stream, in patch order, ranges adjacent in the same
//! arena merged into one draw. Re-tessellated patches land wherever first fit puts them, so
//! the draws split over the frames (on grid32, 20 000 after ten frames, each ~35 µs on
//! lavapipe); past `PACK_DRAWS` the pools are packed with the drawn patches in front, in
//! draw order — a GPU-side copy, the indices keep their values — and each stream is one draw
//! per arena again. Strips are stored as self-contained blocks that concatenate: ending in a
//! restart (primitive restart), or, joined by zero-area windows ([`Join::Degenerate`]),
//! opening with the first index twice more and padded to an even length, so every strip
//! keeps its parity inside a merged draw. Fat borders are non-indexed draws over ranges of
//! points (T vertices per point for a template of T codes). With indirect draws
//! (`Gpu::indirect`) the ranges become one `DrawIndexedIndirectArgs` (surfaces) or three
//! `DrawIndirectArgs` (fat borders, one per variant) each, written once per rebuild, and each
//! run of one arena is one `multi_draw_*_indirect`; otherwise a loop of draws. Mesh-patch
//! cuts drawn from their hierarchies' static buffers (`Renderer::draws_static`) keep that
//! path; only their fat borders are resident.
//!
//! The result is the same picture as [`Renderer::upload`] bit for bit: the same triangles
//! with the same vertices, in the same order, each strip with its orientation
//! (`tests/resident.rs`).
//!
//! Not done here: frames with animation offsets or the heat map are drawn through
//! [`Renderer::upload`] (their meshes change every frame, see `frame::step`); pools never
//! shrink; patches that left the frustum are not evicted.

mod alloc;
mod blocks;
mod draws;
mod instances;
mod pool;

pub(crate) use alloc::Allocator;

use std::collections::HashMap;

use super::pipelines::Pipelines;
use super::upload::{SurfaceVertex, offset_indices, packed_color, strips_of, surface_vertices};
use super::*;
use blocks::strip_block;
use draws::DrawList;
use instances::{PlacedDraws, Slots};
use pool::Pool;

const VERTICES: usize = 0;
const LIST: usize = 1;
const STRIPS: usize = 2;
/// Fat-border points ([`BorderPoint`]).
const POINTS: usize = 3;
const STREAMS: usize = 4;
/// The streams drawn, in draw order.
const DRAWN_STREAMS: [usize; 3] = [LIST, STRIPS, POINTS];

/// Patches built on the CPU at a time: their copies are written and dropped before the next
/// batch is built.
pub(crate) const BATCH: usize = 4096;

/// What one [`ResidentGeometry::update`] did. Every byte given to `write_buffer` is counted
/// in exactly one field of [`UploadStats::uploaded_bytes`]; GPU-side copies are not uploads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Patches whose mesh was (re-)uploaded.
    pub patches: usize,
    /// Their geometry: surface vertices, list or strip indices and fat-border points.
    pub geometry_bytes: u64,
    /// Index streams written again for patches whose vertices a compaction moved.
    pub reindexed_bytes: u64,
    /// Static buffers of mesh-patch hierarchies built on first use.
    pub static_bytes: u64,
    /// Indirect draw arguments (per merged draw one `DrawIndexedIndirectArgs`, 20 bytes; for
    /// fat borders one per variant), written when the draw list was rebuilt on a device that
    /// draws indirect.
    pub args_bytes: u64,
    /// Instanced parts: the records of the changed placed patches (64 bytes each) and the
    /// drawn placements' record indices that changed (4 bytes each), written when the draw
    /// list was rebuilt.
    pub instance_bytes: u64,
    /// Changed patches drawn as placements of a shared mesh (a record, no geometry).
    pub placed: usize,
    /// Bytes copied on the GPU by growth and compaction.
    pub copied_bytes: u64,
    pub grown: usize,
    pub compactions: usize,
    /// Whether the draw list was rebuilt.
    pub rebuilt: bool,
}

impl UploadStats {
    /// Everything written from the CPU.
    pub fn uploaded_bytes(&self) -> u64 {
        self.geometry_bytes
            + self.reindexed_bytes
            + self.static_bytes
            + self.args_bytes
            + self.instance_bytes
    }
}

/// GPU memory of the resident geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ResidentMemory {
    pub arenas: usize,
    /// Bytes of the pools' buffers, per stream: surface vertices, list indices, strip
    /// indices, fat-border points.
    pub capacity: [u64; STREAMS],
    /// Of which in live ranges.
    pub used: [u64; STREAMS],
    /// Instanced parts: the placement records' buffer, and the bytes of live records.
    pub records_capacity: u64,
    pub records_used: u64,
}

impl ResidentMemory {
    /// Bytes in live ranges and records.
    pub(crate) fn used_total(&self) -> u64 {
        self.used.iter().sum::<u64>() + self.records_used
    }
}

/// What a patch's slot holds.
#[derive(Clone, Debug, Default)]
struct Slot {
    mesh: Option<Arc<PatchMesh>>,
    arena: usize,
    /// Per stream `(start, len)` in units of its pool.
    ranges: [Option<(u64, u64)>; STREAMS],
    /// The patch's strips (local indices), kept to write them again after a compaction.
    strips: Option<Arc<Vec<u32>>>,
    /// Drawn from its hierarchy's static buffers (only the fat borders are resident).
    is_static: bool,
    /// A placed patch: the key of its shared mesh's slot, and where its record is.
    instance_of: Option<usize>,
    record_at: Option<u64>,
    /// A shared mesh's slot: the placed patches using it.
    users: usize,
}

/// One patch's geometry on the CPU, indices local to the patch.
struct Built {
    slot: usize,
    mesh: Arc<PatchMesh>,
    /// Only the index streams are written (the vertices moved in a compaction).
    reindex: bool,
    is_static: bool,
    vertices: Vec<SurfaceVertex>,
    list: Vec<u32>,
    strips: Option<Arc<Vec<u32>>>,
    strip_block: Vec<u32>,
    borders: BorderGeometry,
}

impl Built {
    fn new(
        renderer: &Renderer,
        slot: usize,
        mesh: &Arc<PatchMesh>,
        strips: Option<Arc<Vec<u32>>>,
        reindex: bool,
    ) -> Built {
        // A placement drawn as a world-space copy (instances off) is moved here, for the
        // upload only: the frame loop holds no copy of it.
        let world = mesh.world();
        let m = world.as_ref();
        let is_static = renderer.draws_static(m);
        let strips = if is_static || !renderer.primitives.strips_for(m) {
            None
        } else {
            strips.or_else(|| Some(strips_of(&renderer.strips, m, renderer.primitives)))
        };
        let surface = !is_static && !reindex;
        Built {
            slot,
            mesh: mesh.clone(),
            reindex,
            is_static,
            vertices: if surface {
                surface_vertices(&m.positions, &m.normals, m.patch_id, packed_color(m.color))
                    .collect()
            } else {
                Vec::new()
            },
            list: if is_static || strips.is_some() {
                Vec::new()
            } else {
                m.triangles.iter().flatten().copied().collect()
            },
            strip_block: strips
                .as_ref()
                .map_or_else(Vec::new, |s| strip_block(s, renderer.strip_join)),
            strips,
            borders: if reindex {
                BorderGeometry::default()
            } else {
                BorderGeometry::of(std::iter::once(m))
            },
        }
    }

    /// Units of stream `p` this patch takes.
    fn len(&self, p: usize) -> u64 {
        (match p {
            VERTICES => self.vertices.len(),
            LIST => self.list.len(),
            STRIPS => self.strip_block.len(),
            _ => self.borders.points.len(),
        }) as u64
    }

    /// Appends stream `p`'s bytes, indices offset by the slot's vertex base.
    fn append(&self, p: usize, slot: &Slot, out: &mut Vec<u8>) {
        let base = slot.ranges[VERTICES].map_or(0, |r| r.0 as u32);
        match p {
            VERTICES => out.extend_from_slice(bytemuck::cast_slice(&self.vertices)),
            LIST => offset_indices(&self.list, base, out),
            STRIPS => offset_indices(&self.strip_block, base, out),
            _ => out.extend_from_slice(bytemuck::cast_slice(&self.borders.points)),
        }
    }
}

/// Draws of the drawn streams past which their pools are packed in draw order.
const PACK_DRAWS: usize = 256;

/// Whether a pool is worth packing: a quarter or more of it free, in more than 64 ranges,
/// the longest under half of the free units.
fn fragmented(a: &Allocator) -> bool {
    a.free() * 4 >= a.capacity() && a.free_ranges() > 64 && a.largest_free() * 2 < a.free()
}

/// A fault to inject (tests prove they can fail with it).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fault {
    #[default]
    None,
    /// Every update leaves the first changed patch's slot as it was (a stale slot).
    KeepFirstStale,
    /// Placed patches are drawn without their placement (identity records).
    UnplacedInstances,
}

/// One buffer per stream; a patch's streams all live in one arena.
#[derive(Debug)]
struct Arena {
    pools: [Pool; STREAMS],
    /// The bind group of the points pool's buffer, and that buffer.
    points_bind: (wgpu::Buffer, wgpu::BindGroup),
}

impl Arena {
    /// Empty pools, each at most `max_bytes` (or what the device allows).
    fn new(renderer: &Renderer, max_bytes: Option<u64>) -> Arena {
        let gpu = &renderer.gpu;
        let limit = |device: u64| max_bytes.map_or(device, |m| m.min(device));
        let buffer_max = limit(gpu.device.limits().max_buffer_size);
        let points_max = limit(renderer.max_points_bytes());
        let (v, i) = (wgpu::BufferUsages::VERTEX, wgpu::BufferUsages::INDEX);
        let unit = |size: usize| size as u64;
        let pools = [
            Pool::new(
                gpu,
                "resident vertices",
                v,
                unit(size_of::<SurfaceVertex>()),
                buffer_max,
            ),
            Pool::new(gpu, "resident list indices", i, 4, buffer_max),
            Pool::new(gpu, "resident strip indices", i, 4, buffer_max),
            Pool::new(
                gpu,
                "resident fat border points",
                wgpu::BufferUsages::STORAGE,
                unit(size_of::<BorderPoint>()),
                points_max,
            ),
        ];
        let buffer = pools[POINTS].buffer.clone();
        let bind = renderer.points_bind_group(&buffer);
        Arena {
            pools,
            points_bind: (buffer, bind),
        }
    }

    /// Whether `lens` more units (per stream) fit under the pools' largest sizes.
    fn fits(&self, lens: &[u64; STREAMS]) -> bool {
        self.pools.iter().zip(lens).all(|(p, &n)| p.fits(n))
    }

    /// Binds the points pool's current buffer (after growth or compaction replaced it).
    fn rebind(&mut self, renderer: &Renderer) {
        if self.points_bind.0 != self.pools[POINTS].buffer {
            let buffer = self.pools[POINTS].buffer.clone();
            let bind = renderer.points_bind_group(&buffer);
            self.points_bind = (buffer, bind);
        }
    }
}

/// Patch geometry resident on the GPU between frames (see the module doc). Per-view state:
/// owned by a `frame::FrameState`, bound to the device of the renderer that last updated it.
#[derive(Debug)]
pub struct ResidentGeometry {
    device: wgpu::Device,
    /// The renderer settings the slots were built with (primitives, strip join, static arcs).
    config: (Primitives, Join, bool, bool),
    arenas: Vec<Arena>,
    slots: Slots,
    /// Per scene patch the address of the mesh its slot holds (0: none), beside the slots so
    /// that finding the changed patches of a frame reads 8 bytes per drawn patch, not a slot.
    held: Vec<usize>,
    generation: Option<u64>,
    /// The patches of the last update (scene indices, in order).
    drawn: Vec<usize>,
    draws: DrawList,
    /// Indirect arguments of the draw list.
    args: Option<wgpu::Buffer>,
    /// The draws of the placed patches (instanced parts).
    placed: PlacedDraws,

    #[doc(hidden)]
    pub fault: Fault,
    /// Largest bytes of one pool's buffer (tests: many arenas on a small scene); `None`:
    /// what the device allows.
    #[doc(hidden)]
    pub arena_bytes: Option<u64>,
}

impl ResidentGeometry {
    /// Empty pools on `renderer`'s device.
    pub fn new(renderer: &Renderer) -> ResidentGeometry {
        ResidentGeometry {
            device: renderer.gpu.device.clone(),
            config: (
                renderer.primitives,
                renderer.strip_join,
                renderer.static_arcs,
                renderer.instances,
            ),
            arenas: Vec::new(),
            slots: Slots::default(),
            held: Vec::new(),
            generation: None,
            drawn: Vec::new(),
            draws: DrawList::default(),
            args: None,
            placed: PlacedDraws::default(),
            fault: Fault::None,
            arena_bytes: None,
        }
    }

    /// A fresh geometry with this one's test settings.
    fn reset(&mut self, renderer: &Renderer) {
        let (fault, arena_bytes) = (self.fault, self.arena_bytes);
        *self = ResidentGeometry::new(renderer);
        self.fault = fault;
        self.arena_bytes = arena_bytes;
    }

    /// GPU memory held (capacity and live bytes per stream).
    pub fn memory(&self) -> ResidentMemory {
        let mut m = ResidentMemory {
            arenas: self.arenas.len(),
            ..ResidentMemory::default()
        };
        for a in &self.arenas {
            for (p, pool) in a.pools.iter().enumerate() {
                m.capacity[p] += pool.bytes();
                m.used[p] += pool.alloc.used() * pool.unit;
            }
        }
        (m.records_capacity, m.records_used) = self.placed.records_memory();
        m
    }

    /// Makes the patches `meshes` (scene index, mesh; the patches to draw, in scene order)
    /// resident and the draw list theirs. Nothing is walked when `generation` (the frame
    /// loop's, which changes whenever the meshes to draw change) is the last one seen. A
    /// patch larger than an empty arena is [`RenderError::TooLarge`]; the geometry is then
    /// emptied (the next update starts afresh).
    pub fn update<'a>(
        &mut self,
        renderer: &Renderer,
        meshes: impl IntoIterator<Item = (usize, &'a Arc<PatchMesh>)>,
        generation: u64,
    ) -> Result<UploadStats, RenderError> {
        let config = (
            renderer.primitives,
            renderer.strip_join,
            renderer.static_arcs,
            renderer.instances,
        );
        if self.device != renderer.gpu.device || self.config != config {
            self.reset(renderer);
        }
        let mut stats = UploadStats::default();
        if self.generation == Some(generation) {
            return Ok(stats);
        }
        self.generation = Some(generation);
        let drawn: Vec<(usize, &Arc<PatchMesh>)> = meshes.into_iter().collect();
        if let Some(max) = drawn.iter().map(|d| d.0 + 1).max()
            && max > self.slots.patches.len()
        {
            self.slots.patches.resize(max, Slot::default());
            self.held.resize(max, 0);
        }
        let mut changed: Vec<(usize, &Arc<PatchMesh>)> = drawn
            .iter()
            .filter(|(i, m)| self.held[*i] != Arc::as_ptr(m) as usize)
            .copied()
            .collect();
        if self.fault == Fault::KeepFirstStale && !changed.is_empty() {
            changed.remove(0);
        }
        // (Each changed slot holds its new mesh once this update is through; on an error
        // the geometry is emptied, `held` with it.)
        for (i, m) in &changed {
            self.held[*i] = Arc::as_ptr(m) as usize;
        }
        if !changed.is_empty() {
            renderer.strips.begin_upload();
            let changed = match self.attach_instances(renderer, changed, &mut stats) {
                Ok(c) => c,
                Err(e) => {
                    self.reset(renderer);
                    return Err(e);
                }
            };
            for batch in changed.chunks(BATCH) {
                let built: Vec<Built> = batch
                    .par_iter()
                    .map(|(i, m)| Built::new(renderer, *i, m, None, false))
                    .collect();
                stats.patches += built.len();
                if let Err(e) = self.place(renderer, built, &mut stats) {
                    self.reset(renderer);
                    return Err(e);
                }
            }
        }
        self.drawn = drawn.iter().map(|d| d.0).collect();
        let order = std::mem::take(&mut self.drawn);
        self.rebuild_draws(renderer, &order, &mut stats);
        self.drawn = order;
        Ok(stats)
    }

    /// Frees the changed slots' ranges, picks each an arena (the first its streams fit in,
    /// or a new one), allocates and writes the new ranges.
    fn place(
        &mut self,
        renderer: &Renderer,
        built: Vec<Built>,
        stats: &mut UploadStats,
    ) -> Result<(), RenderError> {
        let gpu = &renderer.gpu;
        if let Some(b) = built
            .iter()
            .find(|b| b.borders.longest_ring > super::fat_border::MAX_RING_POINTS)
        {
            let unit = std::mem::size_of::<super::fat_border::BorderPoint>() as u64;
            return Err(RenderError::TooLarge {
                what: "fat-border points of one border loop",
                bytes: b.borders.longest_ring as u64 * unit,
                limit: super::fat_border::MAX_RING_POINTS as u64 * unit,
            });
        }
        for b in &built {
            let slot = &mut self.slots[b.slot];
            for (p, range) in slot.ranges.iter_mut().enumerate() {
                if let Some((start, _)) = range.take() {
                    self.arenas[slot.arena].pools[p].alloc.free_range(start);
                }
            }
            slot.mesh = Some(b.mesh.clone());
            slot.strips = b.strips.clone();
            slot.is_static = b.is_static;
        }
        // Arenas: the first with room for all of a patch's streams (counting this batch).
        let mut wanted: Vec<[u64; STREAMS]> = vec![[0; STREAMS]; self.arenas.len()];
        for b in &built {
            let lens: [u64; STREAMS] = std::array::from_fn(|p| b.len(p));
            let fits =
                |a: &Arena, w: &[u64; STREAMS]| a.fits(&std::array::from_fn(|p| w[p] + lens[p]));
            let found = (0..self.arenas.len()).find(|&a| fits(&self.arenas[a], &wanted[a]));
            let a = match found {
                Some(a) => a,
                None => {
                    let arena = Arena::new(renderer, self.arena_bytes);
                    if !arena.fits(&lens) {
                        let p = (0..STREAMS)
                            .find(|&p| !arena.pools[p].fits(lens[p]))
                            .unwrap_or(0);
                        let pool = &arena.pools[p];
                        return Err(RenderError::TooLarge {
                            what: pool.label,
                            bytes: lens[p] * pool.unit,
                            limit: pool.max_units * pool.unit,
                        });
                    }
                    self.arenas.push(arena);
                    wanted.push([0; STREAMS]);
                    self.arenas.len() - 1
                }
            };
            self.slots[b.slot].arena = a;
            for p in 0..STREAMS {
                wanted[a][p] += lens[p];
            }
        }
        let mut moved = Vec::new();
        for (a, want) in wanted.iter().enumerate() {
            for (p, &needed) in want.iter().enumerate() {
                if needed == 0 {
                    continue;
                }
                let copied = self.arenas[a].pools[p].reserve(gpu, needed)?;
                stats.copied_bytes += copied;
                stats.grown += usize::from(copied > 0);
            }
        }
        for b in &built {
            let a = self.slots[b.slot].arena;
            for p in 0..STREAMS {
                let len = b.len(p);
                if len == 0 {
                    continue;
                }
                let start = match self.arenas[a].pools[p].alloc.alloc(len) {
                    Some(s) => s,
                    None => {
                        self.compact(gpu, a, p, &mut moved, stats);
                        // `reserve` left at least the batch's units free, and compaction
                        // made them one range.
                        self.arenas[a].pools[p]
                            .alloc
                            .alloc(len)
                            .expect("a compacted pool has its free units in one range")
                    }
                };
                self.slots[b.slot].ranges[p] = Some((start, len));
            }
        }
        // Pools left fragmented: packed again (the merged draws follow patch order again).
        for a in 0..self.arenas.len() {
            for p in 0..STREAMS {
                if fragmented(&self.arenas[a].pools[p].alloc) {
                    self.compact(gpu, a, p, &mut moved, stats);
                }
            }
        }
        stats.geometry_bytes += self.write(gpu, &built);
        let fresh: std::collections::HashSet<usize> = built.iter().map(|b| b.slot).collect();
        drop(built);
        moved.retain(|i| !fresh.contains(i));
        self.reindex(renderer, moved, stats);
        // Staged writes go to the GPU now, so their staging memory can be reused.
        self.flush(gpu);
        Ok(())
    }

    /// Writes the index streams of the slots `moved` again (their vertices moved).
    fn reindex(&mut self, renderer: &Renderer, mut moved: Vec<usize>, stats: &mut UploadStats) {
        moved.sort_unstable();
        moved.dedup();
        for batch in moved.chunks(BATCH) {
            let reindexed: Vec<Built> = batch
                .par_iter()
                .filter_map(|&i| {
                    let s = &self.slots[i];
                    let mesh = s.mesh.as_ref()?;
                    Some(Built::new(renderer, i, mesh, s.strips.clone(), true))
                })
                .collect();
            stats.reindexed_bytes += self.write(&renderer.gpu, &reindexed);
        }
    }

    /// Packs every pool in patch order now (each slot's ranges adjacent to its neighbours',
    /// so the draws of patches in a row merge), writes the index streams of the patches whose
    /// vertices moved and rebuilds the draw list.
    pub fn compact_all(&mut self, renderer: &Renderer) -> UploadStats {
        let mut stats = UploadStats::default();
        let mut moved = Vec::new();
        for a in 0..self.arenas.len() {
            for p in 0..STREAMS {
                self.compact(&renderer.gpu, a, p, &mut moved, &mut stats);
            }
        }
        self.reindex(renderer, moved, &mut stats);
        let drawn = std::mem::take(&mut self.drawn);
        self.rebuild_draws(renderer, &drawn, &mut stats);
        self.drawn = drawn;
        stats
    }

    /// Packs pool `p` of arena `a` in patch order; records the slots whose vertices moved.
    fn compact(
        &mut self,
        gpu: &Gpu,
        a: usize,
        p: usize,
        moved: &mut Vec<usize>,
        stats: &mut UploadStats,
    ) {
        self.compact_in(gpu, a, p, &[], moved, stats);
    }

    /// Packs pool `p` of arena `a` with the ranges of the slots `first` (those in the arena)
    /// in front, in that order, the others after them by address; records the slots whose
    /// vertices moved in `moved`.
    fn compact_in(
        &mut self,
        gpu: &Gpu,
        a: usize,
        p: usize,
        first: &[usize],
        moved: &mut Vec<usize>,
        stats: &mut UploadStats,
    ) {
        let order: Vec<u64> = first
            .iter()
            .map(|&i| &self.slots[i])
            .filter(|s| s.arena == a)
            .filter_map(|s| s.ranges[p].map(|r| r.0))
            .collect();
        let (moves, copied) = self.arenas[a].pools[p].compact(gpu, order);
        stats.copied_bytes += copied;
        stats.compactions += 1;
        let to: HashMap<u64, u64> = moves.iter().map(|m| (m.from, m.to)).collect();
        for (i, slot) in self.slots.iter_mut() {
            if slot.arena == a
                && let Some((start, len)) = slot.ranges[p]
                && let Some(&new) = to.get(&start)
            {
                slot.ranges[p] = Some((new, len));
                if p == VERTICES {
                    moved.push(i);
                }
            }
        }
    }

    /// Stages the streams of `built` (index streams only for re-indexed patches), each
    /// pool's contiguous ranges as one run ([`Pool::write`]; written by
    /// [`ResidentGeometry::flush`]). Returns the bytes staged.
    fn write(&mut self, gpu: &Gpu, built: &[Built]) -> u64 {
        let mut written = 0;
        let vertex_stream = |p: usize| p == VERTICES || p == POINTS;
        let slots = &self.slots;
        for (a, arena) in self.arenas.iter_mut().enumerate() {
            for (p, pool) in arena.pools.iter_mut().enumerate() {
                let mut items: Vec<(u64, &Built)> = built
                    .iter()
                    .filter(|b| !(b.reindex && vertex_stream(p)))
                    .filter(|b| slots[b.slot].arena == a)
                    .filter_map(|b| Some((slots[b.slot].ranges[p]?.0, b)))
                    .collect();
                items.sort_unstable_by_key(|x| x.0);
                let mut run: Option<u64> = None;
                let mut bytes = Vec::new();
                for (start, b) in items {
                    if run.is_some_and(|r| r + bytes.len() as u64 / pool.unit != start) {
                        written += pool.write(gpu, run.unwrap_or(0), &bytes);
                        bytes.clear();
                        run = None;
                    }
                    run.get_or_insert(start);
                    b.append(p, &slots[b.slot], &mut bytes);
                }
                if let Some(r) = run {
                    written += pool.write(gpu, r, &bytes);
                }
            }
        }
        written
    }

    /// Writes every pool's staged bytes (one staging buffer and submission per pool with
    /// writes, [`Pool::flush`]).
    fn flush(&mut self, gpu: &Gpu) {
        for arena in &mut self.arenas {
            for pool in &mut arena.pools {
                pool.flush(gpu);
            }
        }
        self.placed.flush(gpu);
    }

    /// The draw list of `drawn` (see the module doc), with its indirect arguments. When the
    /// streams split into more than [`PACK_DRAWS`] draws, their pools are packed with the
    /// drawn patches in front, in order (a GPU-side copy; indices do not change), so each
    /// stream is one draw per arena again.
    fn rebuild_draws(&mut self, renderer: &Renderer, drawn: &[usize], stats: &mut UploadStats) {
        let mut d = DrawList::collect(renderer, &self.slots, drawn, stats);
        if d.split() > PACK_DRAWS {
            let mut moved = Vec::new();
            for a in 0..self.arenas.len() {
                for p in DRAWN_STREAMS {
                    self.compact_in(&renderer.gpu, a, p, drawn, &mut moved, stats);
                }
            }
            d = DrawList::collect(renderer, &self.slots, drawn, stats);
        }
        for a in &mut self.arenas {
            a.rebind(renderer);
        }
        stats.rebuilt = true;
        d.write_args(renderer, &mut self.args, stats);
        self.draws = d;
        self.placed.collect(&self.slots, drawn);
        self.placed.write(renderer, stats);
        // Every staged write (geometry, re-indexed streams, records) goes before a draw.
        self.flush(&renderer.gpu);
    }

    /// Merged draws of the current draw list (all streams, static ranges included).
    pub fn draw_count(&self) -> usize {
        self.draws.draw_count()
    }

    /// Of which fat-border draws (of at most `PATTERN_POINTS` points; three indirect
    /// arguments each, one per variant).
    pub fn border_draw_count(&self) -> usize {
        self.draws.ranges[POINTS].len()
    }

    /// Records the draws of `variant` into `pass`.
    pub(super) fn encode(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        patterns: &[wgpu::Buffer; 3],
        variant: FatBorders,
        edges: Option<&EdgePipelines>,
        indirect: bool,
    ) {
        self.draws.encode(
            pass,
            pipes,
            patterns,
            &self.arenas,
            self.args.as_ref().filter(|_| indirect),
            variant,
            &self.placed,
        );
        if let Some(e) = edges {
            self.draws.encode_edges(pass, e, &self.arenas);
            self.placed.encode_edges(pass, e, &self.arenas);
        }
    }
}
