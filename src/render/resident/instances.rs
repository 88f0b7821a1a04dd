//! Instanced parts in the resident geometry: a patch whose mesh is an [`Instance`] (a
//! placement of a tessellation other placements share, `lod::shared`) uploads no geometry of
//! its own. The shared mesh is resident once, in its surface's own coordinates, in a slot of
//! its own (kept while some drawn placement uses it); the patch keeps one
//! [`InstanceRecord`] — its placement, patch id, colour and added ε — and each shared mesh
//! is drawn once per stream with its placements as instances (`vs_surface_placed`,
//! `vs_border_placed`: the ring points are moved before the fat border is expanded, so the
//! border is the one of the placed mesh). Patch ids stay per placed patch, so the ID image,
//! the visibility and the crack checks see every placement.
//!
//! The records live in a storage buffer (a [`Pool`] of 64-byte units, grown like the others),
//! written when a placed patch changes — 64 bytes instead of its geometry. When the draw list
//! is rebuilt, the indices of the drawn placements' records, grouped by shared mesh (in slot
//! order, each group in patch order), form the instance-step vertex buffer; only the indices
//! that differ from the last ones written are uploaded.

use crate::util::IntMap;
use std::ops::{Index, IndexMut};

use super::super::pipelines::Pipelines;
use super::*;
use crate::tessellate::Instance;

/// One placement of a shared mesh as the placed pipelines read it (`PlacedRecord` in
/// `shaders/scene.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct InstanceRecord {
    /// Rows of the placement's 3 × 4 matrix.
    pub rows: [[f32; 4]; 3],
    pub patch_id: u32,
    /// As the surface vertices' colour attribute (`Unorm8x4`, little-endian).
    pub color: u32,
    /// ε the placement adds to its shared mesh's (world units, rounded up).
    pub eps_added: f32,
    pub pad: u32,
}

impl InstanceRecord {
    /// The record of `mesh`, drawn as `instance`.
    pub fn of(mesh: &PatchMesh, instance: &Instance) -> InstanceRecord {
        let m = instance.transform;
        let row = |k: usize| m.row(k).as_vec4().to_array();
        let e = instance.error_added as f32;
        InstanceRecord {
            rows: [row(0), row(1), row(2)],
            patch_id: mesh.patch_id,
            color: u32::from_le_bytes(packed_color(mesh.color)),
            eps_added: if (e as f64) < instance.error_added {
                e * (1.0 + f32::EPSILON)
            } else {
                e
            },
            pad: 0,
        }
    }
}

/// Key bit of a shared mesh's slot (the other keys are scene patch indices).
pub(super) const SHARED: usize = 1 << (usize::BITS - 2);

/// The slots of the scene's patches and of the shared meshes, indexed by key.
#[derive(Debug, Default)]
pub(super) struct Slots {
    pub(super) patches: Vec<Slot>,
    shared: Vec<Slot>,
    /// Shared mesh (the address of its `Arc`, which its slot holds) → key.
    by_mesh: IntMap<usize, usize>,
    free: Vec<usize>,
}

impl Index<usize> for Slots {
    type Output = Slot;
    fn index(&self, k: usize) -> &Slot {
        if k & SHARED != 0 {
            &self.shared[k & !SHARED]
        } else {
            &self.patches[k]
        }
    }
}

impl IndexMut<usize> for Slots {
    fn index_mut(&mut self, k: usize) -> &mut Slot {
        if k & SHARED != 0 {
            &mut self.shared[k & !SHARED]
        } else {
            &mut self.patches[k]
        }
    }
}

impl Slots {
    /// Every slot with its key.
    pub(super) fn iter_mut(&mut self) -> impl Iterator<Item = (usize, &mut Slot)> {
        let shared = self.shared.iter_mut().enumerate();
        self.patches
            .iter_mut()
            .enumerate()
            .chain(shared.map(|(k, s)| (k | SHARED, s)))
    }

    /// Shared slots (in use or free): keys `SHARED | k` for `k` below it.
    fn shared_slots(&self) -> usize {
        self.shared.len()
    }

    /// Shared meshes resident.
    pub(super) fn shared_count(&self) -> usize {
        self.by_mesh.len()
    }

    /// One more user of `mesh`'s slot: its key, and whether the slot is new (its geometry
    /// still to be built).
    fn acquire(&mut self, mesh: &Arc<PatchMesh>) -> (usize, bool) {
        let ptr = Arc::as_ptr(mesh) as usize;
        if let Some(&k) = self.by_mesh.get(&ptr) {
            self[k].users += 1;
            return (k, false);
        }
        let k = self.free.pop().unwrap_or_else(|| {
            self.shared.push(Slot::default());
            (self.shared.len() - 1) | SHARED
        });
        self.by_mesh.insert(ptr, k);
        self[k] = Slot {
            mesh: Some(mesh.clone()),
            users: 1,
            ..Slot::default()
        };
        (k, true)
    }

