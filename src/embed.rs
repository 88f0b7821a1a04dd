//! Drawing a scene inside a caller's own wgpu renderer: their device and queue, their render
//! pass (their colour and depth targets), their camera.
//!
//! [`Renderer::new`] builds patchwork's pipelines for the caller's target formats on the
//! caller's device; each frame, [`Renderer::prepare`] runs the LOD frame loop
//! ([`crate::lod::FrameLoop`], Balázs, Guthe and Klein, "Fat Borders" (2004) §4.2: the
//! patches furthest off their wanted error re-tessellated within the time budget, only the
//! changed ones uploaded to the resident geometry) for the caller's camera, and
//! [`Renderer::draw`] records the surfaces and their fat borders into the caller's pass, where
//! they are depth-tested against whatever else the pass draws. The pipelines, shaders, upload
//! and encoding are the ones the offscreen renderer ([`crate::render::Renderer::render`]) uses.
//!
//! What it does not do: occlusion. The offscreen frame loop reads a patch-ID buffer back to
//! leave hidden patches at their level; here every patch inside the frustum counts as
//! visible, since patchwork never reads the caller's targets. Cut ranges of mesh patches are
//! drawn one call each rather than from indirect buffers (a device does not say whether its
//! adapter executes them). The camera must be right-handed (view space looks down −z, as
//! `glam`'s `*_rh` matrices) with a symmetric perspective or orthographic projection;
//! either depth range direction works, with [`EmbedOptions::depth_compare`] set to match.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use patchwork::embed::{Camera, EmbedOptions, Renderer};
//! use patchwork::embed::glam::{Mat4, Vec3};
//!
//! # let (device, queue): (wgpu::Device, wgpu::Queue) = unimplemented!();
//! # let (colour_view, depth_view): (wgpu::TextureView, wgpu::TextureView) = unimplemented!();
//! let scene = patchwork::prep::load(std::path::Path::new("models/teapot.bpt"))?;
//! let mut teapot = Renderer::new(
//!     &device,
//!     &queue,
//!     wgpu::TextureFormat::Rgba8UnormSrgb,
//!     wgpu::TextureFormat::Depth32Float,
//!     scene,
//!     EmbedOptions::default(),
//! )?;
//! let camera = Camera {
//!     view: Mat4::look_at_rh(Vec3::new(8.0, -8.0, 6.0), Vec3::ZERO, Vec3::Z),
//!     projection: Mat4::perspective_rh(0.8, 4.0 / 3.0, 0.1, 100.0),
//!     viewport: (800, 600),
//! };
//! // Every frame: the LOD step and uploads, then the draws inside your own pass.
//! let stats = teapot.prepare(&camera, 0.5)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! {
//!     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
//!         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
//!             view: &colour_view,
//!             depth_slice: None,
//!             resolve_target: None,
//!             ops: wgpu::Operations {
//!                 load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
//!                 store: wgpu::StoreOp::Store,
//!             },
//!         })],
//!         depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
//!             view: &depth_view,
//!             depth_ops: Some(wgpu::Operations {
//!                 load: wgpu::LoadOp::Clear(1.0),
//!                 store: wgpu::StoreOp::Store,
//!             }),
//!             stencil_ops: None,
//!         }),
//!         ..Default::default()
//!     });
//!     // ... your own draws ...
//!     teapot.draw(&mut pass);
//! }
//! queue.submit([encoder.finish()]);
//! println!("{} triangles", stats.update.triangles);
//! # Ok(())
//! # }
//! ```

use glam::{DVec3, DVec4, Mat4};
use thiserror::Error;

pub use glam;

use crate::frame::FrameState;
use crate::lod::{LodOptions, UpdateStats};
use crate::model::Scene;
use crate::render::{self, FatBorders, Geometry, RenderError, RenderOptions, Shading, Target};
use crate::view::{Projection, View};

pub use crate::render::{DEFAULT_SURFACE_COLOR, UploadStats};
pub use crate::view::DEFAULT_PIXEL_ERROR;

/// What can go wrong when drawing into a caller's renderer.
#[derive(Debug, Error)]
pub enum EmbedError {
    /// The device refused a pipeline or an upload (e.g. a colour format it cannot render to,
    /// or a buffer larger than it allows).
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("{format:?} is not a depth format (the pass's depth target must have a depth aspect)")]
    NotDepthFormat { format: wgpu::TextureFormat },
    #[error("MSAA sample count {0} is invalid: a power of two from 1 to 16")]
    BadSampleCount(u32),
    #[error("the viewport {width}x{height} is empty")]
    EmptyViewport { width: u32, height: u32 },
    #[error("pixel error {0} is invalid: a finite number above 0")]
    BadPixelError(f64),
    /// A camera that is not a right-handed view with a symmetric perspective or
    /// orthographic projection.
    #[error("unsupported camera: {0}")]
    Camera(String),
}

