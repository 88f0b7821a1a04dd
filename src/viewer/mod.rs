//! Interactive viewer (`patchwork view FILE`): a winit window driven by the LOD frame loop.
//!
//! Every frame: [`crate::frame::step`] (its [`crate::lod::FrameLoop::update`]) for the camera (re-tessellation within the budget), the
//! scene drawn by the same [`Renderer`] the headless commands use (offscreen, read back with
//! the patch-ID buffer that feeds visibility to the next frame), optional overlays (wireframe,
//! drawn on the CPU with a depth test), then the image copied onto the window's surface by a
//! one-triangle pass (`shaders/present.wgsl`; GL surfaces accept no copies). On a software
//! rasterizer the copy is a small part of the frame; images, checks and the window share one
//! drawing path.
//!
//! Mouse: left drag orbits, right drag (or shift + left) pans, wheel zooms, a left click picks
//! (what the pixel shows and the distance from the click before, `render::pick`). Keys: arrows orbit,
//! PageUp/PageDown zoom, `f` fit to view, `b` fat borders off/6/4/2, `e` edges of the model
//! off/feature/all (`render::Edges`), `w` wireframe, `i` patch-ID
//! colours, `h` error heat map (screen error per patch: blue finer than asked, green on target,
//! red coarser), `5` orthographic / perspective projection (as f3d), `+`/`-` pixel error ×2 /
//! ÷2, `p` screenshot, space plays/pauses the
//! implosion loop (`--implode`: parts or patches fly together, stay, fly apart, ... — see
//! [`crate::anim`]), `q`/Esc quit. The title shows fps, triangles, queue length and the
//! largest screen error.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use thiserror::Error;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};

use winit::window::{Window, WindowId};

use crate::frame::{FrameState, StepOptions};
use crate::lod::LodOptions;
use crate::model::Scene;
use crate::render::gpu::Gpu;
use crate::render::{Edges, FatBorders, Frame, RenderError, RenderOptions, Renderer, Shading};
use crate::tessellate::PatchMesh;
use crate::view::{Framing, Projection, View};

mod orbit;
mod overlay;
mod panel;
mod pick;
mod present;
mod script;
mod section;
mod shown;

pub use orbit::Orbit;
pub use overlay::draw_wireframe;
pub use panel::{EXPLODE_DISTANCE, PANEL_WIDTH, Panel, part_colour, tree};
use panel::{Exploded, PanelUi};
use present::Present;
pub use script::{Scripted, script_input, script_key};

