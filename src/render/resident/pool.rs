//! One GPU buffer suballocated by an [`Allocator`]: growth by reallocation with a GPU-side
//! copy (`copy_buffer_to_buffer`, ranges keep their addresses) up to a largest size (the
//! device's largest buffer or binding; past it the caller opens another arena), compaction
//! into a new buffer (ranges move; the caller fixes what refers to them).
//!
//! Writes are staged: [`Pool::write`] keeps the bytes, [`Pool::flush`] puts a frame's writes
//! in one staging buffer and copies each run from it (wgpu's `Queue::write_buffer` makes a
//! staging buffer per call; thousands of scattered instance records a frame made that most
//! of the upload's CPU time). Growth keeps every address, so writes staged before it land in
//! the new buffer, after the growth's copy; compaction moves ranges, so it flushes first.

use super::alloc::{Allocator, Move};
use crate::render::{Gpu, RenderError};

/// Most bytes a pool stages before it writes them.
const STAGED_BYTES: usize = 8 << 20;

/// Units a new pool holds (empty buffers cannot be bound).
const MIN_CAPACITY: u64 = 1024;

/// A GPU buffer of `unit`-byte elements and the allocator of its ranges.
#[derive(Debug)]
pub(crate) struct Pool {
    pub(crate) label: &'static str,
    usage: wgpu::BufferUsages,
    /// Bytes per unit (a multiple of 4, `COPY_BUFFER_ALIGNMENT`).
    pub(crate) unit: u64,
    /// Units the pool may grow to.
    pub(crate) max_units: u64,
    pub(crate) buffer: wgpu::Buffer,
    pub(crate) alloc: Allocator,
    /// Staged writes: their bytes, and per run (byte offset in the buffer, offset in
    /// `pending`, length).
    pending: Vec<u8>,
    runs: Vec<(u64, u64, u64)>,
}

impl Pool {
    pub(crate) fn new(
        gpu: &Gpu,
        label: &'static str,
        usage: wgpu::BufferUsages,
        unit: u64,
        max_bytes: u64,
    ) -> Pool {
        debug_assert!(unit.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT));
        let usage = usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let max_units = (max_bytes / unit).max(1);
        let first = MIN_CAPACITY.min(max_units);
        Pool {
            label,
            usage,
            unit,
            max_units,
            buffer: buffer(gpu, label, usage, unit * first),
            alloc: Allocator::new(first),
            pending: Vec::new(),
            runs: Vec::new(),
        }
    }

    /// Whether `needed` more units fit under [`Pool::max_units`].
    pub(crate) fn fits(&self, needed: u64) -> bool {
        self.alloc.used() + needed <= self.max_units
    }

    /// Makes room for `needed` more units in all (not necessarily in one range): grows to
    /// at least 1.5× when the free units fall short, never past [`Pool::max_units`]
    /// ([`RenderError::TooLarge`] when even that is too small). Returns the bytes copied on
    /// the GPU.
    pub(crate) fn reserve(&mut self, gpu: &Gpu, needed: u64) -> Result<u64, RenderError> {
        if self.alloc.free() >= needed {
            return Ok(0);
        }
        let max_units = self.max_units;
        let used = self.alloc.used() + needed;
        if used > max_units {
            return Err(RenderError::TooLarge {
                what: self.label,
                bytes: used.saturating_mul(self.unit),
                limit: max_units * self.unit,
            });
        }
        let want = (used * 9 / 8).min(max_units);
        let capacity = want
            .max((self.alloc.capacity() * 3 / 2).min(max_units))
            .max(MIN_CAPACITY.min(max_units));
        let new = buffer(gpu, self.label, self.usage, capacity * self.unit);
        let copied = self.alloc.capacity() * self.unit;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &new, 0, copied);
        gpu.queue.submit([encoder.finish()]);
        self.buffer = new;
        self.alloc.grow(capacity);
        Ok(copied)
    }

    /// Packs the live ranges in `order` (starts; see [`Allocator::compact`]) into a new buffer
    /// of the same size. Returns the moves and the bytes copied on the GPU.
    pub(crate) fn compact(
        &mut self,
        gpu: &Gpu,
        order: impl IntoIterator<Item = u64>,
    ) -> (Vec<Move>, u64) {
        self.flush(gpu);
        let before: Vec<(u64, u64)> = self.alloc.live().collect();
        let moves = self.alloc.compact(order);
        let moved: std::collections::HashMap<u64, u64> =
            moves.iter().map(|m| (m.from, m.to)).collect();
        // Every live range, moved or not, goes to the new buffer: runs contiguous in both
        // buffers are one copy.
        let mut copies: Vec<(u64, u64, u64)> = before
            .iter()
            .map(|&(from, len)| (moved.get(&from).copied().unwrap_or(from), from, len))
            .collect();
        copies.sort_unstable();
        let new = buffer(
            gpu,
            self.label,
            self.usage,
            self.alloc.capacity() * self.unit,
        );
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let mut copied = 0;
        let mut run: Option<(u64, u64, u64)> = None;
        let mut flush = |r: (u64, u64, u64), e: &mut wgpu::CommandEncoder| {
            let (to, from, len) = r;
            e.copy_buffer_to_buffer(
                &self.buffer,
                from * self.unit,
                &new,
                to * self.unit,
                len * self.unit,
            );
            copied += len * self.unit;
        };
        for (to, from, len) in copies {
            run = match run {
                Some((t, f, l)) if t + l == to && f + l == from => Some((t, f, l + len)),
                Some(r) => {
                    flush(r, &mut encoder);
                    Some((to, from, len))
                }
                None => Some((to, from, len)),
            };
        }
        if let Some(r) = run {
            flush(r, &mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        self.buffer = new;
        (moves, copied)
    }

    /// Bytes of the buffer.
    pub(crate) fn bytes(&self) -> u64 {
        self.alloc.capacity() * self.unit
    }

    /// Stages `bytes` for unit `start` (written by the next [`Pool::flush`], or now when
    /// more than [`STAGED_BYTES`] are staged: a whole upload of a large scene is not held
    /// twice); returns the bytes staged.
    pub(crate) fn write(&mut self, gpu: &Gpu, start: u64, bytes: &[u8]) -> u64 {
        if self.pending.len() + bytes.len() > STAGED_BYTES {
            self.flush(gpu);
        }
        if !bytes.is_empty() {
            let at = start * self.unit;
            let from = self.pending.len() as u64;
            let len = bytes.len() as u64;
            self.pending.extend_from_slice(bytes);
            match self.runs.last_mut() {
                // A run continuing the last one in both buffers: one copy.
                Some((to, f, l)) if *to + *l == at && *f + *l == from => *l += len,
                _ => self.runs.push((at, from, len)),
            }
        }
        bytes.len() as u64
    }

    /// Writes the staged bytes: one staging buffer, one copy per run, one submission.
    pub(crate) fn flush(&mut self, gpu: &Gpu) {
        if self.runs.is_empty() {
            return;
        }
        // Every unit is a multiple of 4 bytes (`COPY_BUFFER_ALIGNMENT`), so are the runs.
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staged writes"),
            size: self.pending.len() as u64,
            usage: wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        });
        let mapped = staging
            .slice(..)
            .get_mapped_range_mut()
            .map(|mut view| view.copy_from_slice(&self.pending));
        staging.unmap();
        if mapped.is_ok() {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            for &(to, from, len) in &self.runs {
                encoder.copy_buffer_to_buffer(&staging, from, &self.buffer, to, len);
            }
            gpu.queue.submit([encoder.finish()]);
        } else {
            // (A buffer mapped at creation maps; should it not, the slow way still writes.)
            for &(to, from, len) in &self.runs {
                let bytes = &self.pending[from as usize..(from + len) as usize];
                gpu.queue.write_buffer(&self.buffer, to, bytes);
            }
        }
        self.pending.clear();
        self.runs.clear();
    }
}

