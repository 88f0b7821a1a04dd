//! Camera, viewport and the one place where a pixel error becomes an object-space error.
//!
//! Conventions: right-handed world, `look_at_rh(eye, target, up)` and
//! `perspective_rh(fov_y, width/height, near, far)` (depth 0 at the near plane, 1 at the far
//! plane); NDC y points up; pixel (0,0) is the top-left pixel and pixel centres sit at
//! half-integers.
//!
//! Pixel error γ → object error ε, after Balázs et al., section 3: a ball of radius ε at distance
//! d projects to at most `ε · H / (2 d tan(fov_y/2))` pixels, so
//! `ε = γ · d · 2 tan(fov_y / 2) / H`, with d the distance from the eye to the patch's bounding
//! sphere, `d = max(|M − eye| − r, 0)`. Nothing nearer than the near plane is visible, so d is
//! clamped to at least the near-plane distance (otherwise an eye inside a patch's bounding sphere
//! would ask for ε = 0, an infinitely fine tessellation).
//!
//! **Orthographic views** ([`Projection::Orthographic`]) draw parallel rays along the viewing
//! axis into an image `height` world units tall: a pixel is `height / H` wide at every depth, so
//! `ε = γ · height / H` for every patch, near or far. The viewer is then a point at infinity,
//! and everything that needs the direction towards the viewer (fat borders' push-back, shading)
//! takes it from [`View::viewer`]: `(eye, 1)` under perspective, `(−forward, 0)` under an
//! orthographic projection.

mod framing;

pub(crate) use framing::ModelFrame;
pub use framing::{DEFAULT_MARGIN, Framing, NamedView};

use glam::{DMat4, DVec3, DVec4, Mat4};

use crate::model::Sphere;

/// Default allowed screen-space error, in pixels.
pub const DEFAULT_PIXEL_ERROR: f64 = 0.5;
/// Default vertical field of view, in degrees.
pub const DEFAULT_FOV_Y_DEG: f64 = 45.0;

/// How a view projects onto its image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Projection {
    /// Rays through the eye; vertical field of view [`View::fov_y`].
    #[default]
    Perspective,
    /// Rays parallel to the viewing axis; the image is `height` world units tall (and
    /// `height · aspect` wide) at every depth.
    Orthographic { height: f64 },
}

/// A camera and the image it renders into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    pub width: u32,
    pub height: u32,
    pub near: f64,
    pub far: f64,
    pub projection: Projection,
}

impl View {
    /// A view with near/far fitted to `bounds` (the whole model's sphere).
    pub fn new(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        fov_y: f64,
        (width, height): (u32, u32),
        bounds: &Sphere,
    ) -> View {
        let (near, far) = fit_near_far(eye, target, bounds);
        View {
            eye,
            target,
            up,
            fov_y,
            width,
            height,
            near,
            far,
            projection: Projection::Perspective,
        }
    }

    /// This view under an orthographic projection whose image is as tall as this
    /// perspective view's frustum at the target (`2 · |target − eye| · tan(fov_y / 2)`): the
    /// model at the target keeps its size. An orthographic view is returned as it is.
    pub fn orthographic(self, bounds: &Sphere) -> View {
        if self.is_orthographic() {
            return self;
        }
        let height = 2.0 * self.eye.distance(self.target) * (self.fov_y * 0.5).tan();
        self.with_ortho_height(height, bounds)
    }

    /// This view with `projection` (near/far fitted to `bounds` again; see
    /// [`View::with_ortho_height`]).
    pub fn with_projection(self, projection: Projection, bounds: &Sphere) -> View {
        match projection {
            Projection::Orthographic { height } => self.with_ortho_height(height, bounds),
            Projection::Perspective => View::new(
                self.eye,
                self.target,
                self.up,
                self.fov_y,
                (self.width, self.height),
                bounds,
            ),
        }
    }

    /// [`View::orthographic`] when `ortho`, else this view.
    pub fn with_ortho(self, ortho: bool, bounds: &Sphere) -> View {
        if ortho {
            self.orthographic(bounds)
        } else {
            self
        }
    }

