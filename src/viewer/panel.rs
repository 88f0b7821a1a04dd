//! The part panel of the viewer (key `t`): the assembly tree as the scene knows it — every
//! [`Instance`](crate::model::Instance) (a placed part's solid or shell) under the groups of
//! its occurrence path (`assembly_1/sub_2/bolt_1`) — with a visibility checkbox per instance
//! and per group, isolate (only that instance shown) and show all, colour by part, and an
//! explode slider driving the implosion's offsets ([`crate::anim::Explosion`], by placed
//! parts) live.
//!
//! What is drawn is the loaded scene restricted to the checked instances by
//! [`Scene::with_instances`], the path `--only` / `--hide` take: hidden patches are not
//! in the drawn scene at all (surfaces, fat borders and edges), and the drawn scene is an
//! ordinary scene, so the crack guarantees of the frame loop hold for what is visible.
//! A change of visibility or colours makes a new scene and a new frame state (tessellated
//! again); the slider only changes the offsets of the next frame. The state here is plain
//! data ([`Panel`]); [`PanelUi`] draws it with egui (egui-winit feeds it the window's events,
//! egui-wgpu paints it over the presented frame).

use glam::DVec3;

use crate::anim::{Explosion, GroupBy};
use crate::model::Scene;
use crate::render::gpu::Gpu;

/// Width of the panel in logical pixels.
pub const PANEL_WIDTH: f32 = 240.0;

/// How far the slider's full explosion moves the parts, × the model's radius (as
/// `implode --distance`'s default).
pub const EXPLODE_DISTANCE: f64 = 1.0;

/// The panel's settings: what is shown and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// The panel is drawn (`t` toggles).
    pub open: bool,
    /// Per instance of the loaded scene: drawn.
    pub visible: Vec<bool>,
    /// Every part in a colour of its own (a part placed twice has one colour).
    pub colour_by_part: bool,
    /// The explode slider, 0 (assembled) to 1 (exploded by [`EXPLODE_DISTANCE`]).
    pub explode: f64,
    /// The tree of the instances' occurrence paths.
    pub tree: Vec<Node>,
}

/// A row of the tree: a group of the occurrence paths (children) or an instance (a leaf).
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub label: String,
    pub children: Vec<Node>,
    /// The instance a leaf stands for.
    pub instance: Option<usize>,
}

impl Node {
    /// The instances at and below this node.
    pub fn instances(&self, out: &mut Vec<usize>) {
        out.extend(self.instance);
        for c in &self.children {
            c.instances(out);
        }
    }
}

/// The tree of `scene`'s instances: one group per leading segment of the occurrence paths,
/// a leaf per instance labelled with its last segment and, when it differs, its part's name
/// (an unnamed instance by its part's name, else `#N`).
pub fn tree(scene: &Scene) -> Vec<Node> {
    let mut roots: Vec<Node> = Vec::new();
    for (i, inst) in scene.instances.iter().enumerate() {
        let part = scene
            .parts
            .get(inst.part as usize)
            .map_or("", |p| p.name.as_str());
        let segments: Vec<&str> = inst.name.split('/').filter(|s| !s.is_empty()).collect();
        let (groups, last) = match segments.split_last() {
            Some((last, groups)) => (groups, (*last).to_string()),
            None => (&[][..], String::new()),
        };
        let mut label = match (last.is_empty(), part.is_empty()) {
            (true, true) => format!("#{i}"),
            (true, false) => part.to_string(),
            (false, _) => last,
        };
        if !part.is_empty() && label != part && !label.starts_with(part) {
            label = format!("{label} ({part})");
        }
        let mut level = &mut roots;
        for g in groups {
            let at = match level
                .iter()
                .position(|n| n.instance.is_none() && n.label == *g)
            {
                Some(k) => k,
                None => {
                    level.push(Node {
                        label: (*g).to_string(),
                        children: Vec::new(),
                        instance: None,
                    });
                    level.len() - 1
                }
            };
            level = &mut level[at].children;
        }
        level.push(Node {
            label,
            children: Vec::new(),
            instance: Some(i),
        });
    }
    roots
}

