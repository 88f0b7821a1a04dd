//! patchwork inside someone else's renderer: this program opens its own wgpu device
//! (headless, no window), makes its own colour and depth targets and its own triangle
//! pipeline, and draws its triangle and patchwork's teapot in one render pass, depth-tested
//! against each other, then reads the image back and writes a PNG.
//!
//! `cargo run --release --example embed -- embed.png`
//!
//! The triangle is tilted in depth: on the left it lies in front of the whole teapot, on the
//! right behind it (`tests/embed.rs` checks both, and that each shows where only it is).

use std::error::Error;
use std::path::{Path, PathBuf};

use patchwork::embed::glam::{Mat4, Vec3, Vec4};
use patchwork::embed::{Camera, EmbedOptions, Renderer};

/// Image size, pixels.
pub const WIDTH: u32 = 640;
pub const HEIGHT: u32 = 480;
/// The caller's colour target (the bytes read back are the shaders' outputs × 255).
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The caller's triangle, RGBA 0–255, and the background.
pub const TRIANGLE_COLOUR: [u8; 4] = [204, 51, 26, 255];
pub const BACKGROUND: [u8; 4] = [255, 255, 255, 255];

/// Vertical field of view, radians, and the camera's distance from the teapot's centre in
/// bounding-sphere radii.
const FOV_Y: f32 = std::f32::consts::FRAC_PI_4;
const DISTANCE: f32 = 3.5;
/// The triangle lies in the plane depth = `TILT` × across (both in bounding-sphere radii,
/// from the centre, along the camera's forward and right axes).
const TILT: f32 = 2.5;

/// What to draw (the test draws each alone too).
#[derive(Clone, Copy, Debug)]
pub struct Layers {
    pub triangle: bool,
    pub teapot: bool,
}

/// Which image columns are sure: left of `front_max` the triangle's plane lies in front of
/// the teapot's whole bounding sphere, right of `behind_min` behind it.
#[derive(Clone, Copy, Debug)]
pub struct Columns {
    pub front_max: u32,
    pub behind_min: u32,
}

/// The columns where the triangle's plane is nearer / farther than the whole bounding
/// sphere: the plane's points at across = ∓1/TILT radii (depth ∓1 radius) project to fixed
/// columns, whatever their height.
pub fn columns() -> Columns {
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let half = (FOV_Y / 2.0).tan() * aspect;
    let column = |across: f32| {
        let depth = DISTANCE + TILT * across;
        let ndc = across / (depth * half);
        ((ndc + 1.0) / 2.0 * WIDTH as f32) as u32
    };
    Columns {
        front_max: column(-1.0 / TILT),
        behind_min: column(1.0 / TILT) + 1,
    }
}

/// The caller's triangle pipeline: clip-space positions in, one colour out.
const TRIANGLE_WGSL: &str = "
@vertex fn vs(@location(0) p: vec4<f32>) -> @builtin(position) vec4<f32> { return p; }
@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(0.8, 0.2, 0.1, 1.0); }
";

/// The caller's own device: any adapter, no surface.
pub fn device() -> Result<(wgpu::Device, wgpu::Queue), Box<dyn Error>> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    }))
    .map_err(|e| {
        format!(
            "no graphics adapter ({e}); without a GPU install Mesa's lavapipe \
             (apt-get install -y mesa-vulkan-drivers)"
        )
    })?;
    Ok(pollster::block_on(adapter.request_device(
        &wgpu::DeviceDescriptor {
            label: Some("embed example"),
            required_limits: adapter.limits(),
            ..Default::default()
        },
    ))?)
}