    /// An orthographic view along this view's axis, `height` world units tall. The eye's
    /// distance changes nothing in the image but the clipping planes, so an eye less than
    /// one diameter in front of `bounds` is moved back along the axis (the whole model then
    /// lies in front of the near plane), and near/far are fitted again.
    pub fn with_ortho_height(self, height: f64, bounds: &Sphere) -> View {
        let axis = self.forward();
        let r = bounds.radius.max(1e-9);
        let ahead = (bounds.center - self.eye).dot(axis);
        let eye = if ahead < 2.0 * r {
            self.eye - axis * (2.0 * r - ahead)
        } else {
            self.eye
        };
        let (near, far) = fit_near_far(eye, eye + axis, bounds);
        View {
            eye,
            target: self.target,
            near,
            far,
            projection: Projection::Orthographic {
                height: height.max(1e-12),
            },
            ..self
        }
    }

    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic { .. })
    }

    /// Unit viewing axis, from the eye towards the target.
    pub fn forward(&self) -> DVec3 {
        (self.target - self.eye)
            .try_normalize()
            .unwrap_or(DVec3::NEG_Z)
    }

    /// The viewer in homogeneous coordinates: `(eye, 1)` under a perspective projection, the
    /// point at infinity `(−forward, 0)` under an orthographic one. The direction from a point
    /// `p` towards the viewer is `normalize(viewer.xyz − p · viewer.w)` (what the fat borders
    /// push back along, `render::fat_border::expand`).
    pub fn viewer(&self) -> DVec4 {
        match self.projection {
            Projection::Perspective => self.eye.extend(1.0),
            Projection::Orthographic { .. } => (-self.forward()).extend(0.0),
        }
    }

    /// Unit direction from `p` towards the viewer (see [`View::viewer`]).
    #[cfg(test)]
    pub(crate) fn towards_viewer(&self, p: DVec3) -> DVec3 {
        let v = self.viewer();
        (v.truncate() - p * v.w)
            .try_normalize()
            .unwrap_or(-self.forward())
    }

    /// The default camera: frames the model's bounding sphere from a three-quarter view, above
    /// and in front, `up` being the model's up axis.
    pub fn framing(bounds: &Sphere, up: DVec3, fov_y: f64, size: (u32, u32)) -> View {
        let dir = pleasant_direction(up);
        Self::framing_from(bounds, up, dir, fov_y, size)
    }

    /// Frames `bounds` looking from direction `dir` (pointing from the centre to the eye).
    pub fn framing_from(
        bounds: &Sphere,
        up: DVec3,
        dir: DVec3,
        fov_y: f64,
        size: (u32, u32),
    ) -> View {
        Self::framing_with_margin(bounds, up, dir, fov_y, size, framing::DEFAULT_MARGIN)
    }

    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }

    pub fn view_matrix(&self) -> DMat4 {
        DMat4::look_at_rh(self.eye, self.target, self.up)
    }

    pub fn proj_matrix(&self) -> DMat4 {
        match self.projection {
            Projection::Perspective => {
                DMat4::perspective_rh(self.fov_y, self.aspect(), self.near, self.far)
            }
            Projection::Orthographic { height } => {
                let (hw, hh) = (0.5 * height * self.aspect(), 0.5 * height);
                DMat4::orthographic_rh(-hw, hw, -hh, hh, self.near, self.far)
            }
        }
    }

    /// World → clip space, in f32 for the GPU.
    pub(crate) fn view_proj_f32(&self) -> Mat4 {
        (self.proj_matrix() * self.view_matrix()).as_mat4()
    }

    /// Object-space size of one pixel at distance `d` from the eye (the same at every
    /// distance under an orthographic projection).
    pub fn pixel_size_at(&self, d: f64) -> f64 {
        self.eps_of(1.0).pixel_size_at(d)
    }

    /// [`View::eps_obj`] at `pixel_error` for many spheres, the view's constants computed
    /// once (the same arithmetic, so the same values).
    pub(crate) fn eps_of(&self, pixel_error: f64) -> EpsOf {
        EpsOf {
            eye: self.eye,
            near: self.near,
            pixel_error,
            tan: (self.fov_y * 0.5).tan(),
            height: self.height as f64,
            ortho: match self.projection {
                Projection::Perspective => None,
                Projection::Orthographic { height } => Some(height),
            },
        }
    }

    /// ε for a patch with bounding sphere `s` at pixel error `pixel_error` (see module doc).
    ///
    /// ```
    /// use glam::DVec3;
    /// use patchwork::model::Sphere;
    /// use patchwork::view::View;
    ///
    /// let model = Sphere { center: DVec3::ZERO, radius: 1.0 };
    /// let fov = 90f64.to_radians();
    /// let view = View::new(DVec3::new(0.0, 0.0, 11.0), DVec3::ZERO, DVec3::Y, fov, (800, 600), &model);
    /// // d = 11 − 1 = 10 units; one pixel there is 10 · 2 tan 45° / 600 = 1/30 unit.
    /// let eps = view.eps_obj(&model, 0.5);
    /// assert!((eps - 0.5 / 30.0).abs() < 1e-12);
    /// ```
    pub fn eps_obj(&self, s: &Sphere, pixel_error: f64) -> f64 {
        self.eps_of(pixel_error).eps(s)
    }

    /// Linear view-space depth of a world point (distance along the viewing axis).
    pub fn view_depth(&self, p: DVec3) -> f64 {
        -(self.view_matrix() * p.extend(1.0)).z
    }

    /// Whether the sphere `s` reaches into the view frustum (side planes, near and far): what
    /// frustum culling keeps. (One test; [`View::frustum`] precomputes it for many spheres.)
    pub fn sees_sphere(&self, s: &Sphere) -> bool {
        self.frustum().sees(s)
    }

    /// The view's frustum, with the view matrix and side-plane slopes computed once: for
    /// testing many spheres per frame.
    pub fn frustum(&self) -> Frustum {
        // Side planes |a| = o + t · depth: through the eye (o = 0) under perspective,
        // parallel to the axis (t = 0) under an orthographic projection.
        let (ty, oy) = match self.projection {
            Projection::Perspective => ((self.fov_y * 0.5).tan(), 0.0),
            Projection::Orthographic { height } => (0.0, 0.5 * height),
        };
        let (tx, ox) = (ty * self.aspect(), oy * self.aspect());
        Frustum {
            view: self.view_matrix(),
            near: self.near,
            far: self.far,
            tx,
            ty,
            ox,
            oy,
            nx: (1.0 + tx * tx).sqrt(),
            ny: (1.0 + ty * ty).sqrt(),
        }
    }

    /// Projects a world point to pixel coordinates (x right, y down, centres at half-integers)
    /// and linear view depth. `None` behind the eye (perspective; an orthographic view
    /// projects every point).
    pub fn project(&self, p: DVec3) -> Option<(f64, f64, f64)> {
        let at = self.view_matrix() * p.extend(1.0);
        let clip: DVec4 = self.proj_matrix() * at;
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        let x = (ndc.x * 0.5 + 0.5) * self.width as f64;
        let y = (0.5 - ndc.y * 0.5) * self.height as f64;
        Some((x, y, -at.z))
    }
}