/// A colour per part: hues spread by the golden angle, lit-friendly saturation (linear RGB).
pub fn part_colour(part: u32) -> [f32; 3] {
    let h = (part as f32 * 0.618_034).fract() * 6.0;
    let (s, v) = (0.55f32, 0.85f32);
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

impl Panel {
    /// Every instance of `scene` shown, the panel closed.
    pub fn new(scene: &Scene) -> Panel {
        Panel {
            open: false,
            visible: vec![true; scene.instances.len()],
            colour_by_part: false,
            explode: 0.0,
            tree: tree(scene),
        }
    }

    /// Shows or hides instance `i` (out of range: nothing).
    pub fn toggle(&mut self, i: usize) {
        if let Some(v) = self.visible.get_mut(i) {
            *v = !*v;
        }
    }

    /// Only instance `i` shown.
    pub fn isolate(&mut self, i: usize) {
        for (k, v) in self.visible.iter_mut().enumerate() {
            *v = k == i;
        }
    }

    /// Whether the drawn scene is the loaded one as it is (nothing hidden, colours the
    /// file's).
    pub fn is_identity(&self) -> bool {
        !self.colour_by_part && self.visible.iter().all(|&v| v)
    }

    /// The scene to draw: `full` with the checked instances only (no patch when none is
    /// checked; bounds the whole model's then), coloured by part when asked.
    pub fn shown(&self, full: &Scene) -> Scene {
        let mut s = if self.visible.iter().all(|&v| v) {
            full.clone()
        } else {
            full.with_instances(&self.visible).unwrap_or_else(|| {
                let mut empty = full.clone();
                empty.patches.clear();
                empty
            })
        };
        if self.colour_by_part {
            for p in &mut s.patches {
                p.color = Some(part_colour(p.part));
            }
        }
        s
    }
}

/// The slider's explosion of a drawn scene and the sphere holding it at every amount.
#[derive(Clone, Debug)]
pub struct Exploded {
    pub explosion: Explosion,
    /// The drawn scene's own bounds (assembled).
    pub assembled: crate::model::Sphere,
    /// Bounds over the whole flight.
    pub flight: crate::model::Sphere,
}

impl Exploded {
    pub fn new(scene: &Scene) -> Exploded {
        let explosion = Explosion::new(scene, GroupBy::Parts, EXPLODE_DISTANCE);
        let flight = explosion.bounds(scene);
        Exploded {
            explosion,
            assembled: scene.bounds,
            flight,
        }
    }

    /// Offsets at slider position `amount` (none at 0).
    pub fn offsets(&self, amount: f64) -> Option<Vec<DVec3>> {
        (amount > 0.0).then(|| self.explosion.at(amount))
    }
}

/// What a pass of the panel changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changed {
    /// Visibility or colours: a new drawn scene.
    pub scene: bool,
    /// The slider: new offsets.
    pub explode: bool,
}

/// The panel's egui: context, the window's input, the painter.
pub struct PanelUi {
    ctx: egui::Context,
    input: egui_winit::State,
    painter: egui_wgpu::Renderer,
    /// The last pass's output, painted over the presented frame.
    output: Option<egui::FullOutput>,
    /// A scripted press given to the coming pass, released in the one after.
    armed: Option<egui::Pos2>,
    due: Option<egui::Pos2>,
}

/// The primary button pressed or released at `pos`.
fn button(pos: egui::Pos2, pressed: bool) -> egui::Event {
    egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    }
}

impl std::fmt::Debug for PanelUi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PanelUi")
    }
}

impl PanelUi {
    pub fn new(window: &winit::window::Window, gpu: &Gpu, format: wgpu::TextureFormat) -> Self {
        let ctx = egui::Context::default();
        let max = gpu.device.limits().max_texture_dimension_2d as usize;
        let input = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max),
        );
        let painter =
            egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        PanelUi {
            ctx,
            input,
            painter,
            output: None,
            armed: None,
            due: None,
        }
    }

    /// Hands a window event to egui: whether egui took it (a click on the panel) and whether
    /// the panel wants drawing again.
    pub fn event(
        &mut self,
        window: &winit::window::Window,
        e: &winit::event::WindowEvent,
    ) -> (bool, bool) {
        let r = self.input.on_window_event(window, e);
        (r.consumed, r.repaint)
    }

    /// A scripted left click at window pixel `(x, y)`: the pointer moves there and presses
    /// in the next pass and releases in the one after (so a slider, which follows a held
    /// button, moves too). egui finds the widget under the pointer from the pass before, so
    /// the panel must have been drawn once.
    pub fn click(&mut self, x: f32, y: f32) {
        let ppp = self.ctx.pixels_per_point();
        let pos = egui::pos2(x / ppp, y / ppp);
        let raw = self.input.egui_input_mut();
        raw.events.push(egui::Event::PointerMoved(pos));
        raw.events.push(button(pos, true));
        self.armed = Some(pos);
    }

    /// One egui pass over `panel` (closed: an empty pass, so egui's state stays current);
    /// what it changed. `scene` names the instances' parts; `animating` greys out the slider
    /// (`--implode` drives the offsets then).
    pub fn run(
        &mut self,
        window: &winit::window::Window,
        panel: &mut Panel,
        animating: bool,
    ) -> Changed {
        if let Some(pos) = self.due.take() {
            self.input.egui_input_mut().events.push(button(pos, false));
        }
        self.due = self.armed.take();
        let raw = self.input.take_egui_input(window);
        let mut changed = Changed::default();
        let output = self.ctx.run_ui(raw, |ui| {
            if panel.open {
                changed = panel_ui(ui, panel, animating);
            }
        });
        self.input
            .handle_platform_output(window, output.platform_output.clone());
        self.output = Some(output);
        changed
    }

    /// Paints the last pass over `target` (the window's texture, `size` pixels).
    pub fn paint(&mut self, gpu: &Gpu, target: &wgpu::TextureView, size: (u32, u32)) {
        let Some(output) = self.output.take() else {
            return;
        };
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.painter
                    .update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let prims = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: output.pixels_per_point,
        };
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let extra =
            self.painter
                .update_buffers(&gpu.device, &gpu.queue, &mut encoder, &prims, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.painter.render(&mut pass, &prims, &screen);
        }
        gpu.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        for id in &output.textures_delta.free {
            self.painter.free_texture(id);
        }
    }
}