    /// One user less of shared slot `k`: the slot as it was when nobody uses it any more
    /// (emptied here; the caller frees its ranges).
    fn release(&mut self, k: usize) -> Option<Slot> {
        let s = &mut self[k];
        s.users = s.users.saturating_sub(1);
        if s.users > 0 {
            return None;
        }
        let old = std::mem::take(s);
        if let Some(m) = &old.mesh {
            self.by_mesh.remove(&(Arc::as_ptr(m) as usize));
        }
        self.free.push(k);
        Some(old)
    }
}

impl ResidentGeometry {
    /// Attaches the changed patches whose meshes are instances to their shared meshes' slots
    /// (their own ranges freed, their records written) and releases the shared meshes they
    /// used before. Returns the slots to build: new shared meshes and the other changed
    /// patches.
    pub(super) fn attach_instances(
        &mut self,
        renderer: &Renderer,
        changed: Vec<(usize, &Arc<PatchMesh>)>,
        stats: &mut UploadStats,
    ) -> Result<Vec<(usize, Arc<PatchMesh>)>, RenderError> {
        let mut build = Vec::with_capacity(changed.len());
        let mut released = Vec::new();
        let mut records = Vec::new();
        for (i, m) in changed {
            released.extend(self.slots[i].instance_of.take());
            let record_at = self.slots[i].record_at.take();
            let Some(inst) = m.instance.as_ref().filter(|_| renderer.instances) else {
                if let Some(r) = record_at {
                    self.placed.free_record(r);
                }
                build.push((i, m.clone()));
                continue;
            };
            let (k, new) = self.slots.acquire(&inst.shared);
            if new {
                build.push((k, inst.shared.clone()));
            }
            let mut record = InstanceRecord::of(m, inst);
            if self.fault == Fault::UnplacedInstances {
                record.rows = [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                ];
            }
            let old = std::mem::replace(
                &mut self.slots[i],
                Slot {
                    mesh: Some(m.clone()),
                    instance_of: Some(k),
                    record_at,
                    ..Slot::default()
                },
            );
            self.free_ranges(&old);
            // A placement that only changed level (another shared mesh, the same record:
            // the teapot grid's copies) writes nothing.
            if record_at.is_none_or(|at| !self.placed.holds(at, &record)) {
                records.push((i, record));
            }
            stats.placed += 1;
        }
        for k in released {
            if let Some(old) = self.slots.release(k) {
                self.free_ranges(&old);
            }
        }
        let missing = records
            .iter()
            .filter(|(i, _)| self.slots[*i].record_at.is_none())
            .count() as u64;
        self.placed.reserve(renderer, missing, stats)?;
        let mut writes: Vec<(u64, InstanceRecord)> = Vec::with_capacity(records.len());
        for (i, record) in records {
            let at = match self.slots[i].record_at {
                Some(at) => at,
                None => {
                    let at = self.placed.alloc_record();
                    self.slots[i].record_at = Some(at);
                    at
                }
            };
            writes.push((at, record));
        }
        self.placed.write_records(&renderer.gpu, writes, stats);
        Ok(build)
    }

    /// Frees the ranges `slot` held.
    fn free_ranges(&mut self, slot: &Slot) {
        for (p, range) in slot.ranges.iter().enumerate() {
            if let Some((start, _)) = range {
                self.arenas[slot.arena].pools[p].alloc.free_range(*start);
            }
        }
    }

    /// Shared meshes resident (instanced parts).
    pub fn shared_meshes(&self) -> usize {
        self.slots.shared_count()
    }

    /// Patches of the last update drawn as placements of a shared mesh.
    pub fn placed_patches(&self) -> usize {
        self.placed.list.len()
    }
}

/// One shared mesh's draws: its arena, its ranges per stream, and the first and number of
/// its placements' record indices.
type PlacedGroup = (usize, [Option<(u64, u64)>; STREAMS], u32, u32);

/// The placement records (a pool of [`InstanceRecord`]s in a storage buffer) and the draws
/// of the placed patches: per shared mesh drawn, its arena, its ranges and a run of the
/// record indices.
#[derive(Debug, Default)]
pub(super) struct PlacedDraws {
    records: Option<(Pool, wgpu::BindGroup)>,
    groups: Vec<PlacedGroup>,
    /// The drawn placements' record indices, grouped; those last written, and their buffer.
    list: Vec<u32>,
    written: Vec<u32>,
    buffer: Option<wgpu::Buffer>,
    /// The records as written, by index (what the GPU holds; a record written again with
    /// the same bytes is not uploaded).
    shadow: Vec<InstanceRecord>,
}

