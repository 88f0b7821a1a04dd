//! Garland–Heckbert quadrics ("Surface simplification using quadric error metrics", 1997):
//! the order in which [`super::Builder`] tries its collapses.

use glam::{DMat4, DVec3, DVec4};

/// A symmetric 4×4 quadric.
#[derive(Clone, Copy, Debug)]
pub(super) struct Quadric(DMat4);

impl Default for Quadric {
    /// The zero quadric (no plane). Not `DMat4::default()`, which is glam's identity: every
    /// vertex then cost 1 + |p|² more, and collapses were ordered by the distance of their
    /// vertices from the origin rather than by their error.
    fn default() -> Quadric {
        Quadric(DMat4::ZERO)
    }
}

impl Quadric {
    pub(super) fn plane(n: DVec3, p: DVec3, weight: f64) -> Quadric {
        let v = DVec4::new(n.x, n.y, n.z, -n.dot(p));
        Quadric(DMat4::from_cols(v * v.x, v * v.y, v * v.z, v * v.w) * weight)
    }
    pub(super) fn eval(&self, p: DVec3) -> f64 {
        let v = p.extend(1.0);
        v.dot(self.0 * v).max(0.0)
    }
    pub(super) fn add(&mut self, o: &Quadric) {
        self.0 += o.0;
    }
    /// Total weight of its planes (their normals are unit: the trace of the 3×3 part).
    pub(super) fn weight(&self) -> f64 {
        self.0.x_axis.x + self.0.y_axis.y + self.0.z_axis.z
    }
}