/// [`View::eps_obj`] with the view's constants computed once ([`View::eps_of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EpsOf {
    eye: DVec3,
    near: f64,
    pixel_error: f64,
    /// tan(fov_y / 2).
    tan: f64,
    /// The image height, pixels.
    height: f64,
    /// Orthographic projections: the view's height, world units.
    ortho: Option<f64>,
}

impl EpsOf {
    /// ε for a patch with bounding sphere `s` (see [`View::eps_obj`]).
    pub fn eps(&self, s: &Sphere) -> f64 {
        let d = (s.center.distance(self.eye) - s.radius).max(self.near);
        self.pixel_error * self.pixel_size_at(d)
    }

    /// [`View::pixel_size_at`].
    fn pixel_size_at(&self, d: f64) -> f64 {
        match self.ortho {
            None => d * 2.0 * self.tan / self.height,
            Some(height) => height / self.height,
        }
    }
}

/// A view frustum ready for many sphere tests ([`View::frustum`]): side planes
/// `|x| = ox + tx · depth` and `|y| = oy + ty · depth` in view space (through the eye under
/// perspective, parallel to the axis under an orthographic projection), and the near and far
/// planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    view: DMat4,
    near: f64,
    far: f64,
    tx: f64,
    ty: f64,
    ox: f64,
    oy: f64,
    /// Plane normalisers √(1 + t²).
    nx: f64,
    ny: f64,
}

impl Frustum {
    /// Whether the sphere `s` reaches into the frustum (within its radius of every plane's
    /// inner side): conservative, what frustum culling keeps.
    pub fn sees(&self, s: &Sphere) -> bool {
        self.within(s.center, s.radius)
    }

    /// Whether the sphere `s` lies wholly inside the frustum (on the inner side of every
    /// plane by at least its radius): then so does every sphere inside it, and each of those
    /// passes [`Frustum::sees`].
    pub fn contains(&self, s: &Sphere) -> bool {
        self.within(s.center, -s.radius)
    }

    /// Whether `center` lies at most `margin` outside every plane (inside by at least
    /// `-margin` when it is negative).
    fn within(&self, center: DVec3, margin: f64) -> bool {
        let c = (self.view * center.extend(1.0)).truncate();
        let depth = -c.z;
        if depth + margin < self.near || depth - margin > self.far {
            return false;
        }
        // Distance outside the side plane `|a| = o + t · depth`.
        let side = |a: f64, o: f64, t: f64, n: f64| (a.abs() - o - t * depth) / n <= margin;
        side(c.x, self.ox, self.tx, self.nx) && side(c.y, self.oy, self.ty, self.ny)
    }
}

