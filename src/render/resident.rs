//! Resident patch geometry: every patch's surface and fat-border geometry kept in a few large
//! GPU buffers between frames, so a frame uploads only the patches whose tessellation changed.
//!
//! Balázs, Guthe and Klein, "Fat Borders" (2004), §4.2: per frame only a budgeted handful of
//! the visible patches is re-tessellated (the `lod` queue), and every patch is drawn with its
//! own current ε; the geometry of the others does not change. Uploading all of it again
//! whenever one patch changes (what [`Renderer::upload`] does) makes the frame cost follow
//! the scene; here it follows what changed.
//!
//! **Design.** Seven buffers (surface vertices, surface list indices, strip indices, fat-border
//! vertices, fat-border indices for the 6-, 4- and 2-vertex variants), each a
//! [`pool::Pool`]: one `wgpu::Buffer` suballocated by an [`Allocator`] (first fit over a
//! coalesced free list). A pool that runs out of free units grows by reallocation: a new
//! buffer at least 1.5× larger, the old contents copied on the GPU (`copy_buffer_to_buffer`),
//! every range where it was. When the free units suffice but no free range is long enough
//! (fragmentation), or when a quarter of it is free in many small ranges, the pool is
//! compacted: its live ranges packed into a new buffer in patch order, and the patches whose
//! vertices moved get their index streams written again (indices are stored already offset by
//! the patch's vertex base, so a moved vertex range invalidates them).
//!
//! Per scene patch a slot holds its ranges and the `Arc<PatchMesh>` it was built from (held,
//! so the identity cannot be reused by another mesh). [`ResidentGeometry::update`] walks the
//! patches in the frustum only when the frame loop's generation changed; a patch whose mesh
//! is the one its slot holds uploads nothing. The changed ones are built on the CPU in
//! parallel (rayon: surface vertices, list indices or strips, [`BorderGeometry`] of that one
//! patch), their old ranges freed, new ones allocated and written: the contiguous ranges of
//! one pool in one `write_buffer`. Patches leaving the frustum stay resident (at most one
//! tessellation per patch, as the frame loop keeps on the CPU).
//!
//! **Draws.** The draw list is rebuilt from the patches in the frustum (cost ∝ patches drawn)
//! when the generation changed: per index stream, in patch order, ranges adjacent in the
//! buffer merged into one draw. Re-tessellated patches land wherever first fit puts them, so
//! the draws split over the frames (on grid32, 20 000 after ten frames, each ~35 µs on
//! lavapipe); past [`PACK_DRAWS`] the index pools are packed with the drawn patches in front,
//! in draw order — a GPU-side copy, the indices keep their values — and each stream is one
//! draw again. Strips are stored as self-contained blocks that concatenate:
//! ending in a restart (primitive restart), or, joined by zero-area windows
//! ([`Join::Degenerate`]), opening with the first index twice more and padded to an even
//! length, so every strip keeps its parity inside a merged draw. With indirect draws
//! (`Gpu::indirect`) the ranges become one `DrawIndexedIndirectArgs` each, written once per
//! rebuild, and every stream is one `multi_draw_indexed_indirect`; otherwise a loop of
//! `draw_indexed`. Mesh-patch cuts drawn from their hierarchies' static buffers
//! ([`Renderer::draws_static`]) keep that path; only their fat borders are resident.
//!
//! The result is the same picture as [`Renderer::upload`] bit for bit: the same triangles
//! with the same vertices, in the same order, each strip with its orientation
//! (`tests/resident.rs`).
//!
//! Not done here: frames with animation offsets or the heat map are drawn through
//! [`Renderer::upload`] (their meshes change every frame, see `frame::step`); pools never
//! shrink; patches that left the frustum are not evicted.

mod alloc;
mod pool;

pub use alloc::{Allocator, Move};

use std::collections::HashMap;

use super::pipelines::Pipelines;
use super::upload::{
    DRAW_ARGS_BYTES, StaticPatch, SurfaceVertex, encode_statics, offset_indices, packed_color,
    strips_of, surface_vertices,
};
use super::*;
use crate::strips::RESTART;
use pool::Pool;

const VERTICES: usize = 0;
const LIST: usize = 1;
const STRIPS: usize = 2;
const BORDER_VERTICES: usize = 3;
/// Fat-border index streams for [`FatBorders::Six`], `Four`, `Two`.
const BORDER: [usize; 3] = [4, 5, 6];
const STREAMS: usize = 7;
/// The index streams, in draw order.
const INDEX_STREAMS: [usize; 5] = [LIST, STRIPS, BORDER[0], BORDER[1], BORDER[2]];

