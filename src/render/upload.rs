//! Upload: patch meshes into vertex, index and fat-border point buffers; mesh-patch cuts drawn as
//! ranges of per-patch static buffers (Holst's static arcs) with their strips (the one place
//! the strip policy is decided: [`super::Primitives`]).

use super::*;

/// Surface vertex as uploaded.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SurfaceVertex {
    pub(super) position: [f32; 3],
    pub(super) normal: [f32; 3],
    pub(super) patch_id: u32,
    pub(super) color: [u8; 4],
}

/// The surface vertices of one patch.
pub(super) fn surface_vertices<'a>(
    positions: &'a [glam::Vec3],
    normals: &'a [glam::Vec3],
    patch_id: u32,
    color: [u8; 4],
) -> impl Iterator<Item = SurfaceVertex> + 'a {
    positions
        .iter()
        .zip(normals)
        .map(move |(p, n)| SurfaceVertex {
            position: (*p).into(),
            normal: (*n).into(),
            patch_id,
            color,
        })
}

/// A buffer with `bytes`; empty buffers cannot be bound, so an empty one gets a few zeros.
pub(super) fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let pad = [0u8; 80];
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: if bytes.is_empty() { &pad } else { bytes },
        usage,
    })
}

/// A patch colour as a vertex attribute (`Unorm8x4`): alpha 0 means "the default colour".
pub(crate) fn packed_color(c: Option<[f32; 3]>) -> [u8; 4] {
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    c.map_or([0; 4], |c| [q(c[0]), q(c[1]), q(c[2]), 255])
}

/// A patch-local index offset by the patch's first vertex `base` ([`crate::strips::RESTART`]
/// stays).
pub(super) fn offset_index(i: u32, base: u32) -> u32 {
    if i == crate::strips::RESTART {
        i
    } else {
        base + i
    }
}

/// Appends `local` indices offset by `base` ([`offset_index`]) as bytes.
pub(super) fn offset_indices(local: &[u32], base: u32, out: &mut Vec<u8>) {
    out.reserve(local.len() * 4);
    for &i in local {
        out.extend_from_slice(&offset_index(i, base).to_le_bytes());
    }
}

/// Records the draws of mesh patches drawn from their static buffers: per patch its ranges,
/// from `indirect` (the buffer and the first argument of `ranges`) or one `draw_indexed`
/// each.
pub(super) fn encode_statics(
    pass: &mut wgpu::RenderPass<'_>,
    pipes: &super::pipelines::Pipelines,
    statics: &[(Arc<StaticPatch>, u32, u32)],
    indirect: Option<(&wgpu::Buffer, u32)>,
    ranges: &[[u32; 2]],
) {
    for (patch, first, count) in statics {
        pass.set_pipeline(match patch.strips {
            Some(_) => &pipes.surface_strip,
            None => &pipes.surface,
        });
        pass.set_vertex_buffer(0, patch.vertices.slice(..));
        let indices = patch.strips.as_ref().map_or(&patch.indices, |s| &s.indices);
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        match indirect {
            Some((args, base)) => pass.multi_draw_indexed_indirect(
                args,
                (base + first) as u64 * DRAW_ARGS_BYTES,
                *count,
            ),
            None => {
                for &[start, len] in &ranges[*first as usize..(first + count) as usize] {
                    pass.draw_indexed(start..start + len, 0, 0..1);
                }
            }
        }
    }
}

/// Patch meshes uploaded to the GPU: one vertex/index buffer for all surfaces, the border
/// points of the fat borders in buffers of at most one storage binding each.
#[derive(Debug)]
pub struct GpuMeshes {
    pub(super) vertices: wgpu::Buffer,
    /// Triangle lists of the uploaded meshes drawn as lists.
    pub(super) indices: wgpu::Buffer,
    pub(super) index_count: u32,
    /// Strips of the uploaded meshes drawn as strips.
    pub(super) strip_indices: wgpu::Buffer,
    pub(super) strip_index_count: u32,
    /// Surface triangles uploaded in `indices` and `strip_indices`.
    pub(super) triangles: u32,
    /// Border points ([`super::BorderPoint`]) split between rings into buffers of at most
    /// [`Renderer::max_points_bytes`]: each buffer's bind group and point count.
    pub(super) border_points: Vec<(wgpu::BindGroup, u32)>,
    pub(super) border_vertex_count: u32,
    /// Mesh patches drawn from their static buffers: the patch, its first draw in
    /// `indirect` (and `ranges`) and its number of draws.
    pub(super) statics: Vec<(Arc<StaticPatch>, u32, u32)>,
    /// One `DrawIndexedIndirectArgs` per range (when the device draws indirect).
    pub(super) indirect: Option<wgpu::Buffer>,
    /// The ranges `[first index, index count]`, for devices without indirect draws.
    pub(super) ranges: Vec<[u32; 2]>,
    pub(super) static_triangles: u32,
    /// Bytes this upload wrote (buffers created with contents, static buffers built for it).
    pub(super) uploaded_bytes: u64,
}

