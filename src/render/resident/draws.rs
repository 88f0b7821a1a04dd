//! The resident geometry's draw list: per drawn stream, in patch order, the ranges of the
//! drawn patches (adjacent ranges of one arena merged into one draw), the static patches'
//! ranges, their indirect arguments, and the encoding of a frame's draws.

use super::super::pipelines::Pipelines;
use super::super::upload::{DRAW_ARGS_BYTES, StaticPatch, encode_statics};
use super::*;

/// Per-frame draws: merged ranges per drawn stream and the static patches' ranges.
#[derive(Debug, Default)]
pub(super) struct DrawList {
    /// `(arena, [first unit, units])` per stream, in draw order (empty for the vertices).
    pub(super) ranges: [Vec<(usize, [u32; 2])>; STREAMS],
    /// First entry of each index stream's ranges in the indirect arguments (20-byte units).
    first_arg: [u32; STREAMS],
    statics: Vec<(Arc<StaticPatch>, u32, u32)>,
    static_ranges: Vec<[u32; 2]>,
    statics_first_arg: u32,
    /// Byte offset of the fat-border arguments of each variant (6, 4, 2).
    border_args: [u64; 3],
}

/// Runs of consecutive entries of one arena: `(arena, first entry, entries)`.
fn runs(ranges: &[(usize, [u32; 2])]) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
    let mut k = 0;
    std::iter::from_fn(move || {
        let &(arena, _) = ranges.get(k)?;
        let first = k;
        while ranges.get(k).is_some_and(|r| r.0 == arena) {
            k += 1;
        }
        Some((arena, first, k - first))
    })
}

impl DrawList {
    fn push(ranges: &mut Vec<(usize, [u32; 2])>, arena: usize, (start, len): (u64, u64)) {
        let (start, len) = (start as u32, len as u32);
        match ranges.last_mut() {
            Some((a, last)) if *a == arena && last[0] + last[1] == start => last[1] += len,
            _ => ranges.push((arena, [start, len])),
        }
    }

