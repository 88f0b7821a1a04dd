//! Headless wgpu renderer: patch surfaces, then their fat borders, into an offscreen texture
//! of any size with a depth buffer, read back with rows padded to 256 bytes.
//!
//! One frame = one indexed draw of every patch's triangles (mesh patches drawn as cuts of
//! their hierarchies instead draw index ranges of buffers built once per patch — one
//! multi-draw-indirect per patch, Holst's static arcs — so a new cut uploads only its ranges), then (unless fat borders are off)
//! one indexed draw of the chosen fat-border template over every border vertex (no instancing:
//! llvmpipe pays a fixed cost per instance). Shading:
//! `lit` (two-sided: CAD patches are not consistently oriented, so there is no back-face
//! culling), `flat` (one colour) and `ids` (a colour per patch). Optionally a second pass at one
//! sample writes the linear view-space depth (f32 bits in an `R32Uint` target: float targets
//! are not renderable on GL), for crack checks and `--depth-out`. Render targets and the
//! readback buffer are kept between frames of the same size.

pub mod fat_border;
pub mod gpu;
pub mod shaders;

pub use fat_border::{BorderGeometry, BorderVertex, FatBorders};
pub use gpu::{Gpu, RenderError};

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::DVec3;
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use crate::strips::Join;
use crate::tessellate::PatchMesh;
use crate::view::View;

/// How surfaces are coloured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Shading {
    #[default]
    Lit,
    Flat,
    Ids,
}

impl std::str::FromStr for Shading {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "lit" => Ok(Shading::Lit),
            "flat" => Ok(Shading::Flat),
            "ids" => Ok(Shading::Ids),
            _ => Err(format!("shading must be lit, flat or ids, not {s:?}")),
        }
    }
}

/// How surfaces are sent to the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Primitives {
    /// What measured fastest on our models (`auto`, the default): triangle lists for
    /// tessellated patches, multiresolution strips for mesh-patch cuts (as [`Primitives::Mts`]).
    #[default]
    Auto,
    /// Indexed triangle lists.
    List,
    /// Static triangle strips (`strips`): tunneling strips per tessellated patch, static
    /// strips per arc of a mesh patch's hierarchy (Holst §5.2).
    Strips,
    /// Multiresolution strips (`mts`, Belmonte et al.): a mesh patch's strips extracted at
    /// its cut's level whenever the cut moves (uploaded with the cut); tessellated patches as
    /// `strips`.
    Mts,
    /// Strips repaired by tunneling (`repair`, Stewart §4.2): a mesh patch's strips follow
    /// its cut one edge collapse / vertex split at a time (uploaded with the cut);
    /// tessellated patches as `strips`.
    Repair,
}

impl Primitives {
    /// Every choice, as the CLI spells it.
    pub const NAMES: &'static str = "auto, list, strips, mts or repair";

    /// Whether `m` is drawn as triangle strips.
    pub fn strips_for(self, m: &PatchMesh) -> bool {
        match self {
            Primitives::List => false,
            Primitives::Auto => m.arcs.is_some(),
            Primitives::Strips | Primitives::Mts | Primitives::Repair => true,
        }
    }
}

impl std::str::FromStr for Primitives {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Primitives::Auto),
            "list" => Ok(Primitives::List),
            "strips" => Ok(Primitives::Strips),
            "mts" => Ok(Primitives::Mts),
            "repair" => Ok(Primitives::Repair),
            _ => Err(format!(
                "primitives must be {}, not {s:?}",
                Primitives::NAMES
            )),
        }
    }
}

/// Default background (RGB, 0–255).
pub const DEFAULT_BACKGROUND: [u8; 3] = [255, 255, 255];
/// Default surface colour for `lit` shading (RGB, 0–1).
pub const DEFAULT_SURFACE_COLOR: [f32; 3] = [0.74, 0.77, 0.83];

/// What to draw and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    pub shading: Shading,
    pub background: [u8; 3],
    /// Colour of `lit` and `flat` surfaces, RGB 0–1.
    pub surface_color: [f32; 3],
    pub fat_borders: FatBorders,
    /// 1 or 4.
    pub msaa: u32,
    /// Also render linear view-space depth (one sample per pixel).
    pub depth: bool,
    /// Also render the patch ID buffer (one sample per pixel; fat borders count for their
    /// patch): which patches are visible.
    pub ids: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            shading: Shading::Lit,
            background: DEFAULT_BACKGROUND,
            surface_color: DEFAULT_SURFACE_COLOR,
            fat_borders: FatBorders::Six,
            msaa: 1,
            depth: false,
            ids: false,
        }
    }
}