/// The panel's widgets: colour by part, the explode slider, show all, the tree.
fn panel_ui(ui: &mut egui::Ui, panel: &mut Panel, animating: bool) -> Changed {
    let mut changed = Changed::default();
    egui::Panel::left("parts")
        .resizable(false)
        .exact_size(PANEL_WIDTH)
        .show(ui, |ui| {
            ui.heading("Parts");
            if ui
                .checkbox(&mut panel.colour_by_part, "colour by part")
                .changed()
            {
                changed.scene = true;
            }
            ui.add_enabled_ui(!animating, |ui| {
                let slider = egui::Slider::new(&mut panel.explode, 0.0..=1.0).text("explode");
                if ui.add(slider).changed() {
                    changed.explode = true;
                }
            });
            if ui.button("show all").clicked() {
                panel.visible.iter_mut().for_each(|v| *v = true);
                changed.scene = true;
            }
            ui.separator();
            egui::ScrollArea::vertical().show(ui, |ui| {
                let tree = std::mem::take(&mut panel.tree);
                for node in &tree {
                    changed.scene |= node_ui(ui, node, &mut panel.visible);
                }
                panel.tree = tree;
            });
        });
    changed
}

/// A row of the tree (a group: a checkbox for everything below it and its children
/// collapsible; a leaf: its checkbox and an isolate button); whether visibility changed.
fn node_ui(ui: &mut egui::Ui, node: &Node, visible: &mut [bool]) -> bool {
    let mut changed = false;
    match node.instance {
        Some(i) => {
            ui.horizontal(|ui| {
                if let Some(v) = visible.get_mut(i) {
                    changed |= ui.checkbox(v, node.label.as_str()).changed();
                }
                if ui.small_button("isolate").clicked() {
                    for (k, v) in visible.iter_mut().enumerate() {
                        *v = k == i;
                    }
                    changed = true;
                }
            });
        }
        None => {
            let mut below = Vec::new();
            node.instances(&mut below);
            let mut all = below
                .iter()
                .all(|&i| visible.get(i).copied().unwrap_or(false));
            ui.horizontal(|ui| {
                if ui.checkbox(&mut all, "").changed() {
                    for &i in &below {
                        if let Some(v) = visible.get_mut(i) {
                            *v = all;
                        }
                    }
                    changed = true;
                }
                ui.collapsing(node.label.as_str(), |ui| {
                    for c in &node.children {
                        changed |= node_ui(ui, c, visible);
                    }
                });
            });
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Instance, Part, UpAxis};
    use glam::DMat4;

    fn scene() -> Scene {
        let mut s = Scene::from_bezier(Vec::new(), UpAxis::Z);
        s.parts = vec![Part { name: "nut".into() }, Part { name: "rod".into() }];
        let inst = |name: &str, part| Instance {
            name: name.into(),
            part,
            transform: DMat4::IDENTITY,
            shell: None,
        };
        s.instances = vec![
            inst("rod-assembly_1/nut_1", 0),
            inst("rod-assembly_1/rod_1", 1),
            inst("bracket_1/nut_3", 0),
            inst("", 1),
        ];
        s
    }

    #[test]
    fn the_tree_groups_instances_by_their_occurrence_path() {
        let t = tree(&scene());
        let labels: Vec<&str> = t.iter().map(|n| n.label.as_str()).collect();
        assert_eq!(labels, ["rod-assembly_1", "bracket_1", "rod"]);
        let kids: Vec<(&str, Option<usize>)> = t[0]
            .children
            .iter()
            .map(|n| (n.label.as_str(), n.instance))
            .collect();
        assert_eq!(kids, [("nut_1", Some(0)), ("rod_1", Some(1))]);
        let mut below = Vec::new();
        t[0].instances(&mut below);
        assert_eq!(below, [0, 1]);
        assert_eq!(t[2].instance, Some(3));
    }

    #[test]
    fn toggle_and_isolate_choose_the_instances() {
        let mut p = Panel::new(&scene());
        assert!(p.is_identity());
        p.toggle(1);
        assert_eq!(p.visible, [true, false, true, true]);
        p.isolate(2);
        assert_eq!(p.visible, [false, false, true, false]);
        p.toggle(9);
        assert_eq!(p.visible, [false, false, true, false]);
    }

    #[test]
    fn part_colours_differ_between_neighbouring_parts() {
        for k in 0..8 {
            let (a, b) = (part_colour(k), part_colour(k + 1));
            let d: f32 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
            assert!(d > 0.15, "parts {k} and {}: {a:?} {b:?}", k + 1);
            assert!(a.iter().all(|c| (0.0..=1.0).contains(c)));
        }
    }
}
