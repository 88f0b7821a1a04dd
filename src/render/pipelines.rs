//! Pipelines per render target (colour at a sample count, linear depth, patch IDs) and the
//! targets themselves, kept between frames of the same size.

use super::upload::*;
use super::*;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Globals {
    pub(crate) view_proj: [[f32; 4]; 4],
    pub(crate) eye: [f32; 4],
    pub(crate) forward: [f32; 4],
    pub(crate) light: [f32; 4],
    pub(crate) color: [f32; 4],
    pub(crate) mode: [u32; 4],
    /// Section planes ([`super::section::Sections::gpu`]); `mode[2]` of them in use.
    pub(crate) sections: [[f32; 4]; super::section::Sections::MAX],
}

#[derive(Debug)]
pub(crate) struct Pipelines {
    pub(super) surface: wgpu::RenderPipeline,
    pub(super) surface_strip: wgpu::RenderPipeline,
    pub(super) border: wgpu::RenderPipeline,
    /// Instanced parts: shared meshes drawn once per placement (the instance attribute is
    /// the index of its [`super::resident::InstanceRecord`] in the records, group 2).
    pub(super) surface_placed: wgpu::RenderPipeline,
    pub(super) surface_strip_placed: wgpu::RenderPipeline,
    pub(super) border_placed: wgpu::RenderPipeline,
}