fn buffer(gpu: &Gpu, label: &str, usage: wgpu::BufferUsages, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pool's buffer as words (a copy into a mapped buffer).
    fn read(gpu: &Gpu, pool: &Pool) -> Vec<u32> {
        let size = pool.bytes();
        let out = buffer(
            gpu,
            "read back",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            size,
        );
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&pool.buffer, 0, &out, 0, size);
        gpu.queue.submit([encoder.finish()]);
        out.map_async(wgpu::MapMode::Read, .., |r| r.expect("maps"));
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("polls");
        let words = bytemuck::cast_slice(&out.get_mapped_range(..).expect("mapped")).to_vec();
        out.unmap();
        words
    }

    /// Writes staged before a growth or a compaction are in the new buffer: growth keeps
    /// addresses (the flush after it writes there), compaction flushes first (the update
    /// flushes before either today, so only this test sees it).
    #[test]
    fn staged_writes_survive_growth_and_compaction() {
        let gpu = Gpu::new().expect("a wgpu adapter (lavapipe or llvmpipe, see README)");
        let mut pool = Pool::new(&gpu, "test", wgpu::BufferUsages::STORAGE, 4, 1 << 24);
        let gap = pool.alloc.alloc(10).expect("room");
        let a = pool.alloc.alloc(MIN_CAPACITY - 10).expect("room");
        let words: Vec<u32> = (0..MIN_CAPACITY as u32 - 10).collect();
        pool.write(&gpu, a, bytemuck::cast_slice(&words));
        pool.reserve(&gpu, 100).expect("grows");
        assert!(pool.alloc.capacity() > MIN_CAPACITY);
        pool.flush(&gpu);
        let got = read(&gpu, &pool);
        assert_eq!(&got[a as usize..MIN_CAPACITY as usize], &words[..]);
        pool.alloc.free_range(gap);
        pool.write(&gpu, a, bytemuck::cast_slice(&[7u32; 4]));
        let (moves, _) = pool.compact(&gpu, [a]);
        let to = moves.iter().find(|m| m.from == a).map_or(a, |m| m.to);
        pool.flush(&gpu);
        let got = read(&gpu, &pool);
        assert_eq!(&got[to as usize..to as usize + 4], &[7; 4]);
        assert_eq!(&got[to as usize + 4..to as usize + 20], &words[4..20]);
    }
}
