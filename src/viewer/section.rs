//! The viewer's section plane: key `c` cuts the model with a plane through its centre (the
//! middle of its bounding box) whose normal points at the viewer, so the half nearer the eye
//! is removed and the cap (`render::section`, as `render --section` draws it) faces the
//! camera; `c` again removes it. With `--section` planes, `c` turns those off and on
//! instead. Ctrl + drag (either button) moves the first plane along its normal, by the
//! model's diameter per window height (dragging up moves it towards the side it removes, so
//! less is cut away); `[` and `]` step it by a twentieth of the model's radius.

use super::App;
use crate::render::{SectionPlane, Sections};

/// Fraction of the model's radius a `[` / `]` press moves the plane.
pub const STEP: f64 = 0.05;

impl App {
    /// `c`: the `--section` planes off / on, or the viewer's own plane made / removed.
    pub(super) fn toggle_section(&mut self) {
        if !self.options.sections.is_empty() {
            self.sections_on = !self.sections_on;
            return;
        }
        if !self.cut.is_empty() {
            self.cut = Sections::NONE;
            return;
        }
        let (lo, hi) = self.scene.bbox;
        let centre = (lo + hi) * 0.5;
        let towards_eye = self.orbit.eye() - self.orbit.target;
        let normal = if towards_eye.length_squared() > 0.0 {
            towards_eye
        } else {
            self.scene.up.vector()
        };
        if let Ok(plane) = SectionPlane::new(centre, normal, "the viewer's plane")
            && let Ok(s) = Sections::new(&[plane])
        {
            self.cut = s;
            self.sections_on = true;
        }
    }

    /// Moves the first plane by `distance` along its normal (scene units).
    pub(super) fn move_section(&mut self, distance: f64) {
        let mut planes: Vec<SectionPlane> = self.cut.planes().copied().collect();
        let Some(first) = planes.first_mut() else {
            return;
        };
        first.point += first.normal * distance;
        if let Ok(s) = Sections::new(&planes) {
            self.cut = s;
        }
    }

    /// A ctrl + drag of `dy` window pixels in a window `height` pixels tall.
    pub(super) fn drag_section(&mut self, dy: f64, height: u32) {
        let diameter = 2.0 * self.scene.bounds.radius;
        self.move_section(-dy * diameter / f64::from(height.max(1)));
    }

    /// A `[` (−1) or `]` (+1) press.
    pub(super) fn step_section(&mut self, sign: f64) {
        self.move_section(sign * STEP * self.scene.bounds.radius);
    }
}