/// What one [`ResidentGeometry::update`] did. Every byte given to `write_buffer` is counted
/// in exactly one field of [`UploadStats::uploaded_bytes`]; GPU-side copies are not uploads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Patches whose mesh was (re-)uploaded.
    pub patches: usize,
    /// Their geometry: surface vertices, list or strip indices, fat-border vertices and the
    /// indices of all three variants.
    pub geometry_bytes: u64,
    /// Index streams written again for patches whose vertices a compaction moved.
    pub reindexed_bytes: u64,
    /// Static buffers of mesh-patch hierarchies built on first use.
    pub static_bytes: u64,
    /// Indirect draw arguments (one `DrawIndexedIndirectArgs`, 20 bytes, per merged draw),
    /// written when the draw list was rebuilt on a device that draws indirect.
    pub args_bytes: u64,
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
        self.geometry_bytes + self.reindexed_bytes + self.static_bytes + self.args_bytes
    }
}

/// What a patch's slot holds.
#[derive(Clone, Debug, Default)]
struct Slot {
    mesh: Option<Arc<PatchMesh>>,
    /// Per stream `(start, len)` in units of its pool.
    ranges: [Option<(u64, u64)>; STREAMS],
    /// The patch's strips (local indices), kept to write them again after a compaction.
    strips: Option<Arc<Vec<u32>>>,
    /// Drawn from its hierarchy's static buffers (only the fat borders are resident).
    is_static: bool,
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
        let m = mesh.as_ref();
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
            borders: BorderGeometry::of(std::iter::once(m)),
        }
    }

    /// Units of stream `p` this patch takes.
    fn len(&self, p: usize) -> u64 {
        (match p {
            VERTICES => self.vertices.len(),
            LIST => self.list.len(),
            STRIPS => self.strip_block.len(),
            BORDER_VERTICES => self.borders.vertices.len(),
            _ => self.borders.indices[p - BORDER[0]].len(),
        }) as u64
    }

    /// Appends stream `p`'s bytes, indices offset by the slot's vertex bases.
    fn append(&self, p: usize, slot: &Slot, out: &mut Vec<u8>) {
        let base = |s: usize| slot.ranges[s].map_or(0, |r| r.0 as u32);
        match p {
            VERTICES => out.extend_from_slice(bytemuck::cast_slice(&self.vertices)),
            LIST => offset_indices(&self.list, base(VERTICES), out),
            STRIPS => offset_indices(&self.strip_block, base(VERTICES), out),
            BORDER_VERTICES => out.extend_from_slice(bytemuck::cast_slice(&self.borders.vertices)),
            _ => offset_indices(
                &self.borders.indices[p - BORDER[0]],
                base(BORDER_VERTICES),
                out,
            ),
        }
    }
}

/// Draws of the index streams past which their pools are packed in draw order.
const PACK_DRAWS: usize = 256;

/// Whether a pool is worth packing: a quarter or more of it free, in more than 64 ranges,
/// the longest under half of the free units.
fn fragmented(a: &Allocator) -> bool {
    a.free() * 4 >= a.capacity() && a.free_ranges() > 64 && a.largest_free() * 2 < a.free()
}

/// A patch's strips as a block that concatenates with its neighbours' (see the module doc).
fn strip_block(local: &[u32], join: Join) -> Vec<u32> {
    match join {
        Join::Restart => {
            let mut b = Vec::with_capacity(local.len() + 1);
            b.extend_from_slice(local);
            if !b.is_empty() {
                b.push(RESTART);
            }
            b
        }
        Join::Degenerate => {
            let joined = crate::strips::join_degenerate(local, &mut []);
            let (Some(&first), Some(&last)) = (joined.first(), joined.last()) else {
                return Vec::new();
            };
            // first, first: the window from the previous block's last index is zero-area
            // and the strip starts at an even index; last (twice when odd): so is the
            // window into the next block, which starts at an even index again.
            let mut b = Vec::with_capacity(joined.len() + 4);
            b.extend([first, first]);
            b.extend_from_slice(&joined);
            b.push(last);
            if b.len() % 2 == 1 {
                b.push(last);
            }
            b
        }
    }
}