impl PlacedDraws {
    /// Makes room for `needed` more records (the pool made or grown, its bind group renewed).
    fn reserve(
        &mut self,
        renderer: &Renderer,
        needed: u64,
        stats: &mut UploadStats,
    ) -> Result<(), RenderError> {
        if needed == 0 {
            return Ok(());
        }
        let gpu = &renderer.gpu;
        let (pool, bind) = self.records.get_or_insert_with(|| {
            let pool = Pool::new(
                gpu,
                "placement records",
                wgpu::BufferUsages::STORAGE,
                size_of::<InstanceRecord>() as u64,
                renderer.max_points_bytes(),
            );
            let bind = renderer.records_bind_group(&pool.buffer);
            (pool, bind)
        });
        let copied = pool.reserve(gpu, needed)?;
        if copied > 0 {
            stats.copied_bytes += copied;
            stats.grown += 1;
            *bind = renderer.records_bind_group(&pool.buffer);
        }
        Ok(())
    }

    /// Bytes of the records' buffer, and of the live records.
    pub(super) fn records_memory(&self) -> (u64, u64) {
        self.records.as_ref().map_or((0, 0), |(pool, _)| {
            (pool.bytes(), pool.alloc.used() * pool.unit)
        })
    }

    /// A record's index (after [`PlacedDraws::reserve`] made room for it).
    fn alloc_record(&mut self) -> u64 {
        self.records
            .as_mut()
            .and_then(|(pool, _)| pool.alloc.alloc(1))
            .expect("reserve made room for every record allocated")
    }

    /// Whether record `at` holds `record` already.
    fn holds(&self, at: u64, record: &InstanceRecord) -> bool {
        self.shadow.get(at as usize) == Some(record)
    }

    fn free_record(&mut self, at: u64) {
        if let Some((pool, _)) = &mut self.records {
            pool.alloc.free_range(at);
        }
    }

    /// Writes the staged records ([`Pool::flush`]).
    pub(super) fn flush(&mut self, gpu: &crate::render::Gpu) {
        if let Some((pool, _)) = &mut self.records {
            pool.flush(gpu);
        }
    }

    /// Stages `records` at their indices, each run of consecutive indices at once.
    fn write_records(
        &mut self,
        gpu: &crate::render::Gpu,
        mut records: Vec<(u64, InstanceRecord)>,
        stats: &mut UploadStats,
    ) {
        let Some((pool, _)) = &mut self.records else {
            return;
        };
        records.sort_unstable_by_key(|r| r.0);
        if let Some(last) = records.last()
            && last.0 as usize >= self.shadow.len()
        {
            self.shadow
                .resize(last.0 as usize + 1, InstanceRecord::default());
        }
        for (at, r) in &records {
            self.shadow[*at as usize] = *r;
        }
        let mut k = 0;
        while k < records.len() {
            let start = k;
            while k + 1 < records.len() && records[k + 1].0 == records[k].0 + 1 {
                k += 1;
            }
            k += 1;
            let run: Vec<InstanceRecord> = records[start..k].iter().map(|r| r.1).collect();
            stats.instance_bytes += pool.write(gpu, records[start].0, bytemuck::cast_slice(&run));
        }
    }

    /// Groups the placed patches among `drawn` by shared mesh (in slot order, each group in
    /// the order of `drawn`).
    /// (A counting sort by shared slot: two passes over `drawn`, no map.)
    pub(super) fn collect(&mut self, slots: &Slots, drawn: &[usize]) {
        let placed = |i: &usize| {
            let s = &slots[*i];
            Some((s.instance_of? & !SHARED, s.record_at? as u32))
        };
        // Per shared slot its placements' first index in the list, then where the next goes.
        let mut next = vec![0u32; slots.shared_slots() + 1];
        for (k, _) in drawn.iter().filter_map(placed) {
            next[k + 1] += 1;
        }
        for k in 1..next.len() {
            next[k] += next[k - 1];
        }
        let starts = next.clone();
        self.list.clear();
        self.list.resize(next[next.len() - 1] as usize, 0);
        for (k, at) in drawn.iter().filter_map(placed) {
            self.list[next[k] as usize] = at;
            next[k] += 1;
        }
        self.groups.clear();
        for k in 0..slots.shared_slots() {
            let (first, end) = (starts[k], starts[k + 1]);
            let s = &slots[k | SHARED];
            if end > first && s.ranges.iter().any(Option::is_some) {
                self.groups.push((s.arena, s.ranges, first, end - first));
            }
        }
    }