/// How the scene is drawn into the caller's pass.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct EmbedOptions {
    /// Sample count of the caller's pass (its colour and depth targets).
    pub sample_count: u32,
    /// The depth test: `LessEqual` for depth 0 at the near plane (`perspective_rh`),
    /// `GreaterEqual` for reversed depth.
    pub depth_compare: wgpu::CompareFunction,
    /// Lit (default) or flat surfaces (`Shading::Ids` colours each patch).
    pub shading: Shading,
    /// Colour of the surfaces, linear RGB 0–1.
    pub surface_color: [f32; 3],
    /// Fat-border template (six vertices per border vertex by default; `Off` shows the cracks).
    pub fat_borders: FatBorders,
    /// The frame loop: re-tessellation budget per frame, hysteresis, cached levels. Its pixel
    /// error is the one [`Renderer::prepare`] is given.
    pub lod: LodOptions,
}

impl Default for EmbedOptions {
    fn default() -> Self {
        EmbedOptions {
            sample_count: 1,
            depth_compare: wgpu::CompareFunction::LessEqual,
            shading: Shading::Lit,
            surface_color: DEFAULT_SURFACE_COLOR,
            fat_borders: FatBorders::Six,
            lod: LodOptions::default(),
        }
    }
}

/// The caller's camera: right-handed view and projection matrices (world → clip space, as
/// the caller's own shaders use them) and the viewport in pixels (what a pixel error is
/// measured in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub view: Mat4,
    pub projection: Mat4,
    /// Width and height, pixels.
    pub viewport: (u32, u32),
}

impl Camera {
    /// The camera as patchwork's [`View`] (eye, axis, field of view or height, near and far),
    /// for the frame loop's culling and pixel error → object error.
    fn to_view(self) -> Result<View, EmbedError> {
        let (width, height) = self.viewport;
        if width == 0 || height == 0 {
            return Err(EmbedError::EmptyViewport { width, height });
        }
        let (v, p) = (self.view.as_dmat4(), self.projection.as_dmat4());
        if !v.is_finite() || !p.is_finite() {
            return Err(EmbedError::Camera("a matrix is not finite".into()));
        }
        if v.determinant().abs() < 1e-12 || p.determinant().abs() < 1e-300 {
            return Err(EmbedError::Camera("a matrix is singular".into()));
        }
        let inverse = v.inverse();
        let eye = inverse.transform_point3(DVec3::ZERO);
        let forward = inverse.transform_vector3(DVec3::NEG_Z).normalize();
        let up = inverse.transform_vector3(DVec3::Y).normalize();
        let w_row = p.row(3);
        let near_zero = |x: f64| x.abs() <= 1e-9;
        let perspective = near_zero(w_row.x)
            && near_zero(w_row.y)
            && (w_row.z + 1.0).abs() <= 1e-9
            && near_zero(w_row.w);
        let orthographic = near_zero(w_row.x)
            && near_zero(w_row.y)
            && near_zero(w_row.z)
            && (w_row.w - 1.0).abs() <= 1e-9;
        let sy = p.y_axis.y;
        if !(perspective || orthographic) || sy <= 0.0 {
            return Err(EmbedError::Camera(
                "the projection is neither a right-handed perspective nor an orthographic one \
                 (view space must look down -z, y up)"
                    .into(),
            ));
        }
        let off_centre = if perspective {
            [p.z_axis.x, p.z_axis.y]
        } else {
            [p.w_axis.x, p.w_axis.y]
        };
        if off_centre.iter().any(|c| !near_zero(*c)) {
            return Err(EmbedError::Camera(
                "off-centre projections are not supported".into(),
            ));
        }
        // Near and far: the view-space distances of the axis points at depth 0 and 1,
        // whichever way the depth range runs; an infinite far plane stays very far.
        let unproject = p.inverse();
        let distance = |z: f64| {
            let q = unproject * DVec4::new(0.0, 0.0, z, 1.0);
            if q.w.abs() < 1e-300 {
                f64::INFINITY
            } else {
                -q.z / q.w
            }
        };
        let (a, b) = (distance(0.0), distance(1.0));
        let (near, far) = (a.min(b), a.max(b));
        if !(near > 0.0 || orthographic) || near.is_nan() {
            return Err(EmbedError::Camera(format!(
                "the near plane lies at {near} (it must lie in front of the eye)"
            )));
        }
        let far = if far.is_finite() { far } else { near * 1e9 };
        let projection = if perspective {
            Projection::Perspective
        } else {
            Projection::Orthographic { height: 2.0 / sy }
        };
        Ok(View {
            eye,
            target: eye + forward,
            up,
            fov_y: 2.0 * (1.0 / sy).atan(),
            width,
            height,
            near,
            far,
            projection,
        })
    }
}

