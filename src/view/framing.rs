//! Where the default camera stands: named views (front, top, iso…), azimuth and elevation
//! about the model's up axis, and the margin left around the model.
//!
//! Directions are in the model's own frame, which follows its up axis: for a z-up model
//! (STEP, `.bpt`) front is −y, right +x and top +z; for a y-up model (glTF, meshes) front is
//! +z, right +x and top +y. A direction points from the model's centre to the eye, so the
//! `front` view looks at the model's front face.

use glam::{DQuat, DVec3};

use super::View;
use crate::model::Sphere;

/// Default [`Framing::margin`]: the camera stands 2 % farther than the distance at which the
/// model's bounding sphere touches the nearer image edges.
pub const DEFAULT_MARGIN: f64 = 0.02;

/// A named viewing direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedView {
    Front,
    Back,
    Left,
    Right,
    Top,
    Bottom,
    /// Isometric: front, right and top equally.
    Iso,
}

impl NamedView {
    pub(crate) const ALL: [NamedView; 7] = [
        NamedView::Front,
        NamedView::Back,
        NamedView::Left,
        NamedView::Right,
        NamedView::Top,
        NamedView::Bottom,
        NamedView::Iso,
    ];

    pub fn name(self) -> &'static str {
        match self {
            NamedView::Front => "front",
            NamedView::Back => "back",
            NamedView::Left => "left",
            NamedView::Right => "right",
            NamedView::Top => "top",
            NamedView::Bottom => "bottom",
            NamedView::Iso => "iso",
        }
    }

    /// Unit direction from the model's centre towards the eye.
    pub fn direction(self, up: DVec3) -> DVec3 {
        let f = ModelFrame::of(up);
        match self {
            NamedView::Front => f.front,
            NamedView::Back => -f.front,
            NamedView::Left => -f.right,
            NamedView::Right => f.right,
            NamedView::Top => f.up,
            NamedView::Bottom => -f.up,
            NamedView::Iso => (f.front + f.right + f.up).normalize(),
        }
    }
}

impl std::str::FromStr for NamedView {
    type Err = String;

    fn from_str(s: &str) -> Result<NamedView, String> {
        NamedView::ALL
            .into_iter()
            .find(|v| v.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                let names: Vec<&str> = NamedView::ALL.iter().map(|v| v.name()).collect();
                format!("unknown view {s:?} (one of {})", names.join(", "))
            })
    }
}

/// The model's front, right and up unit vectors for its up axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ModelFrame {
    pub front: DVec3,
    pub right: DVec3,
    pub up: DVec3,
}

impl ModelFrame {
    pub fn of(up: DVec3) -> ModelFrame {
        let up = up.try_normalize().unwrap_or(DVec3::Y);
        // "Front" is towards the viewer: −Y for a z-up model, +Z for a y-up model.
        let front = if up.z.abs() > 0.9 {
            DVec3::NEG_Y
        } else {
            DVec3::Z
        };
        let front = (front - up * front.dot(up)).normalize();
        ModelFrame {
            front,
            right: front.cross(up).normalize() * -1.0,
            up,
        }
    }
}

/// Where the framing camera looks from and how much room it leaves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    /// Starting direction (centre → eye); `None`: the three-quarter view of
    /// [`super::pleasant_direction`].
    pub view: Option<NamedView>,
    /// Turn about the up axis, degrees; positive moves the eye towards the model's right.
    pub azimuth_deg: f64,
    /// Turn towards the up axis, degrees; positive moves the eye up (clamped to ±90°).
    pub elevation_deg: f64,
    /// The camera stands `1 + margin` times the distance at which the bounding sphere touches
    /// the nearer image edges (0: touching; negative crops); orthographic: the image is
    /// `1 + margin` times the size at which the sphere touches them.
    pub margin: f64,
    /// An orthographic projection ([`super::Projection::Orthographic`]) instead of a
    /// perspective one.
    pub ortho: bool,
}

impl Default for Framing {
    fn default() -> Framing {
        Framing {
            view: None,
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            margin: DEFAULT_MARGIN,
            ortho: false,
        }
    }
}