/// Why the viewer could not run.
#[derive(Debug, Error)]
pub enum ViewerError {
    #[error(
        "cannot open a window: {}. The viewer needs a display (X11): set DISPLAY, or run it \
         under a virtual one, e.g. `xvfb-run -a patchwork view FILE` (apt-get install xvfb)",
        os_reason(.0)
    )]
    NoDisplay(String),
    #[error("cannot draw into the window: {0}")]
    Surface(String),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Write(#[from] crate::io::png::WriteError),
    #[error(transparent)]
    Check(#[from] crate::check::crack::CheckError),
}

/// A windowing error without winit's `os error at FILE:LINE: ` prefix (a path inside the
/// cargo registry means nothing to a user) or trailing full stops.
fn os_reason(e: &str) -> &str {
    let reason = e
        .strip_prefix("os error at ")
        .and_then(|rest| rest.split_once(": ").map(|(_, why)| why))
        .unwrap_or(e);
    reason.trim_end_matches('.')
}

/// The mouse and keys of the window (printed by `patchwork view --help` and, with `?`, by the
/// window on stderr).
pub const CONTROLS: &str = "\
Mouse: left drag orbits, right drag (or shift + left drag) pans, the wheel zooms,
       a left click prints what it shows (part, face, surface, point; distance from the last).
Keys:  arrows orbit, PageUp / PageDown zoom, f fit to view, 5 orthographic / perspective,
       b fat borders off / 6 / 4 / 2, e edges off / feature / all, w wireframe,
       i patch-ID colours,
       h screen-error heat map (blue finer than asked, green on target, red coarser),
       + / - pixel error x2 / /2, p screenshot, space play / pause (--implode),
       c section plane on / off (through the centre, facing you; or the --section planes),
       ctrl + drag or [ / ] move it along its normal,
       t part panel (visibility, isolate, colour by part, explode slider),
       ? these lines, q or Esc quit.
Title: frames per second, triangles, re-tessellation queue, largest screen error.";

/// Settings of a viewer session.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    pub title: String,
    pub size: (u32, u32),
    pub fov_y: f64,
    /// The starting camera's direction and margin (also what `f` returns to).
    pub framing: crate::view::Framing,
    /// Starting eye (instead of the framing's) and target (default: the model's centre).
    pub eye: Option<DVec3>,
    pub target: Option<DVec3>,
    /// The orbit's up axis (default: the model's).
    pub up: Option<DVec3>,
    pub lod: LodOptions,
    /// Scripted run: draw this many frames, then exit.
    pub frames: Option<usize>,
    /// Written at exit (scripted) or with `p`.
    pub screenshot: Option<PathBuf>,
    /// Keys pressed by script, one per frame from the first (names as in [`script_input`]).
    pub keys: Vec<String>,
    /// Play an implosion/explosion loop (space pauses and resumes).
    pub implode: Option<ViewerAnimation>,
    /// Triangle lists or strips.
    pub primitives: crate::render::Primitives,
    /// Section planes (`c` turns them off and on).
    pub sections: crate::render::Sections,
    /// The edges drawn at the start (`e` cycles off / feature / all).
    pub edges: Edges,
    /// Where the viewer's messages go (the adapter chosen, screenshots written, a screenshot
    /// that failed): the library prints nothing; the binary passes a function that does.
    pub notify: fn(&str),
    /// Where a click's pick goes (what the pixel shows, the distance from the click before;
    /// `render::pick`): data, where `notify`'s messages are diagnostics.
    pub picked: fn(&str),
}

/// The viewer's animation: the parts (or patches) fly together over `frames` frames, stay
/// assembled a while, fly apart again, and so on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewerAnimation {
    pub by: crate::anim::GroupBy,
    pub distance: f64,
    /// Frames per implosion (and per explosion).
    pub frames: usize,
}

/// A playing (or paused) animation.
struct Playing {
    explosion: crate::anim::Explosion,
    frames: usize,
    /// Frames since the start of the loop.
    phase: usize,
    paused: bool,
}

impl Playing {
    /// Explosion amount now: imploding, a quarter of the time assembled, exploding, a
    /// quarter apart.
    fn amount(&self) -> f64 {
        let n = self.frames.max(2);
        let hold = n / 4;
        let k = self.phase % (2 * (n + hold));
        if k < n {
            crate::anim::amount(k, n, false)
        } else if k < n + hold {
            0.0
        } else if k < 2 * n + hold {
            crate::anim::amount(k - n - hold, n, true)
        } else {
            1.0
        }
    }
}

/// What a session did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewerReport {
    pub frames: usize,
    /// Frames that reached the window.
    pub presented: usize,
    pub mean_frame_ms: f64,
}

pub use crate::frame::heat_color;

/// Opens the window and runs until it is closed (or the scripted frames are drawn).
pub fn run(scene: Scene, options: ViewerOptions) -> Result<ViewerReport, ViewerError> {
    run_upgrading(scene, options, None)
}