/// The pipelines of the model's edges (`vs_edge`: line lists pulled from the border points)
/// for a colour target: the patches' own points and the placed ones.
#[derive(Debug)]
pub(crate) struct EdgePipelines {
    pub(super) own: wgpu::RenderPipeline,
    pub(super) placed: wgpu::RenderPipeline,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Target {
    Color {
        samples: u32,
    },
    Depth,
    Ids,
    /// A caller's pass ([`crate::embed`]): its colour and depth formats and sample count, and
    /// the depth test its projection needs (reversed depth tests `GreaterEqual`).
    External {
        color: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
        samples: u32,
        compare: wgpu::CompareFunction,
    },
}

pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Linear depth as f32 bits: `R32Uint` is renderable on every backend, `R32Float` not on GL.
pub(super) const LINEAR_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub(super) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Cleared value of the linear-depth target: "nothing drawn here" (no drawn depth is 0.0).
pub(super) const NO_DEPTH: u32 = 0;

/// The textures, uniform and readback buffer one pass renders with; reused while the image
/// size stays the same.
#[derive(Debug)]
pub(super) struct Targets {
    pub(super) size: (u32, u32),
    pub(super) resolved: wgpu::Texture,
    pub(super) resolved_view: wgpu::TextureView,
    pub(super) msaa_view: Option<wgpu::TextureView>,
    pub(super) depth_view: wgpu::TextureView,
    pub(super) uniform: wgpu::Buffer,
    pub(super) bind: wgpu::BindGroup,
    pub(super) readback: wgpu::Buffer,
    pub(super) row_bytes: u32,
    pub(super) padded_row_bytes: u32,
}

impl Targets {
    pub(super) fn new(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        target: Target,
        w: u32,
        h: u32,
    ) -> Self {
        let (format, samples) = match target {
            Target::Color { samples } => (COLOR_FORMAT, samples),
            Target::Depth | Target::Ids => (LINEAR_DEPTH_FORMAT, 1),
            Target::External { color, samples, .. } => (color, samples),
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

/// A target's formats: colour format, samples and the fragment entry point of its surfaces,
/// depth format and depth test.
struct Formats {
    color: wgpu::TextureFormat,
    samples: u32,
    fs: &'static str,
    depth: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
}

impl Formats {
    fn of(target: Target) -> Formats {
        let (color, samples, fs) = match target {
            Target::Color { samples } => (COLOR_FORMAT, samples, "fs_color"),
            Target::Depth => (LINEAR_DEPTH_FORMAT, 1, "fs_depth"),
            Target::Ids => (LINEAR_DEPTH_FORMAT, 1, "fs_id"),
            Target::External { color, samples, .. } => (color, samples, "fs_color"),
        };
        let (depth, compare) = match target {
            Target::External { depth, compare, .. } => (depth, compare),
            _ => (DEPTH_FORMAT, wgpu::CompareFunction::LessEqual),
        };
        Formats {
            color,
            samples,
            fs,
            depth,
            compare,
        }
    }
}

/// The instance attribute of placed draws: the index of the placement's record (group 2).
fn instance_records() -> wgpu::VertexBufferLayout<'static> {
    const ATTRS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![4 => Uint32];
    wgpu::VertexBufferLayout {
        array_stride: 4,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &ATTRS,
    }
}

impl Renderer {
    /// The pipelines of `target`, if built.
    pub(crate) fn built_pipelines(&self, target: Target) -> Option<&Pipelines> {
        self.pipelines.get(&target)
    }

    pub(crate) fn pipelines(&mut self, target: Target) -> &Pipelines {
        if !self.pipelines.contains_key(&target) {
            let p = self.build_pipelines(target, false);
            self.pipelines.insert(target, p);
        }
        &self.pipelines[&target]
    }

    /// The pipelines of `target` with section planes (`cut`: fragments clipped and capped,
    /// [`super::section`]) or without, built on first use.
    pub(super) fn pipelines_for(&mut self, target: Target, cut: bool) -> &Pipelines {
        if !cut {
            return self.pipelines(target);
        }
        if !self.cut_pipelines.contains_key(&target) {
            let p = self.build_pipelines(target, true);
            self.cut_pipelines.insert(target, p);
        }
        &self.cut_pipelines[&target]
    }

    /// The edge pipelines of colour target `target` (built on first use: most renders draw
    /// no edges). `None` for the depth and ID targets, which draw none.
    pub(crate) fn edge_pipelines(&mut self, target: Target) -> Option<&EdgePipelines> {
        if matches!(target, Target::Depth | Target::Ids) {
            return None;
        }
        if !self.edge_pipes.contains_key(&target) {
            let f = Formats::of(target);
            let edge = |label, layout, vs, buffers| {
                self.pipeline(
                    &f,
                    label,
                    (layout, vs, buffers),
                    wgpu::PrimitiveTopology::LineList,
                    // Tested against the surfaces, not written.
                    ("fs_edge", false),
                )
            };
            let p = EdgePipelines {
                own: edge("edges", &self.border_layout, "vs_edge", &[]),
                placed: edge(
                    "placed edges",
                    &self.placed_border_layout,
                    "vs_edge_placed",
                    &[Some(instance_records())],
                ),
            };
            self.edge_pipes.insert(target, p);
        }
        self.edge_pipes.get(&target)
    }

    /// One pipeline of the scene's shader for a target's formats `f`: its vertex stage
    /// (layout, entry point, buffers), topology and fragment stage (entry point, whether it
    /// writes depth); no culling (CAD patches are not consistently oriented).
    fn pipeline(
        &self,
        f: &Formats,
        label: &str,
        (layout, vs, buffers): (
            &wgpu::PipelineLayout,
            &str,
            &[Option<wgpu::VertexBufferLayout<'_>>],
        ),
        topology: wgpu::PrimitiveTopology,
        (fs, depth_write): (&str, bool),
    ) -> wgpu::RenderPipeline {
        self.gpu
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    strip_index_format: (topology == wgpu::PrimitiveTopology::TriangleStrip)
                        .then_some(wgpu::IndexFormat::Uint32),
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: f.depth,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(f.compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: f.samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: f.color,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    }

    pub(super) fn build_pipelines(&self, target: Target, cut: bool) -> Pipelines {
        let mut f = Formats::of(target);
        f.fs = match (f.fs, cut) {
            (fs, false) => fs,
            ("fs_depth", true) => "fs_depth_cut",
            ("fs_id", true) => "fs_id_cut",
            _ => "fs_color_cut",
        };
        let surface_attrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Uint32, 3 => Unorm8x4
        ];
        let surface_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &surface_attrs,
        })];
        let placed_vertex_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let placed_surface_buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &placed_vertex_attrs,
            }),
            Some(instance_records()),
        ];
        let placed_border_buffers = [Some(instance_records())];
        let make = |label: &str,
                    layout: &wgpu::PipelineLayout,
                    vs: &str,
                    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                    strip: bool| {
            let topology = match strip {
                true => wgpu::PrimitiveTopology::TriangleStrip,
                false => wgpu::PrimitiveTopology::TriangleList,
            };
            self.pipeline(&f, label, (layout, vs, buffers), topology, (f.fs, true))
        };
        Pipelines {
            surface: make(
                "surface",
                &self.layout,
                "vs_surface",
                &surface_buffers,
                false,
            ),
            surface_strip: make(
                "surface strips",
                &self.layout,
                "vs_surface",
                &surface_buffers,
                true,
            ),
            // Vertex pulling from the border points: no vertex buffers.
            border: make("fat border", &self.border_layout, "vs_border", &[], false),
            surface_placed: make(
                "placed surface",
                &self.placed_layout,
                "vs_surface_placed",
                &placed_surface_buffers,
                false,
            ),
            surface_strip_placed: make(
                "placed surface strips",
                &self.placed_layout,
                "vs_surface_placed",
                &placed_surface_buffers,
                true,
            ),
            border_placed: make(
                "placed fat border",
                &self.placed_border_layout,
                "vs_border_placed",
                &placed_border_buffers,
                false,
            ),
        }
    }
}