impl Framing {
    /// Unit direction from the centre to the eye for a model whose up axis is `up`.
    pub fn direction(&self, up: DVec3) -> DVec3 {
        let f = ModelFrame::of(up);
        let base = match self.view {
            Some(v) => v.direction(f.up),
            None => super::pleasant_direction(f.up),
        };
        if self.azimuth_deg == 0.0 && self.elevation_deg == 0.0 {
            return base;
        }
        // Azimuth: about up, counter-clockwise seen from above moves front towards right.
        let turned = DQuat::from_axis_angle(f.up, self.azimuth_deg.to_radians()) * base;
        if self.elevation_deg == 0.0 {
            return turned.normalize();
        }
        let height = turned.dot(f.up).clamp(-1.0, 1.0).asin();
        let horizontal = (turned - f.up * turned.dot(f.up))
            .try_normalize()
            // Looking straight along up: tilt towards the front.
            .unwrap_or(f.front);
        let limit = std::f64::consts::FRAC_PI_2;
        let e = (height + self.elevation_deg.to_radians()).clamp(-limit, limit);
        (horizontal * e.cos() + f.up * e.sin()).normalize()
    }

    /// The screen's up vector for a camera looking from `dir`: the model's up, or, looking
    /// along it (top and bottom views), the model's back (top) or front (bottom), so that the
    /// front stays at the bottom of a top view.
    pub(crate) fn screen_up(dir: DVec3, up: DVec3) -> DVec3 {
        let f = ModelFrame::of(up);
        if dir.cross(f.up).length() > 1e-6 {
            f.up
        } else if dir.dot(f.up) > 0.0 {
            -f.front
        } else {
            f.front
        }
    }
}

impl View {
    /// Frames `bounds` as `framing` asks (direction, margin) for a model whose up axis is
    /// `up`.
    pub fn framed(
        bounds: &Sphere,
        up: DVec3,
        framing: &Framing,
        fov_y: f64,
        size: (u32, u32),
    ) -> View {
        let dir = framing.direction(up);
        let screen_up = Framing::screen_up(dir, up);
        let v = View::framing_with_margin(bounds, screen_up, dir, fov_y, size, framing.margin);
        if !framing.ortho {
            return v;
        }
        // The sphere's diameter, times 1 + margin, fills the nearer image edges' span.
        let aspect = size.0.max(1) as f64 / size.1.max(1) as f64;
        let span = 2.0 * bounds.radius.max(1e-12) * (1.0 + framing.margin).max(1e-3);
        v.with_ortho_height(span / aspect.min(1.0), bounds)
    }

