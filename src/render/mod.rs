//! Headless wgpu renderer: patch surfaces, then their fat borders, into an offscreen texture
//! of any size with a depth buffer, read back with rows padded to 256 bytes.
//!
//! Geometry comes two ways ([`Geometry`]): [`Renderer::upload`] builds one vertex/index buffer
//! of every given mesh ([`GpuMeshes`], one-shot users), and [`ResidentGeometry`] keeps every
//! patch's geometry in suballocated buffers between frames and uploads only the patches that
//! changed (the frame loop's default path). Either way a frame draws every patch's triangles
//! (mesh patches drawn as cuts of their hierarchies instead draw index ranges of buffers built
//! once per patch — one multi-draw-indirect per patch, Holst's static arcs — so a new cut
//! uploads only its ranges), then (unless fat borders are off) the chosen fat-border template
//! over every border vertex (no instancing: llvmpipe pays a fixed cost per instance). Shading:
//! `lit` (two-sided: CAD patches are not consistently oriented, so there is no back-face
//! culling), `flat` (one colour) and `ids` (a colour per patch). Optionally a second pass at one
//! sample writes the linear view-space depth (f32 bits in an `R32Uint` target: float targets
//! are not renderable on GL), for crack checks and `--depth-out`. Render targets and the
//! readback buffer are kept between frames of the same size.

mod draw;
pub mod edges;
pub mod fat_border;
pub mod gpu;
pub mod pick;
mod pipelines;
mod readback;
pub mod resident;
pub mod section;
pub mod shaders;
mod upload;

pub use fat_border::{BorderGeometry, BorderPoint, FatBorders};
pub use gpu::{Gpu, RenderError};
pub use resident::{ResidentGeometry, UploadStats};
pub use section::{SectionError, SectionPlane, Sections};
pub use upload::GpuMeshes;

use pipelines::Targets;
pub(crate) use pipelines::{EdgePipelines, Globals, Pipelines, Target};
use upload::{StaticKey, StaticPatch};

use std::collections::HashMap;
use std::ops::Range;
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

/// Which edges of the model are drawn over the surfaces, as ~1 px dark lines along the
/// border polylines of the frame (`model::edges` says what each border segment runs along).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Edges {
    /// None (the default).
    #[default]
    Off,
    /// Sharp edges only: free edges, creases, faces meeting at an angle; edges between faces
    /// that meet smoothly (G1 within 1°) are left out.
    Feature,
    /// Every edge between faces, smooth ones too (not the seams of closed surfaces nor the
    /// cuts between mesh patches).
    All,
}

impl Edges {
    /// Every choice, as the CLI spells it.
    pub(crate) const NAMES: &'static str = "off, feature or all";

    pub fn name(self) -> &'static str {
        match self {
            Edges::Off => "off",
            Edges::Feature => "feature",
            Edges::All => "all",
        }
    }

    /// The edge bits (`crate::model::edges::EDGE_ALL`, `EDGE_FEATURE`) a segment needs
    /// to be drawn in this mode (0: none is).
    pub fn bits(self) -> u8 {
        match self {
            Edges::Off => 0,
            Edges::Feature => crate::model::edges::EDGE_FEATURE,
            Edges::All => crate::model::edges::EDGE_ALL,
        }
    }

    /// The next mode of the viewer's `e` key: off → feature → all → off.
    pub fn next(self) -> Edges {
        match self {
            Edges::Off => Edges::Feature,
            Edges::Feature => Edges::All,
            Edges::All => Edges::Off,
        }
    }
}

impl std::str::FromStr for Edges {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" => Ok(Edges::Off),
            "feature" => Ok(Edges::Feature),
            "all" => Ok(Edges::All),
            _ => Err(format!("edges must be {}, not {s:?}", Edges::NAMES)),
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
    pub(crate) const NAMES: &'static str = "auto, list, strips, mts or repair";