/// A rendered image read back to the CPU.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, top row first, no padding.
    pub color: Vec<u8>,
    /// Linear view-space depth per pixel (distance along the viewing axis), `f32::INFINITY`
    /// where nothing was drawn. Present when [`RenderOptions::depth`] was set.
    pub depth: Option<Vec<f32>>,
    /// Patch ID + 1 per pixel, 0 where nothing was drawn. Present when [`RenderOptions::ids`]
    /// was set.
    pub ids: Option<Vec<u32>>,
}

impl Frame {
    /// Which patch IDs show in at least one pixel, as a set indexed by ID (`len` IDs).
    pub fn visible_ids(&self, len: usize) -> Option<Vec<bool>> {
        let ids = self.ids.as_ref()?;
        let mut seen = vec![false; len];
        for &i in ids {
            if let Some(s) = (i as usize).checked_sub(1).and_then(|k| seen.get_mut(k)) {
                *s = true;
            }
        }
        Some(seen)
    }

    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [
            self.color[i],
            self.color[i + 1],
            self.color[i + 2],
            self.color[i + 3],
        ]
    }

    /// The colour image as an `image` buffer.
    pub fn to_rgba_image(&self) -> image::RgbaImage {
        image::RgbaImage::from_raw(self.width, self.height, self.color.clone())
            .unwrap_or_else(|| image::RgbaImage::new(self.width, self.height))
    }
}

/// Surface vertex as uploaded.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SurfaceVertex {
    position: [f32; 3],
    normal: [f32; 3],
    patch_id: u32,
    color: [u8; 4],
}

/// The surface vertices of one patch.
fn surface_vertices<'a>(
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
fn buffer_init(
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
    vertices: wgpu::Buffer,
    /// Triangle lists of the uploaded meshes drawn as lists.
    indices: wgpu::Buffer,
    index_count: u32,
    /// Strips of the uploaded meshes drawn as strips.
    strip_indices: wgpu::Buffer,
    strip_index_count: u32,
    /// Surface triangles uploaded in `indices` and `strip_indices`.
    triangles: u32,
    border_vertices: wgpu::Buffer,
    /// Index buffers for the 6-, 4- and 2-vertex variants, with their index counts.
    border_indices: [(wgpu::Buffer, u32); 3],
    border_vertex_count: u32,
    /// Mesh patches drawn from their static buffers: the patch, its first draw in
    /// `indirect` (and `ranges`) and its number of draws.
    statics: Vec<(Arc<StaticPatch>, u32, u32)>,
    /// One `DrawIndexedIndirectArgs` per range (when the device draws indirect).
    indirect: Option<wgpu::Buffer>,
    /// The ranges `[first index, index count]`, for devices without indirect draws.
    ranges: Vec<[u32; 2]>,
    static_triangles: u32,
}

/// Per-arc strips of a mesh patch's hierarchy: the index buffer and, per arc boundary, the
/// first index of the arc.
#[derive(Debug)]
struct StaticStrips {
    indices: wgpu::Buffer,
    starts: Vec<u32>,
}

/// Every vertex and every triangle of one mesh patch's hierarchy, uploaded once; cuts are
/// drawn as index ranges of it.
#[derive(Debug)]
struct StaticPatch {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Static strips per arc (built when the patch is first drawn with strips).
    strips: Option<StaticStrips>,
    /// Keeps the patch alive, so its address (the cache key) is not reused.
    patch: Arc<crate::model::mesh::MeshPatch>,
}

/// Size of one `DrawIndexedIndirectArgs`.
const DRAW_ARGS_BYTES: u64 = 20;