    /// Writes the record indices that differ from those last written (the buffer made or
    /// grown as needed); counts the bytes in `stats`.
    pub(super) fn write(&mut self, renderer: &Renderer, stats: &mut UploadStats) {
        if self.list.is_empty() {
            return;
        }
        let gpu = &renderer.gpu;
        let need = self.list.len() as u64 * 4;
        if self.buffer.as_ref().is_none_or(|b| b.size() < need) {
            self.buffer = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("placed record indices"),
                size: (need * 3 / 2).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
            self.written.clear();
        }
        let Some(buffer) = &self.buffer else {
            return;
        };
        let n = self.list.len();
        let mut k = 0;
        while k < n {
            if self.written.get(k) == Some(&self.list[k]) {
                k += 1;
                continue;
            }
            let start = k;
            while k < n && self.written.get(k) != Some(&self.list[k]) {
                k += 1;
            }
            let bytes: &[u8] = bytemuck::cast_slice(&self.list[start..k]);
            gpu.queue.write_buffer(buffer, start as u64 * 4, bytes);
            stats.instance_bytes += bytes.len() as u64;
        }
        self.written.clone_from(&self.list);
    }

    /// Records the surface draws of the placed patches: one per shared mesh and stream.
    pub(super) fn encode_surfaces(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        arenas: &[Arena],
    ) {
        let (Some(list), Some((_, records))) = (&self.buffer, &self.records) else {
            return;
        };
        for (p, pipeline) in [
            (LIST, &pipes.surface_placed),
            (STRIPS, &pipes.surface_strip_placed),
        ] {
            let mut bound = false;
            for &(a, ranges, first, count) in &self.groups {
                let Some((start, len)) = ranges[p] else {
                    continue;
                };
                if !bound {
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(2, records, &[]);
                    pass.set_vertex_buffer(1, list.slice(..));
                    bound = true;
                }
                let pools = &arenas[a].pools;
                pass.set_vertex_buffer(0, pools[VERTICES].buffer.slice(..));
                pass.set_index_buffer(pools[p].buffer.slice(..), wgpu::IndexFormat::Uint32);
                let (start, len) = (start as u32, len as u32);
                pass.draw_indexed(start..start + len, 0, first..first + count);
            }
        }
    }

    /// Records the edge lines of the placed patches: each shared mesh's points once per
    /// placement.
    pub(super) fn encode_edges(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &EdgePipelines,
        arenas: &[Arena],
    ) {
        let (Some(list), Some((_, records))) = (&self.buffer, &self.records) else {
            return;
        };
        if !self.groups.iter().any(|g| g.1[POINTS].is_some()) {
            return;
        }
        pass.set_pipeline(&pipes.placed);
        pass.set_bind_group(2, records, &[]);
        pass.set_vertex_buffer(0, list.slice(..));
        for &(a, ranges, first, count) in &self.groups {
            let Some((start, len)) = ranges[POINTS] else {
                continue;
            };
            pass.set_bind_group(1, &arenas[a].points_bind.1, &[]);
            draw_edges(pass, start as u32, len as u32, first..first + count);
        }
    }

    /// Records the fat-border draws of `variant` (its index pattern `pattern`) of the placed
    /// patches.
    pub(super) fn encode_borders(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        pattern: &wgpu::Buffer,
        arenas: &[Arena],
        variant: FatBorders,
    ) {
        let (Some(list), Some((_, records))) = (&self.buffer, &self.records) else {
            return;
        };
        if !self.groups.iter().any(|g| g.1[POINTS].is_some()) {
            return;
        }
        let codes = fat_border::pattern(variant).len() as u32;
        pass.set_pipeline(&pipes.border_placed);
        pass.set_bind_group(2, records, &[]);
        pass.set_index_buffer(pattern.slice(..), wgpu::IndexFormat::Uint32);
        pass.set_vertex_buffer(0, list.slice(..));
        for &(a, ranges, first, count) in &self.groups {
            let Some((start, len)) = ranges[POINTS] else {
                continue;
            };
            pass.set_bind_group(1, &arenas[a].points_bind.1, &[]);
            let mut done = 0;
            while done < len {
                let n = (len - done).min(PATTERN_POINTS as u64) as u32;
                let base = (start + done) as usize * fat_border::SLOTS_PER_POINT;
                pass.draw_indexed(0..n * codes, base as i32, first..first + count);
                done += n as u64;
            }
        }
    }
}