/// As [`run`], and when `upgrade` delivers a scene (the same patches, e.g. with the MT
/// hierarchies a background thread built: `prep::PendingHierarchies::build`), draws that one
/// from then on: a new [`FrameState`] over it, camera and pixel error kept. Both scenes stay
/// immutable; the swap happens between frames.
pub fn run_upgrading(
    mut scene: Scene,
    options: ViewerOptions,
    upgrade: Option<std::sync::mpsc::Receiver<Scene>>,
) -> Result<ViewerReport, ViewerError> {
    let event_loop = EventLoop::new().map_err(|e| ViewerError::NoDisplay(e.to_string()))?;
    let playing = options.implode.map(|a| {
        let explosion = crate::anim::Explosion::new(&scene, a.by, a.distance);
        // Frame (and clip) the whole flight.
        scene.bounds = explosion.bounds(&scene);
        Playing {
            explosion,
            frames: a.frames,
            phase: 0,
            paused: false,
        }
    });
    let up = options.up.unwrap_or_else(|| scene.up.vector());
    let target = options.target.unwrap_or(scene.bounds.center);
    let orbit = match options.eye {
        Some(eye) => Orbit::looking(eye, target, up),
        None => {
            let fit = Orbit::fit(
                &scene,
                options.up,
                &options.framing,
                options.fov_y,
                options.size,
            );
            Orbit { target, ..fit }
        }
    };
    let ortho = options.framing.ortho;
    let edges = options.edges;
    let panel = Panel::new(&scene);
    let exploded = Exploded::new(&scene);
    let cut = options.sections;
    let mut app = App {
        full: scene.clone(),
        scene,
        panel,
        exploded,
        cut,
        ctrl: false,
        upgrade,
        playing,
        options,
        orbit,
        state: None,
        error: None,
        fat_borders: FatBorders::Six,
        edges,
        shading: Shading::Lit,
        ortho,
        wireframe: false,
        sections_on: true,
        heat: false,
        drag: None,
        pressed_at: None,
        last_pick: None,
        cursor: PhysicalPosition::new(0.0, 0.0),
        shift: false,
        dirty: true,
        frames: 0,
        presented: 0,
        frame_time: Duration::ZERO,
        last_title: Instant::now(),
        shots: 0,
        quitting: false,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::NoDisplay(e.to_string()))?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if app.frames > 0 && app.presented == 0 {
        return Err(ViewerError::Surface(format!(
            "{} frames drawn, none could be presented to the window",
            app.frames
        )));
    }
    Ok(ViewerReport {
        frames: app.frames,
        presented: app.presented,
        mean_frame_ms: app.frame_time.as_secs_f64() * 1e3 / app.frames.max(1) as f64,
    })
}

struct App {
    /// The scene drawn: the loaded one less the parts the panel hides ([`Panel::shown`]).
    scene: Scene,
    /// The loaded scene (the upgraded one once it arrived).
    full: Scene,
    panel: Panel,
    /// The explode slider's offsets over the drawn scene.
    exploded: Exploded,
    /// The section planes (`--section`, or the one `c` makes; ctrl + drag moves the first).
    cut: crate::render::Sections,
    ctrl: bool,
    /// Where a better scene may come from (see [`run_upgrading`]).
    upgrade: Option<std::sync::mpsc::Receiver<Scene>>,
    /// The implosion loop, with `--implode`.
    playing: Option<Playing>,
    options: ViewerOptions,
    orbit: Orbit,
    state: Option<State>,
    error: Option<ViewerError>,
    fat_borders: FatBorders,
    /// Edges of the model drawn (`e` cycles).
    edges: Edges,
    shading: Shading,
    /// Orthographic projection (`5` toggles).
    ortho: bool,
    wireframe: bool,
    /// The section planes of the options are drawn (`c` toggles).
    sections_on: bool,
    heat: bool,
    drag: Option<MouseButton>,
    /// Where the left button went down: released there, it is a click (a pick).
    pressed_at: Option<PhysicalPosition<f64>>,
    /// The point of the last pick, for the distance to the next.
    last_pick: Option<DVec3>,
    cursor: PhysicalPosition<f64>,
    shift: bool,
    /// Something changed since the last frame (camera, settings, queue not empty).
    dirty: bool,
    frames: usize,
    presented: usize,
    frame_time: Duration,
    last_title: Instant,
    shots: usize,
    /// A scripted `q` / Escape: draw this frame, write the screenshot, then close.
    quitting: bool,
}

struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
    present: Present,
    frame: FrameState,
    last: Option<Frame>,
    ui: PanelUi,
}

