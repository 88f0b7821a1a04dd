//! One GPU buffer suballocated by an [`Allocator`]: growth by reallocation with a GPU-side
//! copy (`copy_buffer_to_buffer`, ranges keep their addresses) up to a largest size (the
//! device's largest buffer or binding; past it the caller opens another arena), compaction
//! into a new buffer (ranges move; the caller fixes what refers to them).

use super::alloc::{Allocator, Move};
use crate::render::{Gpu, RenderError};

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

    /// Writes `bytes` at unit `start`; returns the bytes written.
    pub(crate) fn write(&self, gpu: &Gpu, start: u64, bytes: &[u8]) -> u64 {
        if !bytes.is_empty() {
            gpu.queue
                .write_buffer(&self.buffer, start * self.unit, bytes);
        }
        bytes.len() as u64
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