    /// Whether `m` is drawn as triangle strips.
    pub(crate) fn strips_for(self, m: &PatchMesh) -> bool {
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

/// Points one draw of fat borders covers at most (the length of the index patterns).
pub(crate) const PATTERN_POINTS: usize = 32768;

/// Records the fat-border draws of `variant` over points `start..start + count` of the bound
/// points buffer: the variant's pattern, offset by a base vertex, at most [`PATTERN_POINTS`]
/// points per draw.
fn draw_points(
    pass: &mut wgpu::RenderPass<'_>,
    patterns: &[wgpu::Buffer; 3],
    variant: FatBorders,
    start: u32,
    count: u32,
) {
    let Some(v) = FatBorders::ALL_ON.iter().position(|&x| x == variant) else {
        return;
    };
    let codes = fat_border::pattern(variant).len() as u32;
    pass.set_index_buffer(patterns[v].slice(..), wgpu::IndexFormat::Uint32);
    let mut done = 0;
    while done < count {
        let n = (count - done).min(PATTERN_POINTS as u32);
        let base = (start + done) as usize * fat_border::SLOTS_PER_POINT;
        pass.draw_indexed(0..n * codes, base as i32, 0..1);
        done += n;
    }
}

/// Records the edge lines of points `start..start + count` of the bound points buffer
/// (`vs_edge`: segment s from point s to s + 1, two vertices each; the shader drops the
/// segments not drawn), with `instances` (placed points: their records).
fn draw_edges(pass: &mut wgpu::RenderPass<'_>, start: u32, count: u32, instances: Range<u32>) {
    pass.draw(2 * start..2 * (start + count), instances);
}

/// Default background (RGB, 0–255).
pub(crate) const DEFAULT_BACKGROUND: [u8; 3] = [255, 255, 255];
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
    /// Section planes: the model clipped and its cut capped ([`section`]).
    pub sections: Sections,
    /// Edges drawn over the surfaces in the colour image (not in depth or IDs).
    pub edges: Edges,
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
            sections: Sections::NONE,
            edges: Edges::Off,
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

/// What a render draws: meshes uploaded whole, or the resident geometry.
#[derive(Clone, Copy, Debug)]
pub enum Geometry<'a> {
    Uploaded(&'a GpuMeshes),
    Resident(&'a ResidentGeometry),
}

impl<'a> From<&'a GpuMeshes> for Geometry<'a> {
    fn from(g: &'a GpuMeshes) -> Self {
        Geometry::Uploaded(g)
    }
}

impl<'a> From<&'a ResidentGeometry> for Geometry<'a> {
    fn from(g: &'a ResidentGeometry) -> Self {
        Geometry::Resident(g)
    }
}

/// What the last [`Renderer::render`] cost beyond its geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall time blocked waiting for the GPU: `device.poll(wait)` until each pass's
    /// readback buffer is mapped (the passes' rendering and copies finish in it).
    pub gpu_wait: std::time::Duration,
    /// Bytes written per pass (the uniform block of the view and shading).
    pub uniform_bytes: u64,
}

/// Renderer: device, shader module, pipelines (built on first use per target).
#[derive(Debug)]
pub struct Renderer {
    gpu: Gpu,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    bind_layout: wgpu::BindGroupLayout,
    /// The fat-border pipeline's: globals, then the border points (a storage buffer).
    border_layout: wgpu::PipelineLayout,
    points_layout: wgpu::BindGroupLayout,
    /// Instanced parts: the placements' records (a storage buffer, group 2), and the layouts
    /// of the placed surfaces (globals, —, records) and fat borders (globals, points, records).
    records_layout: wgpu::BindGroupLayout,
    placed_layout: wgpu::PipelineLayout,
    placed_border_layout: wgpu::PipelineLayout,
    /// The fat-border index patterns ([`fat_border::pattern_indices`]) of the 6-, 4- and
    /// 2-vertex variants over [`PATTERN_POINTS`] points.
    patterns: [wgpu::Buffer; 3],
    pipelines: HashMap<Target, Pipelines>,
    /// The same with section planes (fragment shaders `fs_*_cut`), built on first use.
    cut_pipelines: HashMap<Target, Pipelines>,
    /// Edge pipelines per colour target, built when edges are first drawn.
    edge_pipes: HashMap<Target, EdgePipelines>,
    /// Render targets, kept between frames of the same size.
    targets: HashMap<Target, Targets>,
    /// Static buffers of mesh patches' hierarchies, built on first use.
    statics: Mutex<HashMap<StaticKey, Arc<StaticPatch>>>,
    /// Strips of uploaded meshes kept between uploads (per-view state: the scene holds none).
    strips: crate::strips::StripStore,
    /// Draw mesh-patch cuts from static per-patch buffers (default) instead of uploading
    /// their triangles with every new tessellation.
    pub static_arcs: bool,
    /// Resident geometry draws meshes that are instances ([`crate::tessellate::Instance`]:
    /// placements of a part's shared tessellation) as placements of the shared mesh, uploaded
    /// once (default), instead of with geometry of their own (for comparison).
    pub instances: bool,
    /// Triangle lists or strips for surfaces.
    pub primitives: Primitives,
    /// How strips are joined: primitive restart, except on wgpu's GL backend, where
    /// primitive restart draws wrong triangles (measured on llvmpipe-GL: 22 662 of 786 432
    /// teapot pixels differ from lists) and zero-area windows join them.
    pub strip_join: Join,
    /// Figures of the last render.
    last: RenderStats,
}

