//! Upload: patch meshes into vertex, index and fat-border buffers; mesh-patch cuts drawn as
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

/// Patch meshes uploaded to the GPU: one vertex/index buffer for all surfaces, one vertex
/// buffer of displaced fat-border vertices with an index buffer per variant.
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
    pub(super) border_vertices: wgpu::Buffer,
    /// Index buffers for the 6-, 4- and 2-vertex variants, with their index counts.
    pub(super) border_indices: [(wgpu::Buffer, u32); 3],
    pub(super) border_vertex_count: u32,
    /// Mesh patches drawn from their static buffers: the patch, its first draw in
    /// `indirect` (and `ranges`) and its number of draws.
    pub(super) statics: Vec<(Arc<StaticPatch>, u32, u32)>,
    /// One `DrawIndexedIndirectArgs` per range (when the device draws indirect).
    pub(super) indirect: Option<wgpu::Buffer>,
    /// The ranges `[first index, index count]`, for devices without indirect draws.
    pub(super) ranges: Vec<[u32; 2]>,
    pub(super) static_triangles: u32,
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

    pub(super) fn border_indices(&self, variant: FatBorders) -> Option<&(wgpu::Buffer, u32)> {
        match variant {
            FatBorders::Off => None,
            FatBorders::Six => Some(&self.border_indices[0]),
            FatBorders::Four => Some(&self.border_indices[1]),
            FatBorders::Two => Some(&self.border_indices[2]),
        }
    }
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
        let meshes: Vec<&PatchMesh> = meshes.into_iter().collect();
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
        for (i, m) in meshes.iter().copied().enumerate() {
            if let Some(cut) = m.arcs.as_ref().filter(|_| self.draws_static(m)) {
                let first = ranges.len() as u32;
                let join = primitives.strips_for(m).then_some(self.strip_join);
                let sp = self.static_patch(m, &cut.patch, join);
                let arc_start = &cut.patch.hierarchy.arc_start;
                for &[start, count] in &cut.ranges {
                    static_triangles += count;
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
                    strip_indices.extend(s.iter().map(|&i| {
                        if i == crate::strips::RESTART {
                            i
                        } else {
                            base + i
                        }
                    }));
                }
                None => indices.extend(m.triangles.iter().flatten().map(|i| base + i)),
            }
        }
        if self.strip_join == Join::Degenerate {
            strip_indices = crate::strips::join_degenerate(&strip_indices, &mut []);
        }
        let borders = BorderGeometry::of(meshes.iter().copied());
        let init = |label, bytes: &[u8], usage| buffer_init(&self.gpu.device, label, bytes, usage);
        GpuMeshes {
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
            border_vertices: init(
                "fat border vertices",
                bytemuck::cast_slice(&borders.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            border_indices: borders.indices.each_ref().map(|idx| {
                let buf = init(
                    "fat border indices",
                    bytemuck::cast_slice(idx),
                    wgpu::BufferUsages::INDEX,
                );
                (buf, idx.len() as u32)
            }),
            border_vertex_count: (borders.vertices.len() / fat_border::SLOTS) as u32,
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
        }
    }

    /// The static buffers of a mesh patch's hierarchy (built on first use). Entries whose
    /// patch nobody else holds any more are dropped.
    pub(super) fn static_patch(
        &self,
        m: &PatchMesh,
        patch: &Arc<crate::model::mesh::MeshPatch>,
        join: Option<Join>,
    ) -> Arc<StaticPatch> {
        let color = packed_color(m.color);
        let key = (Arc::as_ptr(patch) as usize, m.patch_id, color, join);
        let mut cache = self.statics.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = cache.get(&key) {
            return s.clone();
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
        let buffer =
            |label, bytes: &[u8], usage| buffer_init(&self.gpu.device, label, bytes, usage);
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
        s
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