impl App {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<State, ViewerError> {
        let (w, h) = self.options.size;
        let attrs = Window::default_attributes()
            .with_title(self.options.title.clone())
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| ViewerError::NoDisplay(e.to_string()))?,
        );
        let desc = wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
            event_loop.owned_display_handle(),
        ));
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Surface(e.to_string()))?;
        let adapter = Gpu::adapter(&instance, Some(&surface))?;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Rgba8Unorm
                        | wgpu::TextureFormat::Rgba8UnormSrgb
                        | wgpu::TextureFormat::Bgra8Unorm
                        | wgpu::TextureFormat::Bgra8UnormSrgb
                )
            })
            .ok_or_else(|| {
                ViewerError::Surface(format!("no 8-bit RGBA format among {:?}", caps.formats))
            })?;
        let gpu = Gpu::open(&adapter)?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| {
                ViewerError::Surface("the adapter cannot present to this window".into())
            })?;
        config.format = format;
        config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        config.present_mode = wgpu::PresentMode::AutoVsync;
        config.view_formats.clear();
        surface.configure(&gpu.device, &config);
        let present = Present::new(&gpu.device, format);
        let ui = PanelUi::new(&window, &gpu, format);
        let mut renderer = Renderer::with_gpu(gpu)?;
        renderer.primitives = self.options.primitives;
        (self.options.notify)(&format!("adapter: {}", renderer.gpu().describe()));
        let view = self.view(config.width, config.height);
        let frame = FrameState::new(&self.scene, &view, self.options.lod);
        Ok(State {
            window,
            surface,
            config,
            renderer,
            present,
            frame,
            last: None,
            ui,
        })
    }

    fn view(&self, w: u32, h: u32) -> View {
        self.orbit.view(
            &self.scene,
            self.options.fov_y,
            (w.max(1), h.max(1)),
            self.ortho,
        )
    }

    /// One frame; returns whether the queue still has work.
    fn frame(&mut self) -> Result<bool, ViewerError> {
        let Some((w, h)) = self
            .state
            .as_ref()
            .map(|s| (s.config.width, s.config.height))
        else {
            return Ok(false);
        };
        let start = Instant::now();
        self.panel_pass();
        let view = self.view(w, h);
        let Some(state) = self.state.as_mut() else {
            return Ok(false);
        };
        // Animated or exploded by the panel's slider: patches drawn moved, tessellated for
        // where they are drawn.
        let offsets = match self.playing.as_ref() {
            Some(p) => Some(p.explosion.at(p.amount())),
            None => self.exploded.offsets(self.panel.explode),
        };
        let opts = StepOptions {
            draw: RenderOptions {
                shading: self.shading,
                fat_borders: self.fat_borders,
                msaa: 1,
                depth: self.wireframe,
                sections: if self.sections_on {
                    self.cut
                } else {
                    crate::render::Sections::NONE
                },
                edges: self.edges,
                ..RenderOptions::default()
            },
            offsets: offsets.as_deref(),
            heat_map: self.heat,
            check: false,
        };
        let r = crate::frame::step(
            &mut state.renderer,
            &self.scene,
            &mut state.frame,
            &view,
            &opts,
        )?;
        let (stats, mut frame) = (r.stats, r.frame);
        if self.wireframe {
            draw_wireframe(&mut frame, &view, state.frame.lod.meshes());
        }
        match state.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                let target = t.texture.create_view(&Default::default());
                state.present.draw(state.renderer.gpu(), &frame, &target);
                if self.panel.open {
                    let size = (state.config.width, state.config.height);
                    state.ui.paint(state.renderer.gpu(), &target, size);
                }
                state.window.pre_present_notify();
                state.renderer.gpu().queue.present(t);
                self.presented += 1;
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                state
                    .surface
                    .configure(&state.renderer.gpu().device, &state.config);
            }
            _ => {}
        }
        let dt = start.elapsed();
        self.frames += 1;
        self.frame_time += dt;
        if self.last_title.elapsed() > Duration::from_millis(250) || self.options.frames.is_some() {
            let (max, _) = state.frame.lod.screen_errors();
            state.window.set_title(&format!(
                "{} — {:.1} fps, {} triangles, queue {}, max error {:.2} px, pixel error {}, fat borders {}, edges {}",
                self.options.title,
                1.0 / dt.as_secs_f64().max(1e-6),
                stats.triangles,
                stats.queue_left,
                max,
                state.frame.lod.options.pixel_error,
                self.fat_borders.name(),
                self.edges.name()
            ));
            self.last_title = Instant::now();
        }
        state.last = Some(frame);
        let playing = match self.playing.as_mut() {
            Some(p) if !p.paused => {
                p.phase += 1;
                true
            }
            _ => false,
        };
        Ok(stats.queue_left > 0 || stats.retessellated > 0 || playing)
    }

    fn screenshot(&mut self) -> Result<(), ViewerError> {
        let Some(frame) = self.state.as_ref().and_then(|s| s.last.as_ref()) else {
            return Ok(());
        };
        let path = match &self.options.screenshot {
            Some(p) if self.options.frames.is_some() => p.clone(),
            _ => {
                self.shots += 1;
                PathBuf::from(format!("patchwork-screenshot-{}.png", self.shots))
            }
        };
        crate::io::png::write_rgba(&path, &frame.to_rgba_image())?;
        (self.options.notify)(&format!("wrote {}", path.display()));
        Ok(())
    }

    fn key(&mut self, key: Key, event_loop: &ActiveEventLoop) {
        let step = 10f64.to_radians();
        match key.as_ref() {
            Key::Named(NamedKey::ArrowLeft) => self.orbit.rotate(-step, 0.0),
            Key::Named(NamedKey::ArrowRight) => self.orbit.rotate(step, 0.0),
            Key::Named(NamedKey::ArrowUp) => self.orbit.rotate(0.0, step),
            Key::Named(NamedKey::ArrowDown) => self.orbit.rotate(0.0, -step),
            Key::Named(NamedKey::PageUp) => self.orbit.zoom(0.8),
            Key::Named(NamedKey::PageDown) => self.orbit.zoom(1.25),
            Key::Named(NamedKey::Escape) | Key::Character("q") => {
                if self.options.frames.is_some() {
                    self.quitting = true;
                } else {
                    event_loop.exit();
                }
            }
            Key::Character("?") => (self.options.notify)(CONTROLS),
            Key::Character("f") => {
                let size = self
                    .state
                    .as_ref()
                    .map_or(self.options.size, |s| (s.config.width, s.config.height));
                self.orbit = Orbit::fit(
                    &self.scene,
                    self.options.up,
                    &Framing {
                        ortho: self.ortho,
                        ..self.options.framing
                    },
                    self.options.fov_y,
                    size,
                );
                self.pan_for_panel(1.0);
            }
            Key::Character("b") => {
                self.fat_borders = match self.fat_borders {
                    FatBorders::Off => FatBorders::Six,
                    FatBorders::Six => FatBorders::Four,
                    FatBorders::Four => FatBorders::Two,
                    FatBorders::Two => FatBorders::Off,
                }
            }
            Key::Character("e") => self.edges = self.edges.next(),
            Key::Character("w") => self.wireframe = !self.wireframe,
            Key::Character("c") => self.toggle_section(),
            Key::Character("[") => self.step_section(-1.0),
            Key::Character("]") => self.step_section(1.0),
            Key::Character("t") => self.toggle_panel(),
            Key::Character("5") => self.ortho = !self.ortho,
            Key::Named(NamedKey::Space) => {
                if let Some(p) = self.playing.as_mut() {
                    p.paused = !p.paused;
                }
            }
            Key::Character("i") => {
                self.shading = if self.shading == Shading::Ids {
                    Shading::Lit
                } else {
                    Shading::Ids
                }
            }
            Key::Character("h") => {
                self.heat = !self.heat;
            }
            Key::Character("+") | Key::Character("=") => self.scale_pixel_error(2.0),
            Key::Character("-") => self.scale_pixel_error(0.5),
            Key::Character("p") => {
                if let Err(e) = self.screenshot() {
                    (self.options.notify)(&format!("error: {e}"));
                }
            }
            _ => return,
        }
        self.dirty = true;
    }

    fn scale_pixel_error(&mut self, factor: f64) {
        if let Some(s) = self.state.as_mut() {
            let pe = &mut s.frame.lod.options.pixel_error;
            *pe = (*pe * factor).clamp(0.125, 64.0);
        }
    }

    /// Takes the upgraded scene when it has arrived; whether one is still awaited.
    fn poll_upgrade(&mut self) -> bool {
        use std::sync::mpsc::TryRecvError;
        let Some(rx) = self.upgrade.as_ref() else {
            return false;
        };
        let mut scene = match rx.try_recv() {
            Ok(s) => s,
            Err(TryRecvError::Empty) => return true,
            Err(TryRecvError::Disconnected) => {
                self.upgrade = None;
                return false;
            }
        };
        self.upgrade = None;
        // Same patches, same bounds: the explosion's offsets still hold.
        if let Some(p) = self.playing.as_ref() {
            scene.bounds = p.explosion.bounds(&scene);
        }
        self.full = scene;
        self.reshow();
        (self.options.notify)("hierarchies ready: now drawing level-of-detail cuts");
        self.dirty = true;
        false
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewerError) {
        self.error = Some(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        if self.give_panel(&event) {
            return;
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(s) = self.state.as_mut()
                    && size.width > 0
                    && size.height > 0
                {
                    s.config.width = size.width;
                    s.config.height = size.height;
                    s.surface.configure(&s.renderer.gpu().device, &s.config);
                    self.dirty = true;
                }
            }
            WindowEvent::ModifiersChanged(m) => {
                self.shift = m.state().shift_key();
                self.ctrl = m.state().control_key();
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(event.logical_key, event_loop)
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some(button);
                self.click(state, button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = (position.x - self.cursor.x, position.y - self.cursor.y);
                self.cursor = position;
                let height = self.state.as_ref().map_or(1, |s| s.config.height);
                match self.drag {
                    Some(_) if self.ctrl => {
                        self.drag_section(dy, height);
                        self.dirty = true;
                    }
                    Some(MouseButton::Left) if !self.shift => {
                        self.orbit.rotate(-dx * 0.01, dy * 0.01);
                        self.dirty = true;
                    }
                    Some(MouseButton::Left) | Some(MouseButton::Right) => {
                        self.orbit.pan(dx, dy, self.options.fov_y, height);
                        self.dirty = true;
                    }
                    _ => {}
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.orbit.zoom(0.9f64.powf(lines));
                self.dirty = true;
            }
            WindowEvent::RedrawRequested => {
                if let Some(name) = self.options.keys.get(self.frames).cloned() {
                    match script_input(&name) {
                        Some(s) => self.scripted(s, event_loop),
                        None => {
                            let why = format!("unknown key {name:?} in the script");
                            return self.fail(event_loop, ViewerError::Surface(why));
                        }
                    }
                }
                self.dirty = false;
                match self.frame() {
                    Ok(busy) => self.dirty |= busy,
                    Err(e) => return self.fail(event_loop, e),
                }
                if self.quitting || self.options.frames.is_some_and(|n| self.frames >= n) {
                    if let Err(e) = self.screenshot() {
                        return self.fail(event_loop, e);
                    }
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let awaiting = self.poll_upgrade();
        // Scripted runs draw back to back; interactive ones only while something changes or
        // the queue has work (and look for the upgraded scene 20 times a second meanwhile).
        if self.dirty || self.options.frames.is_some() {
            if let Some(s) = self.state.as_ref() {
                s.window.request_redraw();
            }
            event_loop.set_control_flow(ControlFlow::Poll);
        } else if awaiting {
            let at = Instant::now() + Duration::from_millis(50);
            event_loop.set_control_flow(ControlFlow::WaitUntil(at));
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

#[cfg(test)]
mod tests;
