//! Picking in the window: a left click (pressed and released within 3 pixels, without
//! shift) prints what the last frame shows there — `render::pick` on the frame's own ID image
//! and the frame loop's meshes — and the distance from the click before.

use winit::event::{ElementState, MouseButton};

use super::App;
use crate::render::pick::{describe, hit_at};

impl App {
    /// A mouse button went down or up: a left click picks.
    pub(super) fn click(&mut self, state: ElementState, button: MouseButton) {
        if button != MouseButton::Left {
            return;
        }
        let at = self.cursor;
        match state {
            ElementState::Pressed => self.pressed_at = Some(at),
            ElementState::Released => {
                let moved = self
                    .pressed_at
                    .take()
                    .map(|p| (p.x - at.x).hypot(p.y - at.y));
                if moved.is_some_and(|d| d < 3.0) && !self.shift {
                    self.pick(at.x, at.y);
                }
            }
        }
    }

    /// A click at window position `(x, y)`: what the last frame shows there (`render::pick`),
    /// and the distance from the click before, to [`super::ViewerOptions::picked`]. Not
    /// while `--implode` moves the parts (the frame loop's meshes stay assembled).
    fn pick(&mut self, x: f64, y: f64) {
        if self.playing.is_some() {
            (self.options.picked)("pick: not with --implode (the parts are drawn moved)");
            return;
        }
        let Some(state) = self.state.as_ref() else {
            return;
        };
        let Some(frame) = state.last.as_ref() else {
            return;
        };
        let (px, py) = (x.max(0.0) as u32, y.max(0.0) as u32);
        let view = self.view(frame.width, frame.height);
        let hit = hit_at(frame, &view, state.frame.lod.meshes(), px, py);
        let described = hit.and_then(|h| Some((h, describe(&self.scene, h.patch)?)));
        let unit = self.scene.unit.unwrap_or("units");
        match described {
            Some((h, d)) => {
                let mut line = format!("pick {px},{py}: {}", d.line(&h, unit));
                if let Some(last) = self.last_pick {
                    line += &format!(
                        "; {:.4} {unit} from the pick before",
                        last.distance(h.point)
                    );
                }
                (self.options.picked)(&line);
                self.last_pick = Some(h.point);
            }
            None => (self.options.picked)(&format!("pick {px},{py}: nothing (background)")),
        }
    }
}