/// Near/far planes around the model's sphere, with a margin so fat borders pushed back by ε
/// stay inside the frustum.
pub(crate) fn fit_near_far(eye: DVec3, target: DVec3, bounds: &Sphere) -> (f64, f64) {
    let axis = (target - eye).try_normalize().unwrap_or(DVec3::NEG_Z);
    let r = bounds.radius.max(1e-9) * 1.05;
    let c = (bounds.center - eye).dot(axis);
    let far = (c + r).max(r * 1e-3);
    let near = (c - r).max(far * 1e-4).max(r * 1e-4);
    (near, far * 1.02)
}

/// A three-quarter view from the front-right, above, for a model whose up axis is `up`.
pub fn pleasant_direction(up: DVec3) -> DVec3 {
    let f = ModelFrame::of(up);
    (f.front + 0.45 * f.right + 0.55 * f.up).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Sphere {
        Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        }
    }

    #[test]
    fn frustum_culling_keeps_what_is_seen() {
        let model = Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
        let view = View::new(
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::ZERO,
            DVec3::Y,
            60f64.to_radians(),
            (400, 300),
            &model,
        );
        let sphere = |x: f64, y: f64, z: f64, r: f64| Sphere {
            center: DVec3::new(x, y, z),
            radius: r,
        };
        assert!(view.sees_sphere(&model));
        // Half height of the frustum at depth 10 is 10 tan 30° = 5.77; half width 7.70.
        assert!(view.sees_sphere(&sphere(0.0, 6.0, 0.0, 0.5)));
        assert!(!view.sees_sphere(&sphere(0.0, 7.0, 0.0, 0.5)));
        assert!(view.sees_sphere(&sphere(8.0, 0.0, 0.0, 0.5)));
        assert!(!view.sees_sphere(&sphere(9.0, 0.0, 0.0, 0.5)));
        // Behind the eye.
        assert!(!view.sees_sphere(&sphere(0.0, 0.0, 12.0, 1.0)));
        // Every point a view projects inside the image is in a sphere it sees.
        for p in [DVec3::new(0.9, 0.0, 0.0), DVec3::new(-0.5, 0.5, 0.5)] {
            let (x, y, _) = view.project(p).expect("in front of the eye");
            assert!(x > 0.0 && x < 400.0 && y > 0.0 && y < 300.0);
            assert!(view.sees_sphere(&Sphere {
                center: p,
                radius: 0.01
            }));
        }
    }

    #[test]
    fn eps_follows_the_papers_formula() {
        let v = View::new(
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::ZERO,
            DVec3::Y,
            60f64.to_radians(),
            (800, 600),
            &unit(),
        );
        let s = Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
        let expect = 0.5 * 9.0 * 2.0 * 30f64.to_radians().tan() / 600.0;
        assert!((v.eps_obj(&s, 0.5) - expect).abs() < 1e-12);
        // Eye inside the sphere: clamped to the near plane, never zero.
        let inside = Sphere {
            center: DVec3::new(0.0, 0.0, 10.0),
            radius: 5.0,
        };
        assert!(v.eps_obj(&inside, 0.5) > 0.0);
    }

    #[test]
    fn projection_convention_top_left_origin() {
        let v = View::new(
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::ZERO,
            DVec3::Y,
            1.0,
            (100, 50),
            &unit(),
        );
        let (x, y, d) = v.project(DVec3::ZERO).expect("in front");
        assert!((x - 50.0).abs() < 1e-9 && (y - 25.0).abs() < 1e-9);
        assert!((d - 5.0).abs() < 1e-9);
        // A point above the target lands in the upper half (smaller y).
        let (_, y_up, _) = v.project(DVec3::new(0.0, 0.5, 0.0)).expect("in front");
        assert!(y_up < 25.0);
        assert!((v.view_depth(DVec3::ZERO) - 5.0).abs() < 1e-9);
    }

    #[test]
    fn framing_keeps_the_sphere_inside() {
        let s = Sphere {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 2.0,
        };
        let v = View::framing(&s, DVec3::Z, 45f64.to_radians(), (1024, 768));
        assert!(v.near < v.eye.distance(s.center) - s.radius);
        assert!(v.far > v.eye.distance(s.center) + s.radius);
        for dir in [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::X,
            -DVec3::Y,
            -DVec3::Z,
        ] {
            let (x, y, _) = v.project(s.center + dir * s.radius).expect("in front");
            assert!((0.0..=1024.0).contains(&x) && (0.0..=768.0).contains(&y));
        }
    }

    fn ortho() -> View {
        View::new(
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::ZERO,
            DVec3::Y,
            60f64.to_radians(),
            (800, 600),
            &unit(),
        )
        .orthographic(&unit())
    }

    /// Orthographic: ε = γ · height / H for every patch, near or far (the perspective ε
    /// grows with the distance).
    #[test]
    fn orthographic_eps_does_not_depend_on_distance() {
        let v = ortho();
        let height = 2.0 * 10.0 * 30f64.to_radians().tan();
        assert_eq!(v.projection, Projection::Orthographic { height });
        let at = |z: f64| Sphere {
            center: DVec3::new(0.0, 0.0, z),
            radius: 0.1,
        };
        let expect = 0.5 * height / 600.0;
        for z in [0.9, 0.0, -0.9] {
            assert!((v.eps_obj(&at(z), 0.5) - expect).abs() < 1e-15, "z = {z}");
        }
        let p = View {
            projection: Projection::Perspective,
            ..v
        };
        assert!(p.eps_obj(&at(-0.9), 0.5) > 1.1 * p.eps_obj(&at(0.9), 0.5));
    }

    /// Orthographic frustum: a box |x| ≤ w/2, |y| ≤ h/2 at every depth; projection maps
    /// equal lengths at any depth to equal pixel lengths; the viewer is at infinity.
    #[test]
    fn orthographic_frustum_and_projection_are_parallel() {
        let v = ortho();
        let Projection::Orthographic { height } = v.projection else {
            panic!("orthographic")
        };
        let (hh, hw) = (0.5 * height, 0.5 * height * v.aspect());
        let sphere = |x: f64, y: f64, z: f64| Sphere {
            center: DVec3::new(x, y, z),
            radius: 0.1,
        };
        for z in [0.9, -0.9] {
            assert!(v.sees_sphere(&sphere(0.0, hh + 0.09, z)));
            assert!(!v.sees_sphere(&sphere(0.0, hh + 0.11, z)));
            assert!(v.sees_sphere(&sphere(-hw - 0.09, 0.0, z)));
            assert!(!v.sees_sphere(&sphere(-hw - 0.11, 0.0, z)));
        }
        // Beyond the far plane and in front of the near plane.
        assert!(!v.sees_sphere(&sphere(0.0, 0.0, v.eye.z - v.far - 0.2)));
        assert!(!v.sees_sphere(&sphere(0.0, 0.0, v.eye.z - v.near + 0.2)));
        // A unit segment along x at depths 9.1 and 10.9 is equally long on the image.
        let len = |z: f64| {
            let a = v.project(DVec3::new(0.0, 0.0, z)).expect("projects");
            let b = v.project(DVec3::new(1.0, 0.0, z)).expect("projects");
            assert!((a.2 - (v.eye.z - z)).abs() < 1e-9, "linear depth");
            b.0 - a.0
        };
        assert!((len(0.9) - len(-0.9)).abs() < 1e-9);
        assert!((len(0.0) - 600.0 / height).abs() < 1e-9);
        assert_eq!(v.viewer(), DVec4::new(0.0, 0.0, 1.0, 0.0));
        assert_eq!(v.towards_viewer(DVec3::new(5.0, -3.0, 1.0)), DVec3::Z);
        assert_eq!(
            View::new(v.eye, v.target, v.up, v.fov_y, (8, 6), &unit()).viewer(),
            v.eye.extend(1.0)
        );
    }

    /// An eye inside (or near) the model is moved back along the axis: the model lies
    /// between near and far, and the image stays the same.
    #[test]
    fn orthographic_eye_stands_outside_the_model() {
        let s = unit();
        let v = View::new(
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::ZERO,
            DVec3::Y,
            1.0,
            (64, 64),
            &s,
        )
        .with_ortho_height(3.0, &s);
        assert!(v.eye.z >= 2.0 - 1e-12, "{}", v.eye);
        assert!(v.near > 0.0 && v.near < v.eye.z - 1.0 && v.far > v.eye.z + 1.0);
        assert!(v.sees_sphere(&s));
        let (x, y, _) = v.project(DVec3::new(1.5, 0.0, 0.0)).expect("projects");
        assert!((x - 64.0).abs() < 1e-9 && (y - 32.0).abs() < 1e-9);
    }
}