/// Cache key of a static patch: the patch's address, its id, its colour and, when it holds
/// strips, how they are joined.
type StaticKey = (usize, u32, [u8; 4], Option<Join>);

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

    fn border_indices(&self, variant: FatBorders) -> Option<&(wgpu::Buffer, u32)> {
        match variant {
            FatBorders::Off => None,
            FatBorders::Six => Some(&self.border_indices[0]),
            FatBorders::Four => Some(&self.border_indices[1]),
            FatBorders::Two => Some(&self.border_indices[2]),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    forward: [f32; 4],
    light: [f32; 4],
    color: [f32; 4],
    mode: [u32; 4],
}

#[derive(Debug)]
struct Pipelines {
    surface: wgpu::RenderPipeline,
    surface_strip: wgpu::RenderPipeline,
    border: wgpu::RenderPipeline,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Target {
    Color { samples: u32 },
    Depth,
    Ids,
}

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Linear depth as f32 bits: `R32Uint` is renderable on every backend, `R32Float` not on GL.
const LINEAR_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Cleared value of the linear-depth target: "nothing drawn here" (no drawn depth is 0.0).
const NO_DEPTH: u32 = 0;

/// Renderer: device, shader module, pipelines (built on first use per target).
#[derive(Debug)]
pub struct Renderer {
    gpu: Gpu,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    bind_layout: wgpu::BindGroupLayout,
    pipelines: HashMap<Target, Pipelines>,
    /// Render targets, kept between frames of the same size.
    targets: HashMap<Target, Targets>,
    /// Static buffers of mesh patches' hierarchies, built on first use.
    statics: Mutex<HashMap<StaticKey, Arc<StaticPatch>>>,
    /// Strips of uploaded meshes kept between uploads (per-view state: the scene holds none).
    strips: crate::strips::StripStore,
    /// Draw mesh-patch cuts from static per-patch buffers (default) instead of uploading
    /// their triangles with every new tessellation.
    pub static_arcs: bool,
    /// Triangle lists or strips for surfaces.
    pub primitives: Primitives,
    /// How strips are joined: primitive restart, except on wgpu's GL backend, where
    /// primitive restart draws wrong triangles (measured on llvmpipe-GL: 22 662 of 786 432
    /// teapot pixels differ from lists) and zero-area windows join them.
    pub strip_join: Join,
}

/// The textures, uniform and readback buffer one pass renders with; reused while the image
/// size stays the same.
#[derive(Debug)]
struct Targets {
    size: (u32, u32),
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    msaa_view: Option<wgpu::TextureView>,
    depth_view: wgpu::TextureView,
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
    readback: wgpu::Buffer,
    row_bytes: u32,
    padded_row_bytes: u32,
}

impl Targets {
    fn new(gpu: &Gpu, layout: &wgpu::BindGroupLayout, target: Target, w: u32, h: u32) -> Self {
        let (format, samples) = match target {
            Target::Color { samples } => (COLOR_FORMAT, samples),
            Target::Depth | Target::Ids => (LINEAR_DEPTH_FORMAT, 1),
        };
        let device = &gpu.device;
        let size = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let texture = |label, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let resolved = texture("target", format, 1, attach | wgpu::TextureUsages::COPY_SRC);
        let msaa = (samples > 1).then(|| texture("msaa target", format, samples, attach));
        let depth = texture("depth", DEPTH_FORMAT, samples, attach);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        // Both formats have 4 bytes per pixel.
        let row_bytes = w * 4;
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row_bytes = row_bytes.div_ceil(align) * align;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded_row_bytes as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Targets {
            size: (w, h),
            resolved_view: resolved.create_view(&Default::default()),
            resolved,
            msaa_view: msaa.as_ref().map(|t| t.create_view(&Default::default())),
            depth_view: depth.create_view(&Default::default()),
            uniform,
            bind,
            readback,
            row_bytes,
            padded_row_bytes,
        }
    }
}

impl Renderer {
    /// Opens the default adapter and compiles the shaders.
    pub fn new() -> Result<Renderer, RenderError> {
        Self::with_gpu(Gpu::new()?)
    }

    pub fn with_gpu(gpu: Gpu) -> Result<Renderer, RenderError> {
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shaders::SCENE.into()),
        });
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        let gpu_backend = gpu.info.backend;
        Ok(Renderer {
            gpu,
            module,
            layout,
            bind_layout,
            pipelines: HashMap::new(),
            targets: HashMap::new(),
            statics: Mutex::new(HashMap::new()),
            strips: crate::strips::StripStore::new(),
            static_arcs: true,
            primitives: Primitives::default(),
            strip_join: if gpu_backend == wgpu::Backend::Gl {
                Join::Degenerate
            } else {
                Join::Restart
            },
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Whether `m` is drawn as ranges of its patch's static buffers (a mesh-patch cut, with
    /// lists or static strips).
    fn draws_static(&self, m: &PatchMesh) -> bool {
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
    fn static_patch(
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

    fn pipelines(&mut self, target: Target) -> &Pipelines {
        if !self.pipelines.contains_key(&target) {
            let p = self.build_pipelines(target);
            self.pipelines.insert(target, p);
        }
        &self.pipelines[&target]
    }

    fn build_pipelines(&self, target: Target) -> Pipelines {
        let (format, samples, fs) = match target {
            Target::Color { samples } => (COLOR_FORMAT, samples, "fs_color"),
            Target::Depth => (LINEAR_DEPTH_FORMAT, 1, "fs_depth"),
            Target::Ids => (LINEAR_DEPTH_FORMAT, 1, "fs_id"),
        };
        let surface_attrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Uint32, 3 => Unorm8x4
        ];
        let border_attrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3,
            4 => Float32, 5 => Uint32, 6 => Uint32, 7 => Unorm8x4
        ];
        let surface_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &surface_attrs,
        })];
        let border_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<BorderVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &border_attrs,
        })];
        let make = |label: &str,
                    vs: &str,
                    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                    strip: bool| {
            self.gpu
                .device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&self.layout),
                    vertex: wgpu::VertexState {
                        module: &self.module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: if strip {
                            wgpu::PrimitiveTopology::TriangleStrip
                        } else {
                            wgpu::PrimitiveTopology::TriangleList
                        },
                        strip_index_format: strip.then_some(wgpu::IndexFormat::Uint32),
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::LessEqual),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: wgpu::MultisampleState {
                        count: samples,
                        ..Default::default()
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &self.module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        };
        Pipelines {
            surface: make("surface", "vs_surface", &surface_buffers, false),
            surface_strip: make("surface strips", "vs_surface", &surface_buffers, true),
            border: make("fat border", "vs_border", &border_buffers, false),
        }
    }

    /// Renders `meshes` for `view` and reads the image (and depth, if asked) back.
    pub fn render(
        &mut self,
        meshes: &GpuMeshes,
        view: &View,
        opts: &RenderOptions,
    ) -> Result<Frame, RenderError> {
        let (w, h) = (view.width, view.height);
        let max = self.gpu.max_texture_side();
        if w == 0 || h == 0 {
            return Err(RenderError::BadSize {
                width: w,
                height: h,
                reason: "zero-sized".into(),
            });
        }
        if w > max || h > max {
            return Err(RenderError::BadSize {
                width: w,
                height: h,
                reason: format!("this adapter's largest texture side is {max}"),
            });
        }
        if opts.msaa != 1 && opts.msaa != 4 {
            return Err(RenderError::BadSampleCount(opts.msaa));
        }
        let scope = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let oom = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let globals = self.globals(view, opts);
        let bg = opts.background.map(|c| c as f64 / 255.0);
        let clear = wgpu::Color {
            r: bg[0],
            g: bg[1],
            b: bg[2],
            a: 1.0,
        };
        let color = self.draw(
            meshes,
            &globals,
            opts,
            Target::Color { samples: opts.msaa },
            w,
            h,
            clear,
        )?;
        let depth = if opts.depth {
            let no = wgpu::Color {
                r: NO_DEPTH as f64,
                g: 0.0,
                b: 0.0,
                a: 0.0,
            };
            let raw = self.draw(meshes, &globals, opts, Target::Depth, w, h, no)?;
            let bits: Vec<u32> = bytemuck::pod_collect_to_vec::<u8, u32>(&raw);
            Some(
                bits.into_iter()
                    .map(|b| {
                        if b == NO_DEPTH {
                            f32::INFINITY
                        } else {
                            f32::from_bits(b)
                        }
                    })
                    .collect(),
            )
        } else {
            None
        };
        let ids = if opts.ids {
            let none = wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a: 0.0,
            };
            let raw = self.draw(meshes, &globals, opts, Target::Ids, w, h, none)?;
            Some(bytemuck::pod_collect_to_vec::<u8, u32>(&raw))
        } else {
            None
        };
        if let Some(e) = pollster::block_on(oom.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        Ok(Frame {
            width: w,
            height: h,
            color,
            depth,
            ids,
        })
    }

    fn globals(&self, view: &View, opts: &RenderOptions) -> Globals {
        let forward = (view.target - view.eye)
            .try_normalize()
            .unwrap_or(DVec3::NEG_Z);
        let right = forward.cross(view.up).try_normalize().unwrap_or(DVec3::X);
        let up = right.cross(forward);
        // A key light from above-left of the viewer.
        let light = (-forward * 0.8 + up * 0.55 - right * 0.35).normalize();
        let f4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        let c = opts.surface_color;
        Globals {
            view_proj: view.view_proj_f32().to_cols_array_2d(),
            eye: f4(view.eye),
            forward: f4(forward),
            light: f4(light),
            color: [c[0], c[1], c[2], 1.0],
            mode: [
                match opts.shading {
                    Shading::Lit => 0,
                    Shading::Flat => 1,
                    Shading::Ids => 2,
                },
                0,
                0,
                0,
            ],
        }
    }

    /// One pass into a fresh target; returns the unpadded bytes of the (resolved) colour target.
    #[allow(clippy::too_many_arguments)]
    fn draw(
        &mut self,
        meshes: &GpuMeshes,
        globals: &Globals,
        opts: &RenderOptions,
        target: Target,
        w: u32,
        h: u32,
        clear: wgpu::Color,
    ) -> Result<Vec<u8>, RenderError> {
        self.pipelines(target);
        if self.targets.get(&target).is_none_or(|t| t.size != (w, h)) {
            let t = Targets::new(&self.gpu, &self.bind_layout, target, w, h);
            self.targets.insert(target, t);
        }
        let device = &self.gpu.device;
        let pipes = &self.pipelines[&target];
        let targets = &self.targets[&target];
        self.gpu
            .queue
            .write_buffer(&targets.uniform, 0, bytemuck::bytes_of(globals));
        let (resolved_view, msaa_view, depth_view, bind) = (
            &targets.resolved_view,
            &targets.msaa_view,
            &targets.depth_view,
            &targets.bind,
        );
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let (view, resolve_target) = match msaa_view {
                Some(v) => (v, Some(resolved_view)),
                None => (resolved_view, None),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, bind, &[]);
            for (pipeline, indices, count) in [
                (&pipes.surface, &meshes.indices, meshes.index_count),
                (
                    &pipes.surface_strip,
                    &meshes.strip_indices,
                    meshes.strip_index_count,
                ),
            ] {
                if count > 0 {
                    pass.set_pipeline(pipeline);
                    pass.set_vertex_buffer(0, meshes.vertices.slice(..));
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..count, 0, 0..1);
                }
            }
            if !meshes.statics.is_empty() {
                for (patch, first, count) in &meshes.statics {
                    pass.set_pipeline(match patch.strips {
                        Some(_) => &pipes.surface_strip,
                        None => &pipes.surface,
                    });
                    pass.set_vertex_buffer(0, patch.vertices.slice(..));
                    let indices = patch.strips.as_ref().map_or(&patch.indices, |s| &s.indices);
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    match &meshes.indirect {
                        Some(args) => pass.multi_draw_indexed_indirect(
                            args,
                            *first as u64 * DRAW_ARGS_BYTES,
                            *count,
                        ),
                        None => {
                            let ranges = &meshes.ranges[*first as usize..(first + count) as usize];
                            for &[start, len] in ranges {
                                pass.draw_indexed(start..start + len, 0, 0..1);
                            }
                        }
                    }
                }
            }
            if let Some((indices, count)) = meshes.border_indices(opts.fat_borders)
                && *count > 0
            {
                pass.set_pipeline(&pipes.border);
                pass.set_vertex_buffer(0, meshes.border_vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..*count, 0, 0..1);
            }
        }
        read_texture(&self.gpu, encoder, targets)
    }
}