/// Per-arc strips of a mesh patch's hierarchy: the index buffer and, per arc boundary, the
/// first index of the arc.
#[derive(Debug)]
pub(super) struct StaticStrips {
    pub(super) indices: wgpu::Buffer,
    pub(super) starts: Vec<u32>,
}

/// Every vertex and every triangle of one mesh patch's hierarchy, uploaded once; cuts are
/// drawn as index ranges of it.
#[derive(Debug)]
pub(super) struct StaticPatch {
    pub(super) vertices: wgpu::Buffer,
    pub(super) indices: wgpu::Buffer,
    /// Static strips per arc (built when the patch is first drawn with strips).
    pub(super) strips: Option<StaticStrips>,
    /// Keeps the patch alive, so its address (the cache key) is not reused.
    pub(super) patch: Arc<crate::model::mesh::MeshPatch>,
}

/// Size of one `DrawIndexedIndirectArgs`.
pub(super) const DRAW_ARGS_BYTES: u64 = 20;

/// Cache key of a static patch: the patch's address, its id, its colour and, when it holds
/// strips, how they are joined.
pub(super) type StaticKey = (usize, u32, [u8; 4], Option<Join>);

impl GpuMeshes {
    /// Bytes written to the GPU by the upload that made these buffers.
    pub fn uploaded_bytes(&self) -> u64 {
        self.uploaded_bytes
    }

    pub fn triangle_count(&self) -> u32 {
        self.triangles + self.static_triangles
    }

    /// Surface indices a draw sends (uploaded and static ranges; restarts and swaps included).
    pub fn index_count(&self) -> u64 {
        self.index_count as u64
            + self.strip_index_count as u64
            + self.ranges.iter().map(|r| r[1] as u64).sum::<u64>()
    }

    /// Index ranges drawn from static per-patch buffers (after merging adjacent arcs).
    pub fn static_range_count(&self) -> usize {
        self.ranges.len()
    }
    /// Border vertices (of the patch polylines, before expansion).
    pub fn border_vertex_count(&self) -> u32 {
        self.border_vertex_count
    }

    /// Records the draws of `variant` (and with `edges`, the edge lines) into `pass`.
    pub(super) fn encode(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipes: &super::pipelines::Pipelines,
        patterns: &[wgpu::Buffer; 3],
        variant: FatBorders,
        edges: Option<&EdgePipelines>,
    ) {
        for (pipeline, indices, count) in [
            (&pipes.surface, &self.indices, self.index_count),
            (
                &pipes.surface_strip,
                &self.strip_indices,
                self.strip_index_count,
            ),
        ] {
            if count > 0 {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, self.vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..count, 0, 0..1);
            }
        }
        encode_statics(
            pass,
            pipes,
            &self.statics,
            self.indirect.as_ref().map(|a| (a, 0)),
            &self.ranges,
        );
        if variant != FatBorders::Off {
            pass.set_pipeline(&pipes.border);
            for (bind, points) in &self.border_points {
                pass.set_bind_group(1, bind, &[]);
                draw_points(pass, patterns, variant, 0, *points);
            }
        }
        if let Some(e) = edges {
            pass.set_pipeline(&e.own);
            for (bind, points) in &self.border_points {
                pass.set_bind_group(1, bind, &[]);
                draw_edges(pass, 0, *points, 0..1);
            }
        }
    }
}

/// Splits `points` between rings into runs of at most `max` points (a ring longer than that
/// alone), so each run's rings have their neighbours in it.
pub(super) fn ring_runs(points: &[BorderPoint], max: usize) -> Vec<std::ops::Range<usize>> {
    let mut runs = Vec::new();
    let (mut start, mut ring) = (0, 0);
    for k in 0..=points.len() {
        let opens = k == points.len() || points[k].info & fat_border::INFO_FIRST != 0;
        if opens && k > ring {
            // Ring [ring, k) read: cut before it when the run would pass `max`.
            if k - start > max && ring > start {
                runs.push(start..ring);
                start = ring;
            }
            ring = k;
        }
    }
    if points.len() > start {
        runs.push(start..points.len());
    }
    runs
}