    /// The merged draws of the slots `drawn`, no arguments yet.
    pub(super) fn collect(
        renderer: &Renderer,
        slots: &Slots,
        drawn: &[usize],
        stats: &mut UploadStats,
    ) -> DrawList {
        let mut d = DrawList::default();
        for &i in drawn {
            let slot = &slots[i];
            for p in DRAWN_STREAMS {
                if let Some(r) = slot.ranges[p] {
                    DrawList::push(&mut d.ranges[p], slot.arena, r);
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
        // Fat-border draws index a pattern of at most PATTERN_POINTS points.
        let max = PATTERN_POINTS as u32;
        if d.ranges[POINTS].iter().any(|r| r.1[1] > max) {
            d.ranges[POINTS] = d.ranges[POINTS]
                .iter()
                .flat_map(|&(a, [start, len])| {
                    (0..len.div_ceil(max))
                        .map(move |k| (a, [start + k * max, (len - k * max).min(max)]))
                })
                .collect();
        }
        d
    }

    /// Draws of the drawn streams (without the static ranges).
    pub(super) fn split(&self) -> usize {
        DRAWN_STREAMS.iter().map(|&p| self.ranges[p].len()).sum()
    }

    pub(super) fn draw_count(&self) -> usize {
        self.split() + self.static_ranges.len()
    }

    /// Writes the indirect arguments (on devices that draw indirect) into `args`, made or
    /// grown as needed: surfaces and static ranges first, then the fat borders' for each
    /// variant.
    pub(super) fn write_args(
        &mut self,
        renderer: &Renderer,
        args: &mut Option<wgpu::Buffer>,
        stats: &mut UploadStats,
    ) {
        if !renderer.gpu.indirect {
            return;
        }
        let mut bytes: Vec<u8> = Vec::with_capacity(
            (self.draw_count() + 2 * self.ranges[POINTS].len()) * DRAW_ARGS_BYTES as usize,
        );
        let mut n = 0u32;
        let mut put = |ranges: &mut dyn Iterator<Item = [u32; 2]>, bytes: &mut Vec<u8>| {
            let first = n;
            for [first_index, index_count] in ranges {
                bytes.extend_from_slice(
                    wgpu::util::DrawIndexedIndirectArgs {
                        index_count,
                        instance_count: 1,
                        first_index,
                        base_vertex: 0,
                        first_instance: 0,
                    }
                    .as_bytes(),
                );
                n += 1;
            }
            first
        };
        for p in [LIST, STRIPS] {
            self.first_arg[p] = put(&mut self.ranges[p].iter().map(|r| r.1), &mut bytes);
        }
        self.statics_first_arg = put(&mut self.static_ranges.iter().copied(), &mut bytes);
        for (v, variant) in FatBorders::ALL_ON.iter().enumerate() {
            self.border_args[v] = bytes.len() as u64;
            let codes = fat_border::pattern(*variant).len() as u32;
            for &(_, [first, count]) in &self.ranges[POINTS] {
                bytes.extend_from_slice(
                    wgpu::util::DrawIndexedIndirectArgs {
                        index_count: count * codes,
                        instance_count: 1,
                        first_index: 0,
                        base_vertex: (first as usize * fat_border::SLOTS_PER_POINT) as i32,
                        first_instance: 0,
                    }
                    .as_bytes(),
                );
            }
        }
        if bytes.is_empty() {
            return;
        }
        let gpu = &renderer.gpu;
        if args.as_ref().is_none_or(|b| b.size() < bytes.len() as u64) {
            let size = (bytes.len() as u64 * 3 / 2).next_multiple_of(DRAW_ARGS_BYTES * 4);
            *args = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("resident draw arguments"),
                size,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        if let Some(b) = args {
            gpu.queue.write_buffer(b, 0, &bytes);
            stats.args_bytes = bytes.len() as u64;
        }
    }

    /// Records the draws of `variant` into `pass` (indirect from `args` when given), with
    /// the placed patches' after the others of each kind (surfaces, fat borders).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn encode(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        patterns: &[wgpu::Buffer; 3],
        arenas: &[Arena],
        args: Option<&wgpu::Buffer>,
        variant: FatBorders,
        placed: &PlacedDraws,
    ) {
        for (p, pipeline) in [(LIST, &pipes.surface), (STRIPS, &pipes.surface_strip)] {
            if self.ranges[p].is_empty() {
                continue;
            }
            pass.set_pipeline(pipeline);
            for (a, first, n) in runs(&self.ranges[p]) {
                let pools = &arenas[a].pools;
                pass.set_vertex_buffer(0, pools[VERTICES].buffer.slice(..));
                pass.set_index_buffer(pools[p].buffer.slice(..), wgpu::IndexFormat::Uint32);
                match args {
                    Some(b) => pass.multi_draw_indexed_indirect(
                        b,
                        (self.first_arg[p] as usize + first) as u64 * DRAW_ARGS_BYTES,
                        n as u32,
                    ),
                    None => {
                        for &(_, [start, count]) in &self.ranges[p][first..first + n] {
                            pass.draw_indexed(start..start + count, 0, 0..1);
                        }
                    }
                }
            }
        }
        encode_statics(
            pass,
            pipes,
            &self.statics,
            args.map(|a| (a, self.statics_first_arg)),
            &self.static_ranges,
        );
        placed.encode_surfaces(pass, pipes, arenas);
        let Some(v) = FatBorders::ALL_ON.iter().position(|&x| x == variant) else {
            return;
        };
        self.encode_borders(pass, pipes, patterns, arenas, args, variant, v);
        placed.encode_borders(pass, pipes, &patterns[v], arenas, variant);
    }

    /// Records the edge lines of the patches' own points (one draw per merged range of
    /// points).
    pub(super) fn encode_edges(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &EdgePipelines,
        arenas: &[Arena],
    ) {
        if self.ranges[POINTS].is_empty() {
            return;
        }
        pass.set_pipeline(&pipes.own);
        for (a, first, n) in runs(&self.ranges[POINTS]) {
            pass.set_bind_group(1, &arenas[a].points_bind.1, &[]);
            for &(_, [start, count]) in &self.ranges[POINTS][first..first + n] {
                draw_edges(pass, start, count, 0..1);
            }
        }
    }

    /// Records the fat-border draws of `variant` (pattern `v`) of the patches' own points.
    #[allow(clippy::too_many_arguments)]
    fn encode_borders(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &Pipelines,
        patterns: &[wgpu::Buffer; 3],
        arenas: &[Arena],
        args: Option<&wgpu::Buffer>,
        variant: FatBorders,
        v: usize,
    ) {
        if self.ranges[POINTS].is_empty() {
            return;
        }
        pass.set_pipeline(&pipes.border);
        pass.set_index_buffer(patterns[v].slice(..), wgpu::IndexFormat::Uint32);
        for (a, first, n) in runs(&self.ranges[POINTS]) {
            pass.set_bind_group(1, &arenas[a].points_bind.1, &[]);
            match args {
                Some(b) => pass.multi_draw_indexed_indirect(
                    b,
                    self.border_args[v] + first as u64 * DRAW_ARGS_BYTES,
                    n as u32,
                ),
                None => {
                    for &(_, [start, count]) in &self.ranges[POINTS][first..first + n] {
                        draw_points(pass, patterns, variant, start, count);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_split_where_the_arena_changes() {
        let r = [(0, [0, 3]), (0, [5, 1]), (1, [0, 2]), (0, [9, 1])];
        assert_eq!(
            runs(&r).collect::<Vec<_>>(),
            vec![(0, 0, 2), (1, 2, 1), (0, 3, 1)]
        );
        assert_eq!(runs(&[]).count(), 0);
    }

    #[test]
    fn adjacent_ranges_merge_only_within_an_arena() {
        let mut r = Vec::new();
        DrawList::push(&mut r, 0, (0, 4));
        DrawList::push(&mut r, 0, (4, 2));
        DrawList::push(&mut r, 1, (6, 1));
        DrawList::push(&mut r, 1, (9, 1));
        assert_eq!(r, vec![(0, [0, 6]), (1, [6, 1]), (1, [9, 1])]);
    }
}