/// Copies the resolved target into the readback buffer (rows padded to
/// `COPY_BYTES_PER_ROW_ALIGNMENT`, 256), maps it and strips the padding.
fn read_texture(
    gpu: &Gpu,
    mut encoder: wgpu::CommandEncoder,
    targets: &Targets,
) -> Result<Vec<u8>, RenderError> {
    let (w, h) = targets.size;
    let (unpadded, padded) = (targets.row_bytes, targets.padded_row_bytes);
    let (texture, buffer) = (&targets.resolved, &targets.readback);
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut out = Vec::with_capacity((unpadded * h) as usize);
    let copied = buffer.get_mapped_range(..).map(|data| {
        for row in data.chunks_exact(padded as usize) {
            out.extend_from_slice(&row[..unpadded as usize]);
        }
    });
    // Unmapped whatever happened: the buffer is reused by the next frame.
    buffer.unmap();
    copied.map_err(|e| RenderError::Readback(e.to_string()))?;
    Ok(out)
}

/// The strips of an uploaded mesh, indices into its own vertices: for a mesh-patch cut with
/// `auto` / `mts` / `repair`, its hierarchy's multiresolution strips at the cut's level or its
/// repaired cut strips; otherwise tunneling strips of its triangles (kept in `store` while
/// the tessellation is drawn).
fn strips_of(
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
