//! The orbit camera: around a target, the model's up axis kept up.

use super::*;

/// Orbit camera around a target, `up` being the model's up axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: DVec3,
    pub distance: f64,
    /// Angle around `up`, radians.
    pub yaw: f64,
    /// Angle above the horizontal plane, radians (kept within ±89°).
    pub pitch: f64,
    pub up: DVec3,
}

impl Orbit {
    /// The camera of [`View::framed`] (fit to view, from the framing's direction). For an
    /// orthographic framing the distance is the one whose [`Orbit::view`] is the framed
    /// view's height (`height = 2 · distance · tan(fov_y / 2)`).
    pub fn fit(
        scene: &Scene,
        up: Option<DVec3>,
        framing: &Framing,
        fov_y: f64,
        size: (u32, u32),
    ) -> Orbit {
        let up = up.unwrap_or_else(|| scene.up.vector());
        let v = View::framed(&scene.bounds, up, framing, fov_y, size);
        let mut o = Orbit::looking(v.eye, v.target, up);
        if let Projection::Orthographic { height } = v.projection {
            o.distance = height / (2.0 * (fov_y * 0.5).tan());
        }
        o
    }

    /// The orbit whose camera stands at `eye` looking at `target` (pitch kept within ±89°).
    pub fn looking(eye: DVec3, target: DVec3, up: DVec3) -> Orbit {
        let up = up.try_normalize().unwrap_or(DVec3::Y);
        let d = eye - target;
        let (x, y) = basis(up);
        let mut h = d - up * d.dot(up);
        if h.length() < 1e-9 * d.length() {
            // Straight above or below: the orbit stands just in front (the top view's front
            // at the bottom of the image).
            h = crate::view::ModelFrame::of(up).front;
        }
        let limit = 89f64.to_radians();
        let length = d.length().max(1e-9);
        Orbit {
            target,
            distance: length,
            yaw: h.dot(y).atan2(h.dot(x)),
            pitch: (d.dot(up) / length)
                .clamp(-1.0, 1.0)
                .asin()
                .clamp(-limit, limit),
            up,
        }
    }

    pub fn eye(&self) -> DVec3 {
        let (x, y) = basis(self.up);
        let dir = (x * self.yaw.cos() + y * self.yaw.sin()) * self.pitch.cos()
            + self.up * self.pitch.sin();
        self.target + dir * self.distance
    }

    /// The camera, perspective or (`ortho`) orthographic as tall as the perspective view at
    /// the target ([`View::orthographic`]): zooming changes the height the same way.
    pub fn view(&self, scene: &Scene, fov_y: f64, size: (u32, u32), ortho: bool) -> View {
        View::new(self.eye(), self.target, self.up, fov_y, size, &scene.bounds)
            .with_ortho(ortho, &scene.bounds)
    }

    pub fn rotate(&mut self, dyaw: f64, dpitch: f64) {
        let limit = 89f64.to_radians();
        self.yaw += dyaw;
        self.pitch = (self.pitch + dpitch).clamp(-limit, limit);
    }

    /// Moves the target by `(dx, dy)` pixels of a view of height `height` and field `fov_y`.
    pub fn pan(&mut self, dx: f64, dy: f64, fov_y: f64, height: u32) {
        let forward = (self.target - self.eye()).normalize();
        let right = forward.cross(self.up).normalize_or_zero();
        let up = right.cross(forward);
        let pixel = self.distance * 2.0 * (fov_y * 0.5).tan() / height.max(1) as f64;
        self.target += (-right * dx + up * dy) * pixel;
    }

    /// Multiplies the distance by `factor` (> 0).
    pub fn zoom(&mut self, factor: f64) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).max(1e-9);
        }
    }
}

/// Two unit vectors completing `up` to a right-handed basis.
fn basis(up: DVec3) -> (DVec3, DVec3) {
    let a = if up.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = (a - up * a.dot(up)).normalize();
    (x, up.cross(x))
}