/// Per-frame draws: merged ranges per index stream and the static patches' ranges.
#[derive(Debug, Default)]
struct DrawList {
    /// `[first index, index count]` per stream (empty for the vertex streams).
    ranges: [Vec<[u32; 2]>; STREAMS],
    /// First entry of each stream's ranges in the indirect arguments.
    first_arg: [u32; STREAMS],
    statics: Vec<(Arc<StaticPatch>, u32, u32)>,
    static_ranges: Vec<[u32; 2]>,
    statics_first_arg: u32,
}

impl DrawList {
    fn push(ranges: &mut Vec<[u32; 2]>, (start, len): (u64, u64)) {
        let (start, len) = (start as u32, len as u32);
        match ranges.last_mut() {
            Some(last) if last[0] + last[1] == start => last[1] += len,
            _ => ranges.push([start, len]),
        }
    }

    fn draw_count(&self) -> usize {
        INDEX_STREAMS
            .iter()
            .map(|&p| self.ranges[p].len())
            .sum::<usize>()
            + self.static_ranges.len()
    }
}

/// A fault to inject (tests prove they can fail with it).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fault {
    #[default]
    None,
    /// Every update leaves the first changed patch's slot as it was (a stale slot).
    KeepFirstStale,
}

/// Patch geometry resident on the GPU between frames (see the module doc). Per-view state:
/// owned by a `frame::FrameState`, bound to the device of the renderer that last updated it.
#[derive(Debug)]
pub struct ResidentGeometry {
    device: wgpu::Device,
    /// The renderer settings the slots were built with (primitives, strip join, static arcs).
    config: (Primitives, Join, bool),
    pools: [Pool; STREAMS],
    slots: Vec<Slot>,
    generation: Option<u64>,
    /// The patches of the last update (scene indices, in order).
    drawn: Vec<usize>,
    draws: DrawList,
    /// Indirect arguments of the draw list.
    args: Option<wgpu::Buffer>,
    #[doc(hidden)]
    pub fault: Fault,
}

impl ResidentGeometry {
    /// Empty pools on `renderer`'s device.
    pub fn new(renderer: &Renderer) -> ResidentGeometry {
        let gpu = &renderer.gpu;
        let (v, i) = (wgpu::BufferUsages::VERTEX, wgpu::BufferUsages::INDEX);
        let unit = |size: usize| size as u64;
        ResidentGeometry {
            device: gpu.device.clone(),
            config: (
                renderer.primitives,
                renderer.strip_join,
                renderer.static_arcs,
            ),
            pools: [
                Pool::new(
                    gpu,
                    "resident vertices",
                    v,
                    unit(size_of::<SurfaceVertex>()),
                ),
                Pool::new(gpu, "resident list indices", i, 4),
                Pool::new(gpu, "resident strip indices", i, 4),
                Pool::new(
                    gpu,
                    "resident fat border vertices",
                    v,
                    unit(size_of::<BorderVertex>()),
                ),
                Pool::new(gpu, "resident fat border indices 6", i, 4),
                Pool::new(gpu, "resident fat border indices 4", i, 4),
                Pool::new(gpu, "resident fat border indices 2", i, 4),
            ],
            slots: Vec::new(),
            generation: None,
            drawn: Vec::new(),
            draws: DrawList::default(),
            args: None,
            fault: Fault::None,
        }
    }