impl Renderer {
    /// Opens the default adapter and compiles the shaders.
    pub fn new() -> Result<Renderer, RenderError> {
        Self::with_gpu(Gpu::new()?)
    }

    pub(crate) fn with_gpu(gpu: Gpu) -> Result<Renderer, RenderError> {
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
        let storage_layout = |label| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                }],
            })
        };
        let points_layout = storage_layout("fat border points");
        let records_layout = storage_layout("placed records");
        let border_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("fat borders"),
            bind_group_layouts: &[Some(&bind_layout), Some(&points_layout)],
            immediate_size: 0,
        });
        let placed_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("placed surfaces"),
            bind_group_layouts: &[Some(&bind_layout), None, Some(&records_layout)],
            immediate_size: 0,
        });
        let placed_border_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("placed fat borders"),
            bind_group_layouts: &[
                Some(&bind_layout),
                Some(&points_layout),
                Some(&records_layout),
            ],
            immediate_size: 0,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        let patterns = FatBorders::ALL_ON.map(|v| {
            upload::buffer_init(
                device,
                "fat border pattern",
                bytemuck::cast_slice(&fat_border::pattern_indices(v, PATTERN_POINTS)),
                wgpu::BufferUsages::INDEX,
            )
        });
        let gpu_backend = gpu.info.backend;
        Ok(Renderer {
            gpu,
            module,
            layout,
            bind_layout,
            border_layout,
            points_layout,
            records_layout,
            placed_layout,
            placed_border_layout,
            patterns,
            pipelines: HashMap::new(),
            cut_pipelines: HashMap::new(),
            edge_pipes: HashMap::new(),
            targets: HashMap::new(),
            statics: Mutex::new(HashMap::new()),
            strips: crate::strips::StripStore::new(),
            static_arcs: true,
            instances: true,
            primitives: Primitives::default(),
            strip_join: if gpu_backend == wgpu::Backend::Gl {
                Join::Degenerate
            } else {
                Join::Restart
            },
            last: RenderStats::default(),
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The bind group of a buffer of border points ([`BorderPoint`]s) for the fat-border
    /// pipeline.
    pub(super) fn points_bind_group(&self, points: &wgpu::Buffer) -> wgpu::BindGroup {
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fat border points"),
                layout: &self.points_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: points.as_entire_binding(),
                }],
            })
    }

    /// The bind group of a buffer of placement records ([`resident::InstanceRecord`]).
    pub(super) fn records_bind_group(&self, records: &wgpu::Buffer) -> wgpu::BindGroup {
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("placed records"),
                layout: &self.records_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: records.as_entire_binding(),
                }],
            })
    }

    /// Bytes of border points one binding (one buffer) may hold: the device's largest
    /// storage binding, at most its largest buffer.
    pub(super) fn max_points_bytes(&self) -> u64 {
        let l = self.gpu.device.limits();
        l.max_storage_buffer_binding_size.min(l.max_buffer_size)
    }

    /// GPU wait and bytes written by the last [`Renderer::render`].
    pub fn last_render(&self) -> RenderStats {
        self.last
    }
}