    /// Frames `bounds` looking from direction `dir` (centre → eye), the camera
    /// `1 + margin` times the distance at which the sphere touches the nearer image edges.
    pub(crate) fn framing_with_margin(
        bounds: &Sphere,
        up: DVec3,
        dir: DVec3,
        fov_y: f64,
        (width, height): (u32, u32),
        margin: f64,
    ) -> View {
        let aspect = width.max(1) as f64 / height.max(1) as f64;
        let fov_x = 2.0 * ((fov_y * 0.5).tan() * aspect).atan();
        let half = 0.5 * fov_y.min(fov_x);
        let radius = bounds.radius.max(1e-12);
        let dist = radius / half.sin() * (1.0 + margin).max(1e-3);
        let eye = bounds.center + dir.normalize() * dist;
        View::new(eye, bounds.center, up, fov_y, (width, height), bounds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Sphere {
        Sphere {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 2.0,
        }
    }

    /// The named views look at the faces they name, for both up conventions.
    #[test]
    fn named_views_follow_the_up_axis() {
        assert_eq!(NamedView::Front.direction(DVec3::Z), DVec3::NEG_Y);
        assert_eq!(NamedView::Right.direction(DVec3::Z), DVec3::X);
        assert_eq!(NamedView::Top.direction(DVec3::Z), DVec3::Z);
        assert_eq!(NamedView::Front.direction(DVec3::Y), DVec3::Z);
        assert_eq!(NamedView::Left.direction(DVec3::Y), DVec3::NEG_X);
        assert_eq!(NamedView::Bottom.direction(DVec3::Y), DVec3::NEG_Y);
        let iso = NamedView::Iso.direction(DVec3::Z);
        assert!((iso - DVec3::new(1.0, -1.0, 1.0).normalize()).length() < 1e-12);
        assert_eq!("TOP".parse::<NamedView>(), Ok(NamedView::Top));
        assert!(
            "diagonal"
                .parse::<NamedView>()
                .expect_err("no such view")
                .contains("iso")
        );
    }

    /// Azimuth 90° from the front is the right view; elevation 90° is the top view; the
    /// default (no view, no turns) is the three-quarter view.
    #[test]
    fn azimuth_and_elevation_turn_about_up() {
        let front = Framing {
            view: Some(NamedView::Front),
            ..Framing::default()
        };
        for up in [DVec3::Z, DVec3::Y] {
            let right = Framing {
                azimuth_deg: 90.0,
                ..front
            }
            .direction(up);
            assert!((right - NamedView::Right.direction(up)).length() < 1e-12);
            let top = Framing {
                elevation_deg: 90.0,
                ..front
            }
            .direction(up);
            assert!((top - up).length() < 1e-12, "{top}");
            let over = Framing {
                elevation_deg: 150.0,
                ..front
            }
            .direction(up);
            assert!((over - up).length() < 1e-12, "clamped: {over}");
            assert_eq!(
                Framing::default().direction(up),
                super::super::pleasant_direction(up)
            );
        }
    }

    /// The framed sphere touches the nearer image edges at margin 0, and the top view keeps
    /// the front at the bottom of the image.
    #[test]
    fn framing_fits_the_sphere_and_orients_top_views() {
        let s = unit();
        let fov = 40f64.to_radians();
        let framing = Framing {
            view: Some(NamedView::Top),
            margin: 0.0,
            ..Framing::default()
        };
        let v = View::framed(&s, DVec3::Z, &framing, fov, (800, 600));
        let d = v.eye.distance(s.center);
        assert!((s.radius / d - (fov * 0.5).sin()).abs() < 1e-12);
        // The model's front (−y) projects below its centre.
        let (_, y_front, _) = v.project(s.center + DVec3::NEG_Y).expect("in front");
        let (_, y_centre, _) = v.project(s.center).expect("in front");
        assert!(y_front > y_centre, "{y_front} vs {y_centre}");
        let wider = View::framed(
            &s,
            DVec3::Z,
            &Framing {
                margin: 0.5,
                ..framing
            },
            fov,
            (800, 600),
        );
        assert!((wider.eye.distance(s.center) - 1.5 * d).abs() < 1e-9);
    }

    /// Orthographic framing: the sphere's diameter fills the nearer image edges at margin
    /// 0, 1 + margin times that otherwise; the eye stands outside the sphere.
    #[test]
    fn orthographic_framing_fits_the_sphere() {
        let s = unit();
        let fov = 40f64.to_radians();
        for (size, margin) in [((800, 600), 0.0), ((600, 800), 0.0), ((800, 600), 0.5)] {
            let framing = Framing {
                view: Some(NamedView::Front),
                margin,
                ortho: true,
                ..Framing::default()
            };
            let v = View::framed(&s, DVec3::Z, &framing, fov, size);
            let super::super::Projection::Orthographic { height } = v.projection else {
                panic!("orthographic");
            };
            let width = height * v.aspect();
            assert!(
                (height.min(width) - 2.0 * s.radius * (1.0 + margin)).abs() < 1e-9,
                "{size:?}: {height} x {width}"
            );
            assert!(v.near > 0.0 && v.near < v.eye.distance(s.center) - s.radius);
            // Margin 0: the sphere's right (or top) point lands on the nearer edge.
            if margin == 0.0 {
                let edge = if size.0 < size.1 {
                    v.project(s.center + DVec3::X * s.radius)
                        .expect("projects")
                        .0
                } else {
                    v.project(s.center + DVec3::Z * s.radius)
                        .expect("projects")
                        .1
                };
                let want = if size.0 < size.1 { size.0 as f64 } else { 0.0 };
                assert!((edge - want).abs() < 1e-6, "{size:?}: {edge}");
            }
        }
    }
}