/// Draws `layers` into a fresh pair of targets and reads the colour back.
pub fn draw(layers: Layers) -> Result<image::RgbaImage, Box<dyn Error>> {
    let (device, queue) = device()?;

    // The scene and the caller's camera, framing the teapot's bounding sphere.
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::prep::load(&model)?;
    let centre = scene.bounds.center.as_vec3();
    let radius = scene.bounds.radius as f32;
    let up = scene.up.vector().as_vec3();
    let forward = Vec3::new(0.0, 1.0, -0.35).normalize();
    let right = forward.cross(up).normalize();
    let camera_up = right.cross(forward);
    let eye = centre - forward * DISTANCE * radius;
    let camera = Camera {
        view: Mat4::look_at_rh(eye, centre, up),
        projection: Mat4::perspective_rh(
            FOV_Y,
            WIDTH as f32 / HEIGHT as f32,
            0.1 * radius,
            10.0 * radius,
        ),
        viewport: (WIDTH, HEIGHT),
    };

    // The caller's targets.
    let texture = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: WIDTH,
                height: HEIGHT,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let colour = texture(
        "colour",
        COLOUR_FORMAT,
        attach | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = texture("depth", DEPTH_FORMAT, attach);

    // The caller's triangle: in the tilted plane, in radii about the teapot's centre.
    let corner = |across: f32, height: f32| {
        let p = centre + (right * across + camera_up * height + forward * TILT * across) * radius;
        camera.projection * camera.view * p.extend(1.0)
    };
    let corners: [Vec4; 3] = [corner(-1.2, -3.0), corner(3.0, -3.0), corner(0.0, 3.0)];
    let vertices = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("triangle"),
        size: std::mem::size_of_val(&corners) as u64,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    queue.write_buffer(&vertices, 0, bytemuck::cast_slice(&corners));
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("triangle"),
        source: wgpu::ShaderSource::Wgsl(TRIANGLE_WGSL.into()),
    });
    let triangle = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("triangle"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 16,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x4],
            })],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(COLOUR_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    });

    // patchwork: pipelines for these targets, one LOD step for this camera.
    let mut teapot = Renderer::new(
        &device,
        &queue,
        COLOUR_FORMAT,
        DEPTH_FORMAT,
        scene,
        EmbedOptions::default(),
    )?;
    let stats = teapot.prepare(&camera, patchwork::embed::DEFAULT_PIXEL_ERROR)?;
    if layers.teapot {
        println!(
            "teapot: {} patches in the frustum, {} triangles, worst error {:.2} px",
            stats.update.in_frustum, stats.update.triangles, stats.max_error_px
        );
    }

    // One pass: the caller's triangle, then patchwork's teapot.
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let colour_view = colour.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        let bg = BACKGROUND.map(|c| c as f64 / 255.0);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("one pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &colour_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg[0],
                        g: bg[1],
                        b: bg[2],
                        a: bg[3],
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        if layers.triangle {
            pass.set_pipeline(&triangle);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.draw(0..3, 0..1);
        }
        if layers.teapot {
            teapot.draw(&mut pass);
        }
    }
    read_back(&device, &queue, encoder, &colour)
}

/// Copies `texture` (RGBA8, `WIDTH`×`HEIGHT`) to a buffer, rows padded to 256 bytes, and
/// returns it without the padding.
fn read_back(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
) -> Result<image::RgbaImage, Box<dyn Error>> {
    let row = WIDTH * 4;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: padded as u64 * HEIGHT as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(HEIGHT),
            },
        },
        wgpu::Extent3d {
            width: WIDTH,
            height: HEIGHT,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |r| drop(sender.send(r)));
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receiver.recv()??;
    let mapped = buffer.get_mapped_range(..)?;
    let mut pixels = Vec::with_capacity((row * HEIGHT) as usize);
    for r in mapped.chunks(padded as usize) {
        pixels.extend_from_slice(&r[..row as usize]);
    }
    image::RgbaImage::from_raw(WIDTH, HEIGHT, pixels).ok_or_else(|| "short readback".into())
}

/// Draws the triangle and the teapot and writes the PNG to `out` (a temporary name beside
/// it, then renamed).
pub fn run(out: &Path) -> Result<image::RgbaImage, Box<dyn Error>> {
    let image = draw(Layers {
        triangle: true,
        teapot: true,
    })?;
    patchwork::io::png::write_rgba(out, &image)?;
    Ok(image)
}

#[allow(dead_code)] // (The test includes this file for `draw` and `run`.)
fn main() -> Result<(), Box<dyn Error>> {
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("embed.png"), PathBuf::from);
    run(&out)?;
    println!("wrote {}", out.display());
    Ok(())
}
