//! What the viewer draws as the part panel ([`super::panel`]) says: the panel's pass each
//! frame, the drawn scene made again when visibility or colours change, the explode slider's
//! bounds, window events shared with egui, and scripted panel input.

use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;

use super::panel::{Exploded, PANEL_WIDTH};
use super::{App, Scripted};
use crate::frame::FrameState;

impl App {
    /// The panel's egui pass for this frame, and what it changed applied.
    pub(super) fn panel_pass(&mut self) {
        let animating = self.playing.is_some();
        let Some(state) = self.state.as_mut() else {
            return;
        };
        let changed = state.ui.run(&state.window, &mut self.panel, animating);
        if changed.scene {
            self.reshow();
        }
        if changed.explode {
            self.explode_bounds();
        }
    }

    /// The drawn scene made again from the loaded one and the panel (a new frame state over
    /// it, camera and pixel error kept); the animation's and the slider's explosions with it.
    pub(super) fn reshow(&mut self) {
        let mut scene = self.panel.shown(&self.full);
        self.exploded = Exploded::new(&scene);
        if let (Some(p), Some(a)) = (self.playing.as_mut(), self.options.implode) {
            p.explosion = crate::anim::Explosion::new(&scene, a.by, a.distance);
            scene.bounds = p.explosion.bounds(&scene);
        }
        self.scene = scene;
        self.explode_bounds();
        let size = self
            .state
            .as_ref()
            .map(|s| (s.config.width, s.config.height));
        if let Some((w, h)) = size {
            let view = self.view(w, h);
            if let Some(s) = self.state.as_mut() {
                s.frame = FrameState::new(&self.scene, &view, s.frame.lod.options);
            }
        }
        self.dirty = true;
    }

    /// The drawn scene's bounds hold the parts where the slider puts them (near and far
    /// planes).
    pub(super) fn explode_bounds(&mut self) {
        if self.playing.is_none() {
            self.scene.bounds = if self.panel.explode > 0.0 {
                self.exploded.flight
            } else {
                self.exploded.assembled
            };
        }
        self.dirty = true;
    }

    /// `t`: the panel opens or closes, and the camera pans by half its width so that the
    /// model stays in the middle of what the panel leaves free.
    pub(super) fn toggle_panel(&mut self) {
        if self.panel.open {
            self.pan_for_panel(-1.0);
            self.panel.open = false;
        } else {
            self.panel.open = true;
            self.pan_for_panel(1.0);
        }
    }

    /// Pans by `sign` × half the panel's width when the panel is open (after `f` too).
    pub(super) fn pan_for_panel(&mut self, sign: f64) {
        let Some(state) = self.state.as_ref() else {
            return;
        };
        if !self.panel.open {
            return;
        }
        let half = f64::from(PANEL_WIDTH) * 0.5 * state.window.scale_factor();
        let height = state.config.height;
        self.orbit.pan(sign * half, 0.0, self.options.fov_y, height);
    }

    /// Gives a window event to the panel's egui; whether the panel took it (a press, a wheel
    /// turn or a key on the open panel: not for the camera; a release always reaches the
    /// camera too, so a drag that ends over the panel ends).
    pub(super) fn give_panel(&mut self, event: &WindowEvent) -> bool {
        let Some(state) = self.state.as_mut() else {
            return false;
        };
        let (consumed, repaint) = state.ui.event(&state.window, event);
        if !self.panel.open {
            return false;
        }
        self.dirty |= repaint;
        consumed
            && matches!(
                event,
                WindowEvent::MouseInput {
                    state: winit::event::ElementState::Pressed,
                    ..
                } | WindowEvent::MouseWheel { .. }
                    | WindowEvent::KeyboardInput { .. }
            )
    }

    /// One scripted entry (`--keys`).
    pub(super) fn scripted(&mut self, s: Scripted, event_loop: &ActiveEventLoop) {
        match s {
            Scripted::Key(k) => self.key(k, event_loop),
            Scripted::Click(x, y) => {
                if let Some(state) = self.state.as_mut() {
                    state.ui.click(x, y);
                }
            }
            Scripted::Part(n) => {
                self.panel.toggle(n);
                self.reshow();
            }
            Scripted::Explode(f) => {
                self.panel.explode = f;
                self.explode_bounds();
            }
        }
        self.dirty = true;
    }
}