impl Renderer {
    /// Whether `m` is drawn as ranges of its patch's static buffers (a mesh-patch cut, with
    /// lists or static strips).
    pub(super) fn draws_static(&self, m: &PatchMesh) -> bool {
        m.arcs.as_ref().is_some_and(|cut| !cut.moved)
            && self.static_arcs
            && matches!(self.primitives, Primitives::List | Primitives::Strips)
    }

    /// Uploads patch meshes: surfaces and fat-border geometry ([`BorderGeometry`]).
    pub fn upload<'a>(&self, meshes: impl IntoIterator<Item = &'a PatchMesh>) -> GpuMeshes {
        // Instances (no vertices of their own) as world-space copies.
        let worlds: Vec<std::borrow::Cow<'a, PatchMesh>> =
            meshes.into_iter().map(PatchMesh::world).collect();
        let meshes: Vec<&PatchMesh> = worlds.iter().map(AsRef::as_ref).collect();
        let mut vertices = Vec::new();
        let (mut indices, mut strip_indices): (Vec<u32>, Vec<u32>) = Default::default();
        let (mut statics, mut ranges, mut static_triangles) = (Vec::new(), Vec::new(), 0u32);
        let primitives = self.primitives;
        self.strips.begin_upload();
        // The strips of every uploaded mesh drawn as strips, built (or extracted, or
        // repaired) in parallel.
        let uploaded_strips: Vec<Option<Arc<Vec<u32>>>> = meshes
            .par_iter()
            .map(|m| {
                (primitives.strips_for(m) && !self.draws_static(m))
                    .then(|| strips_of(&self.strips, m, primitives))
            })
            .collect();
        let mut triangles = 0u32;
        let mut uploaded_bytes = 0u64;
        for (i, m) in meshes.iter().copied().enumerate() {
            if self.draws_static(m) {
                let (tris, bytes) = self.static_draws(m, &mut statics, &mut ranges);
                static_triangles += tris;
                uploaded_bytes += bytes;
                continue;
            }
            let base = vertices.len() as u32;
            vertices.extend(surface_vertices(
                &m.positions,
                &m.normals,
                m.patch_id,
                packed_color(m.color),
            ));
            triangles += m.triangles.len() as u32;
            match uploaded_strips.get(i).and_then(Option::as_ref) {
                Some(s) => {
                    if !s.is_empty() && !strip_indices.is_empty() {
                        strip_indices.push(crate::strips::RESTART);
                    }
                    strip_indices.extend(s.iter().map(|&i| offset_index(i, base)));
                }
                None => indices.extend(m.triangles.iter().flatten().map(|i| base + i)),
            }
        }
        if self.strip_join == Join::Degenerate {
            strip_indices = crate::strips::join_degenerate(&strip_indices, &mut []);
        }
        let borders = BorderGeometry::of(meshes.iter().copied());
        let written = std::cell::Cell::new(uploaded_bytes);
        let init = |label, bytes: &[u8], usage| {
            written.set(written.get() + bytes.len() as u64);
            buffer_init(&self.gpu.device, label, bytes, usage)
        };
        let mut gpu = GpuMeshes {
            vertices: init(
                "vertices",
                bytemuck::cast_slice(&vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: init(
                "indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX,
            ),
            index_count: indices.len() as u32,
            strip_indices: init(
                "strip indices",
                bytemuck::cast_slice(&strip_indices),
                wgpu::BufferUsages::INDEX,
            ),
            strip_index_count: strip_indices.len() as u32,
            triangles,
            border_points: {
                let max = (self.max_points_bytes() / size_of::<BorderPoint>() as u64) as usize;
                ring_runs(&borders.points, max)
                    .into_iter()
                    .map(|run| {
                        let points = &borders.points[run];
                        let buf = init(
                            "fat border points",
                            bytemuck::cast_slice(points),
                            wgpu::BufferUsages::STORAGE,
                        );
                        (self.points_bind_group(&buf), points.len() as u32)
                    })
                    .collect()
            },
            border_vertex_count: meshes.iter().map(|m| m.border_vertex_count() as u32).sum(),
            indirect: (self.gpu.indirect && !ranges.is_empty()).then(|| {
                let args: Vec<u8> = ranges
                    .iter()
                    .flat_map(|&[first_index, index_count]| {
                        wgpu::util::DrawIndexedIndirectArgs {
                            index_count,
                            instance_count: 1,
                            first_index,
                            base_vertex: 0,
                            first_instance: 0,
                        }
                        .as_bytes()
                        .to_vec()
                    })
                    .collect();
                init("cut ranges", &args, wgpu::BufferUsages::INDIRECT)
            }),
            statics,
            ranges,
            static_triangles,
            uploaded_bytes: 0,
        };
        gpu.uploaded_bytes = written.get();
        gpu
    }

    /// Appends the draws of mesh-patch cut `m` (drawn from its static buffers, see
    /// [`Renderer::draws_static`]) to `statics` and `ranges`. Returns its triangles and the
    /// bytes of static buffers built for it now (first use).
    pub(super) fn static_draws(
        &self,
        m: &PatchMesh,
        statics: &mut Vec<(Arc<StaticPatch>, u32, u32)>,
        ranges: &mut Vec<[u32; 2]>,
    ) -> (u32, u64) {
        let Some(cut) = &m.arcs else {
            return (0, 0);
        };
        let first = ranges.len() as u32;
        let join = self.primitives.strips_for(m).then_some(self.strip_join);
        let (sp, bytes) = self.static_patch(m, &cut.patch, join);
        let arc_start = &cut.patch.hierarchy.arc_start;
        let mut triangles = 0;
        for &[start, count] in &cut.ranges {
            triangles += count;
            match &sp.strips {
                Some(st) => {
                    // Ranges cover whole arcs: map arc boundaries to strip indices.
                    let a = arc_start.partition_point(|&x| x < start);
                    let b = arc_start.partition_point(|&x| x < start + count);
                    ranges.push([st.starts[a], st.starts[b] - st.starts[a]]);
                }
                None => ranges.push([start * 3, count * 3]),
            }
        }
        statics.push((sp, first, ranges.len() as u32 - first));
        (triangles, bytes)
    }

    /// The static buffers of a mesh patch's hierarchy (built on first use). Entries whose
    /// patch nobody else holds any more are dropped.
    pub(super) fn static_patch(
        &self,
        m: &PatchMesh,
        patch: &Arc<crate::model::mesh::MeshPatch>,
        join: Option<Join>,
    ) -> (Arc<StaticPatch>, u64) {
        let color = packed_color(m.color);
        let key = (Arc::as_ptr(patch) as usize, m.patch_id, color, join);
        let mut cache = self.statics.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = cache.get(&key) {
            return (s.clone(), 0);
        }
        cache.retain(|_, s| Arc::strong_count(&s.patch) > 1);
        let vertices: Vec<SurfaceVertex> =
            surface_vertices(&patch.positions, &patch.normals, m.patch_id, color).collect();
        let indices: Vec<u32> = patch
            .hierarchy
            .triangles
            .iter()
            .flatten()
            .copied()
            .collect();
        let written = std::cell::Cell::new(0u64);
        let buffer = |label, bytes: &[u8], usage| {
            written.set(written.get() + bytes.len() as u64);
            buffer_init(&self.gpu.device, label, bytes, usage)
        };
        let s = Arc::new(StaticPatch {
            vertices: buffer(
                "patch vertices",
                bytemuck::cast_slice(&vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer(
                "patch hierarchy indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX,
            ),
            strips: join.map(|join| {
                let (st, mut starts) = crate::strips::arc_strips(
                    &patch.hierarchy,
                    &crate::strips::tunnel::TunnelOptions::default(),
                );
                let indices = match join {
                    Join::Restart => st.indices,
                    Join::Degenerate => crate::strips::join_degenerate(&st.indices, &mut starts),
                };
                StaticStrips {
                    indices: buffer(
                        "patch arc strips",
                        bytemuck::cast_slice(&indices),
                        wgpu::BufferUsages::INDEX,
                    ),
                    starts,
                }
            }),
            patch: patch.clone(),
        });
        cache.insert(key, s.clone());
        (s, written.get())
    }
}

/// The strips of an uploaded mesh, indices into its own vertices: for a mesh-patch cut with
/// `auto` / `mts` / `repair`, its hierarchy's multiresolution strips at the cut's level or its
/// repaired cut strips; otherwise tunneling strips of its triangles (kept in `store` while
/// the tessellation is drawn).
pub(super) fn strips_of(
    store: &crate::strips::StripStore,
    m: &PatchMesh,
    primitives: Primitives,
) -> Arc<Vec<u32>> {
    match (&m.arcs, primitives) {
        (Some(cut), Primitives::Auto | Primitives::Mts | Primitives::Repair) => {
            let mut out = Vec::new();
            store.cut(
                &cut.patch,
                cut.applied,
                primitives != Primitives::Repair,
                &mut out,
            );
            Arc::new(out)
        }
        _ => store.tessellation(m.patch_id, &m.triangles),
    }
}