/// What one [`Renderer::prepare`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// The frame loop's step: patches in the frustum, re-tessellated, left in the queue,
    /// triangles.
    pub update: UpdateStats,
    /// What was uploaded (only the patches whose tessellation changed).
    pub upload: UploadStats,
    /// Largest and 99th-percentile screen-space error of the patches in the frustum, pixels.
    pub max_error_px: f64,
    pub p99_error_px: f64,
}

/// A scene drawn into a caller's render passes (see the module documentation).
#[derive(Debug)]
pub struct Renderer {
    renderer: render::Renderer,
    scene: Scene,
    options: EmbedOptions,
    target: Target,
    /// The globals of the last prepared camera, and their bind group (group 0).
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
    /// The frame loop and the resident geometry: made by the first `prepare`.
    state: Option<FrameState>,
}

impl Renderer {
    /// Builds the pipelines for a pass with colour target `colour_format` and depth target
    /// `depth_format` (sample count [`EmbedOptions::sample_count`]) on the caller's device.
    /// Nothing is tessellated before the first [`Renderer::prepare`].
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        colour_format: wgpu::TextureFormat,
        depth_format: wgpu::TextureFormat,
        scene: Scene,
        options: EmbedOptions,
    ) -> Result<Renderer, EmbedError> {
        if !depth_format.has_depth_aspect() {
            return Err(EmbedError::NotDepthFormat {
                format: depth_format,
            });
        }
        let samples = options.sample_count;
        if !samples.is_power_of_two() || samples > 16 {
            return Err(EmbedError::BadSampleCount(samples));
        }
        let mut renderer = render::Renderer::with_gpu(render::Gpu::from_device(device, queue))?;
        let target = Target::External {
            color: colour_format,
            depth: depth_format,
            samples,
            compare: options.depth_compare,
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        renderer.pipelines(target);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("patchwork globals"),
            size: size_of::<render::Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = renderer.globals_bind_group(&uniform);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()).into());
        }
        Ok(Renderer {
            renderer,
            scene,
            options,
            target,
            uniform,
            bind,
            state: None,
        })
    }

    /// The scene drawn.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// One step of the LOD frame loop for `camera` at `pixel_error` (pixels; patchwork's
    /// default is [`DEFAULT_PIXEL_ERROR`]): the first call tessellates every patch, later ones
    /// re-tessellate the patches furthest off their wanted error within the budget; the
    /// changed patches are uploaded and the camera written for the next [`Renderer::draw`].
    /// Call it before beginning the pass (it writes buffers through the queue).
    pub fn prepare(&mut self, camera: &Camera, pixel_error: f64) -> Result<FrameStats, EmbedError> {
        if !(pixel_error.is_finite() && pixel_error > 0.0) {
            return Err(EmbedError::BadPixelError(pixel_error));
        }
        let view = camera.to_view()?;
        let state = match &mut self.state {
            Some(state) => state,
            None => self.state.insert(FrameState::new(
                &self.scene,
                &view,
                LodOptions {
                    pixel_error,
                    ..self.options.lod
                },
            )),
        };
        state.lod.options.pixel_error = pixel_error;
        let update = state.lod.update(&self.scene, &view);
        let device = &self.renderer.gpu().device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let upload = state.upload(&self.renderer)?;
        let mut globals = self.renderer.globals(
            &view,
            &RenderOptions {
                shading: self.options.shading,
                surface_color: self.options.surface_color,
                fat_borders: self.options.fat_borders,
                ..RenderOptions::default()
            },
        );
        // The caller's own clip space, so that our depths compare with theirs.
        globals.view_proj = (camera.projection * camera.view).to_cols_array_2d();
        self.renderer
            .gpu()
            .queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&globals));
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()).into());
        }
        let (max_error_px, p99_error_px) = state.lod.screen_errors();
        Ok(FrameStats {
            update,
            upload,
            max_error_px,
            p99_error_px,
        })
    }

    /// Records the scene's draws (surfaces, then fat borders) into `pass`, as last prepared:
    /// the pass's colour and depth targets must have the formats and sample count given to
    /// [`Renderer::new`]. Before the first [`Renderer::prepare`] it records nothing. Leaves
    /// the pass's pipeline, bind group 0 to 2 and vertex/index buffers changed.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        let Some(resident) = self.state.as_ref().and_then(FrameState::resident) else {
            return;
        };
        // Built in `new`: a `Renderer` never exists without them.
        let Some(pipes) = self.renderer.built_pipelines(self.target) else {
            return;
        };
        self.renderer.encode_into(
            pass,
            Geometry::Resident(resident),
            pipes,
            &self.bind,
            self.options.fat_borders,
            None,
        );
    }
}