    /// Makes the patches `meshes` (scene index, mesh; the patches to draw, in scene order)
    /// resident and the draw list theirs. Nothing is walked when `generation` (the frame
    /// loop's, which changes whenever the meshes to draw change) is the last one seen. A
    /// pool that would pass the device's largest buffer is [`RenderError::TooLarge`]; the
    /// geometry is then emptied (the next update starts afresh).
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
        );
        if self.device != renderer.gpu.device || self.config != config {
            let fault = self.fault;
            *self = ResidentGeometry::new(renderer);
            self.fault = fault;
        }
        let mut stats = UploadStats::default();
        if self.generation == Some(generation) {
            return Ok(stats);
        }
        self.generation = Some(generation);
        let drawn: Vec<(usize, &Arc<PatchMesh>)> = meshes.into_iter().collect();
        if let Some(max) = drawn.iter().map(|d| d.0 + 1).max()
            && max > self.slots.len()
        {
            self.slots.resize(max, Slot::default());
        }
        let mut changed: Vec<(usize, &Arc<PatchMesh>)> = drawn
            .iter()
            .filter(|(i, m)| {
                !self.slots[*i]
                    .mesh
                    .as_ref()
                    .is_some_and(|held| Arc::ptr_eq(held, m))
            })
            .copied()
            .collect();
        if self.fault == Fault::KeepFirstStale && !changed.is_empty() {
            changed.remove(0);
        }
        if !changed.is_empty() {
            renderer.strips.begin_upload();
            let built: Vec<Built> = changed
                .par_iter()
                .map(|&(i, m)| Built::new(renderer, i, m, None, false))
                .collect();
            stats.patches = built.len();
            if let Err(e) = self.place(renderer, built, &mut stats) {
                let fault = self.fault;
                *self = ResidentGeometry::new(renderer);
                self.fault = fault;
                return Err(e);
            }
        }
        self.drawn = drawn.iter().map(|d| d.0).collect();
        let order = std::mem::take(&mut self.drawn);
        self.rebuild_draws(renderer, &order, &mut stats);
        self.drawn = order;
        Ok(stats)
    }

    /// Frees the changed slots' ranges, allocates and writes the new ones.
    fn place(
        &mut self,
        renderer: &Renderer,
        built: Vec<Built>,
        stats: &mut UploadStats,
    ) -> Result<(), RenderError> {
        let gpu = &renderer.gpu;
        for b in &built {
            let slot = &mut self.slots[b.slot];
            for (p, range) in slot.ranges.iter_mut().enumerate() {
                if let Some((start, _)) = range.take() {
                    self.pools[p].alloc.free_range(start);
                }
            }
            slot.mesh = Some(b.mesh.clone());
            slot.strips = b.strips.clone();
            slot.is_static = b.is_static;
        }
        let mut moved = Vec::new();
        for p in 0..STREAMS {
            let needed: u64 = built.iter().map(|b| b.len(p)).sum();
            if needed == 0 {
                continue;
            }
            let copied = self.pools[p].reserve(gpu, needed)?;
            stats.copied_bytes += copied;
            stats.grown += usize::from(copied > 0);
            for b in &built {
                let len = b.len(p);
                if len == 0 {
                    continue;
                }
                let start = match self.pools[p].alloc.alloc(len) {
                    Some(s) => s,
                    None => {
                        self.compact(gpu, p, &mut moved, stats);
                        // `reserve` left at least `needed` units free, and compaction made
                        // them one range.
                        self.pools[p]
                            .alloc
                            .alloc(len)
                            .expect("a compacted pool has its free units in one range")
                    }
                };
                self.slots[b.slot].ranges[p] = Some((start, len));
            }
        }
        // Pools left fragmented: packed again (the merged draws follow patch order again).
        for p in 0..STREAMS {
            if fragmented(&self.pools[p].alloc) {
                self.compact(gpu, p, &mut moved, stats);
            }
        }
        stats.geometry_bytes += self.write(gpu, &built);
        let fresh: std::collections::HashSet<usize> = built.iter().map(|b| b.slot).collect();
        moved.retain(|i| !fresh.contains(i));
        self.reindex(renderer, moved, stats);
        Ok(())
    }

    /// Writes the index streams of the slots `moved` again (their vertices moved).
    fn reindex(&mut self, renderer: &Renderer, mut moved: Vec<usize>, stats: &mut UploadStats) {
        moved.sort_unstable();
        moved.dedup();
        let reindexed: Vec<Built> = moved
            .par_iter()
            .filter_map(|&i| {
                let s = &self.slots[i];
                let mesh = s.mesh.as_ref()?;
                Some(Built::new(renderer, i, mesh, s.strips.clone(), true))
            })
            .collect();
        stats.reindexed_bytes += self.write(&renderer.gpu, &reindexed);
    }

    /// Packs every pool in patch order now (each slot's ranges adjacent to its neighbours',
    /// so the draws of patches in a row merge), writes the index streams of the patches whose
    /// vertices moved and rebuilds the draw list.
    pub fn compact_all(&mut self, renderer: &Renderer) -> UploadStats {
        let mut stats = UploadStats::default();
        let mut moved = Vec::new();
        for p in 0..STREAMS {
            self.compact(&renderer.gpu, p, &mut moved, &mut stats);
        }
        self.reindex(renderer, moved, &mut stats);
        let drawn = std::mem::take(&mut self.drawn);
        self.rebuild_draws(renderer, &drawn, &mut stats);
        self.drawn = drawn;
        stats
    }

    /// Packs pool `p` in patch order; records the slots whose vertices moved in `moved`.
    fn compact(&mut self, gpu: &Gpu, p: usize, moved: &mut Vec<usize>, stats: &mut UploadStats) {
        let all: Vec<usize> = (0..self.slots.len()).collect();
        self.compact_in(gpu, p, &all, moved, stats);
    }

    /// Packs pool `p` with the ranges of the slots `first` in front, in that order (the
    /// others after them by address); records the slots whose vertices moved in `moved`.
    fn compact_in(
        &mut self,
        gpu: &Gpu,
        p: usize,
        first: &[usize],
        moved: &mut Vec<usize>,
        stats: &mut UploadStats,
    ) {
        let order: Vec<u64> = first
            .iter()
            .filter_map(|&i| self.slots[i].ranges[p].map(|r| r.0))
            .collect();
        let (moves, copied) = self.pools[p].compact(gpu, order);
        stats.copied_bytes += copied;
        stats.compactions += 1;
        let to: HashMap<u64, u64> = moves.iter().map(|m| (m.from, m.to)).collect();
        for (i, slot) in self.slots.iter_mut().enumerate() {
            if let Some((start, len)) = slot.ranges[p]
                && let Some(&new) = to.get(&start)
            {
                slot.ranges[p] = Some((new, len));
                if p == VERTICES || p == BORDER_VERTICES {
                    moved.push(i);
                }
            }
        }
    }

    /// Writes the streams of `built` (index streams only for re-indexed patches), each
    /// pool's contiguous ranges in one `write_buffer`. Returns the bytes written.
    fn write(&self, gpu: &Gpu, built: &[Built]) -> u64 {
        let mut written = 0;
        for (p, pool) in self.pools.iter().enumerate() {
            if (p == VERTICES || p == BORDER_VERTICES) && built.iter().all(|b| b.reindex) {
                continue;
            }
            let mut items: Vec<(u64, &Built)> = built
                .iter()
                .filter(|b| !(b.reindex && (p == VERTICES || p == BORDER_VERTICES)))
                .filter_map(|b| Some((self.slots[b.slot].ranges[p]?.0, b)))
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
                b.append(p, &self.slots[b.slot], &mut bytes);
            }
            if let Some(r) = run {
                written += pool.write(gpu, r, &bytes);
            }
        }
        written
    }

    /// The draw list of `drawn` (see the module doc), with its indirect arguments. When the
    /// index streams split into more than [`PACK_DRAWS`] draws, their pools are packed with
    /// the drawn patches in front, in order (a GPU-side copy; indices do not change), so each
    /// stream is one draw again.
    fn rebuild_draws(&mut self, renderer: &Renderer, drawn: &[usize], stats: &mut UploadStats) {
        let mut d = self.collect_draws(renderer, drawn, stats);
        let split: usize = INDEX_STREAMS.iter().map(|&p| d.ranges[p].len()).sum();
        if split > PACK_DRAWS {
            let mut moved = Vec::new();
            for p in INDEX_STREAMS {
                self.compact_in(&renderer.gpu, p, drawn, &mut moved, stats);
            }
            d = self.collect_draws(renderer, drawn, stats);
        }
        stats.rebuilt = true;
        self.write_args(renderer, &mut d, stats);
        self.draws = d;
    }

    /// The merged draws of `drawn`, no arguments yet.
    fn collect_draws(
        &self,
        renderer: &Renderer,
        drawn: &[usize],
        stats: &mut UploadStats,
    ) -> DrawList {
        let mut d = DrawList::default();
        for &i in drawn {
            let slot = &self.slots[i];
            for p in INDEX_STREAMS {
                if let Some(r) = slot.ranges[p] {
                    DrawList::push(&mut d.ranges[p], r);
                }
            }
            if slot.is_static
                && let Some(m) = &slot.mesh
            {
                stats.static_bytes += renderer
                    .static_draws(m, &mut d.statics, &mut d.static_ranges)
                    .1;
            }
        }
        d
    }

    /// Writes the indirect arguments of `d` (on devices that draw indirect).
    fn write_args(&mut self, renderer: &Renderer, d: &mut DrawList, stats: &mut UploadStats) {
        if renderer.gpu.indirect {
            let mut args: Vec<u8> = Vec::with_capacity(d.draw_count() * DRAW_ARGS_BYTES as usize);
            let mut n = 0u32;
            let mut put = |ranges: &[[u32; 2]], args: &mut Vec<u8>| {
                let first = n;
                for &[first_index, index_count] in ranges {
                    args.extend_from_slice(
                        wgpu::util::DrawIndexedIndirectArgs {
                            index_count,
                            instance_count: 1,
                            first_index,
                            base_vertex: 0,
                            first_instance: 0,
                        }
                        .as_bytes(),
                    );
                }
                n += ranges.len() as u32;
                first
            };
            for p in INDEX_STREAMS {
                d.first_arg[p] = put(&d.ranges[p], &mut args);
            }
            d.statics_first_arg = put(&d.static_ranges, &mut args);
            if !args.is_empty() {
                let gpu = &renderer.gpu;
                if self
                    .args
                    .as_ref()
                    .is_none_or(|b| b.size() < args.len() as u64)
                {
                    let size = (args.len() as u64 * 3 / 2).next_multiple_of(DRAW_ARGS_BYTES * 4);
                    self.args = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("resident draw arguments"),
                        size,
                        usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }));
                }
                if let Some(b) = &self.args {
                    gpu.queue.write_buffer(b, 0, &args);
                    stats.args_bytes = args.len() as u64;
                }
            }
        }
    }

    /// Merged draws of the current draw list (all streams, static ranges included).
    pub fn draw_count(&self) -> usize {
        self.draws.draw_count()
    }

    /// Records the draws of `variant` into `pass`.
    pub(super) fn encode(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        variant: FatBorders,
        indirect: bool,
    ) {
        let d = &self.draws;
        let args = self.args.as_ref().filter(|_| indirect);
        let draw = |pass: &mut wgpu::RenderPass<'_>, p: usize| match args {
            Some(a) => pass.multi_draw_indexed_indirect(
                a,
                d.first_arg[p] as u64 * DRAW_ARGS_BYTES,
                d.ranges[p].len() as u32,
            ),
            None => {
                for &[first, count] in &d.ranges[p] {
                    pass.draw_indexed(first..first + count, 0, 0..1);
                }
            }
        };
        for (p, pipeline) in [(LIST, &pipes.surface), (STRIPS, &pipes.surface_strip)] {
            if !d.ranges[p].is_empty() {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, self.pools[VERTICES].buffer.slice(..));
                pass.set_index_buffer(self.pools[p].buffer.slice(..), wgpu::IndexFormat::Uint32);
                draw(pass, p);
            }
        }
        encode_statics(
            pass,
            pipes,
            &d.statics,
            args.map(|a| (a, d.statics_first_arg)),
            &d.static_ranges,
        );
        let p = match variant {
            FatBorders::Off => return,
            FatBorders::Six => BORDER[0],
            FatBorders::Four => BORDER[1],
            FatBorders::Two => BORDER[2],
        };
        if !d.ranges[p].is_empty() {
            pass.set_pipeline(&pipes.border);
            pass.set_vertex_buffer(0, self.pools[BORDER_VERTICES].buffer.slice(..));
            pass.set_index_buffer(self.pools[p].buffer.slice(..), wgpu::IndexFormat::Uint32);
            draw(pass, p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_blocks_concatenate_with_every_strip_at_an_even_index() {
        // Two patches' strips, each two strips joined by a restart.
        let a = strip_block(&[0, 1, 2, 3, 4, RESTART, 5, 6, 7], Join::Degenerate);
        let b = strip_block(&[10, 11, 12, RESTART, 13, 14, 15, 16], Join::Degenerate);
        assert_eq!(a.len() % 2, 0);
        assert_eq!(b.len() % 2, 0);
        let merged: Vec<u32> = a.iter().chain(&b).copied().collect();
        // Triangles with their strip orientation (odd positions swap the first two).
        let tris = |s: &[u32]| -> Vec<[u32; 3]> {
            s.windows(3)
                .enumerate()
                .map(|(k, w)| {
                    if k % 2 == 0 {
                        [w[0], w[1], w[2]]
                    } else {
                        [w[1], w[0], w[2]]
                    }
                })
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .collect()
        };
        let alone = |local: &[u32]| {
            let mut out = Vec::new();
            for s in local.split(|&i| i == RESTART) {
                out.extend(tris(s));
            }
            out
        };
        let mut want = alone(&[0, 1, 2, 3, 4, RESTART, 5, 6, 7]);
        want.extend(alone(&[10, 11, 12, RESTART, 13, 14, 15, 16]));
        assert_eq!(tris(&merged), want);
    }

    #[test]
    fn restart_blocks_end_in_a_restart() {
        assert_eq!(
            strip_block(&[0, 1, 2], Join::Restart),
            vec![0, 1, 2, RESTART]
        );
        assert!(strip_block(&[], Join::Restart).is_empty());
        assert!(strip_block(&[], Join::Degenerate).is_empty());
    }
}
