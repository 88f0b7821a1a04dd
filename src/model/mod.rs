//! The scene: patches to draw, read-only after loading.
//!
//! Data flows one way: `io` builds a [`Scene`], `tessellate` turns each [`Patch`] into a
//! [`crate::tessellate::PatchMesh`] for a view, `render` draws those.

pub mod bezier;

pub use bezier::{BezierPatch, MAX_DEGREE};

use glam::DVec3;

/// A bounding sphere (centre, radius), in object units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: DVec3,
    pub radius: f64,
}

/// Axis-aligned bounds of `points`, `None` when empty.
fn box_of(points: impl IntoIterator<Item = DVec3>) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    lo.is_finite().then_some((lo, hi))
}

impl Sphere {
    const EMPTY: Sphere = Sphere {
        center: DVec3::ZERO,
        radius: 0.0,
    };

    /// Sphere around `points`: centre of their bounding box, radius the farthest point.
    /// A zero sphere at the origin for no points.
    pub fn around(points: impl IntoIterator<Item = DVec3> + Clone) -> Sphere {
        let Some((lo, hi)) = box_of(points.clone()) else {
            return Sphere::EMPTY;
        };
        let center = (lo + hi) * 0.5;
        let radius = points
            .into_iter()
            .map(|p| p.distance(center))
            .fold(0.0, f64::max);
        Sphere { center, radius }
    }

    /// Union of spheres (conservative: centre of their boxes, farthest reach).
    pub fn union(spheres: &[Sphere]) -> Sphere {
        let corners = spheres.iter().flat_map(|s| {
            [
                s.center - DVec3::splat(s.radius),
                s.center + DVec3::splat(s.radius),
            ]
        });
        let Some((lo, hi)) = box_of(corners) else {
            return Sphere::EMPTY;
        };
        let center = (lo + hi) * 0.5;
        let radius = spheres
            .iter()
            .map(|s| s.center.distance(center) + s.radius)
            .fold(0.0, f64::max);
        Sphere { center, radius }
    }
}

/// One independently tessellated surface piece.
#[derive(Clone, Debug)]
pub struct Patch {
    /// Index of the patch in its scene (also its colour in `ids` shading).
    pub id: u32,
    pub surface: BezierPatch,
    pub bounds: Sphere,
}

/// Which world axis points up in a model's own convention.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpAxis {
    Y,
    Z,
}

impl UpAxis {
    pub fn vector(self) -> DVec3 {
        match self {
            UpAxis::Y => DVec3::Y,
            UpAxis::Z => DVec3::Z,
        }
    }
}

/// A loaded model: its patches and what we know of its conventions.
#[derive(Clone, Debug)]
pub struct Scene {
    pub patches: Vec<Patch>,
    /// Up axis by the file format's convention (used by the default camera).
    pub up: UpAxis,
    pub bounds: Sphere,
}

impl Scene {
    /// Builds a scene from Bézier surfaces, numbering the patches in order.
    pub fn from_bezier(surfaces: Vec<BezierPatch>, up: UpAxis) -> Scene {
        let patches: Vec<Patch> = surfaces
            .into_iter()
            .enumerate()
            .map(|(i, surface)| Patch {
                id: i as u32,
                bounds: surface.bounding_sphere(),
                surface,
            })
            .collect();
        let spheres: Vec<Sphere> = patches.iter().map(|p| p.bounds).collect();
        Scene {
            bounds: Sphere::union(&spheres),
            patches,
            up,
        }
    }
}
