//! The scene: patches to draw, read-only after loading.
//!
//! Data flows one way: `io` builds a [`Scene`], `tessellate` turns each [`Patch`] into a
//! [`crate::tessellate::PatchMesh`] for a view, `render` draws those.

pub mod analytic;
pub mod bezier;
pub mod creases;
pub mod edges;
pub mod knots;
pub mod memory;
pub mod merge;
pub mod mesh;
pub mod nurbs;
pub mod poles;
pub(crate) mod seam;
pub mod select;
pub mod trimmed;

use std::sync::Arc;

pub use bezier::BezierPatch;
pub use trimmed::TrimmedFace;

use glam::{DMat4, DVec3};

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
    pub(crate) const EMPTY: Sphere = Sphere {
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

/// The surface of a patch.
#[derive(Clone, Debug)]
pub enum PatchSurface {
    Bezier(BezierPatch),
    /// A trimmed face, shared by every placed instance of its part.
    Trimmed(Arc<TrimmedFace>),
    /// A patch of a triangle mesh (world coordinates).
    Mesh(Arc<mesh::MeshPatch>),
}

/// One independently tessellated surface piece.
#[derive(Clone, Debug)]
pub struct Patch {
    /// Index of the patch in its scene (also its colour in `ids` shading).
    pub id: u32,
    pub surface: PatchSurface,
    /// Placement of the surface in the scene (object → world); identity outside assemblies.
    pub transform: DMat4,
    /// Bounds in world coordinates.
    pub bounds: Sphere,
    /// Index into [`Scene::parts`].
    pub part: u32,
    /// Colour from the file (sRGB 0–1, the space it is drawn in: a glTF file's linear base
    /// colour is converted on reading), when it has one.
    pub color: Option<[f32; 3]>,
    /// Index into [`Scene::instances`]: the placed solid or shell the patch belongs to.
    pub instance: u32,
}

impl Patch {
    /// How much the placement scales lengths (1 for rigid placements).
    pub fn scale(&self) -> f64 {
        transform_scale(&self.transform)
    }
}

/// Largest factor by which `m` stretches a length.
pub(crate) fn transform_scale(m: &DMat4) -> f64 {
    m.x_axis
        .truncate()
        .length()
        .max(m.y_axis.truncate().length())
        .max(m.z_axis.truncate().length())
}

/// A face the reader could not use, and why (the rest of the file is still drawn).
#[derive(Clone, Debug, PartialEq)]
pub struct SkippedFace {
    /// STEP entity id of the face.
    pub face: u64,
    pub reason: String,
}

/// A named part (a product of an assembly, or the whole model).
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub name: String,
}

/// One placement of a part's solid or shell: the unit an assembly tree lists and CAD kernels
/// count (OCCT's placed solids).
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Occurrence names along the assembly path, joined by `/` (empty when unnamed).
    pub name: String,
    /// Index into [`Scene::parts`].
    pub part: u32,
    /// Object → world, in scene units (millimetres for STEP).
    pub transform: DMat4,
    /// The STEP shell entity, when read from STEP.
    pub shell: Option<u64>,
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
    /// Axis-aligned box of the model (world), `(min, max)`.
    pub bbox: (DVec3, DVec3),
    pub parts: Vec<Part>,
    /// Placed solids / shells (one per placement of a part's shell), what CAD kernels count
    /// as the assembly's instances; one for a Bézier or mesh scene.
    pub instances: Vec<Instance>,
    /// Faces left out, with the reason.
    pub skipped: Vec<SkippedFace>,
    /// What the reader wants the user to know (unsupported entities, repairs).
    pub warnings: Vec<String>,
    /// The length unit of the coordinates when the format states one (`"mm"`: STEP, scaled
    /// to millimetres; `"m"`: glTF); `None` when it does not (`.bpt`, OBJ, PLY, STL).
    pub unit: Option<&'static str>,
    /// Coarse groups of a mesh's patches ([`mesh::MeshGroup`], members before their groups);
    /// empty for other scenes and after patches are renumbered (selection, merging).
    pub mesh_groups: Vec<mesh::MeshGroup>,
}

impl Scene {
    /// Builds a scene from Bézier surfaces, numbering the patches in order.
    /// Sides that another patch repeats are classified as smooth or sharp edges
    /// (`edges::bezier_sides`).
    pub fn from_bezier(surfaces: Vec<BezierPatch>, up: UpAxis) -> Scene {
        let sides = edges::bezier_sides(&surfaces);
        let surfaces: Vec<BezierPatch> = surfaces
            .into_iter()
            .zip(sides)
            .map(|(s, k)| s.with_sides(k))
            .collect();
        let bbox = box_of(
            surfaces
                .iter()
                .flat_map(|s| s.control_points().iter().copied()),
        )
        .unwrap_or_default();
        let patches: Vec<Patch> = surfaces
            .into_iter()
            .enumerate()
            .map(|(i, surface)| Patch {
                id: i as u32,
                bounds: surface.bounding_sphere(),
                surface: PatchSurface::Bezier(surface),
                transform: DMat4::IDENTITY,
                part: 0,
                color: None,
                instance: 0,
            })
            .collect();
        Scene::single_part(patches, up, bbox, Vec::new())
    }

    /// A scene of one unnamed part, its bounds from the patches'.
    pub(crate) fn single_part(
        patches: Vec<Patch>,
        up: UpAxis,
        bbox: (DVec3, DVec3),
        warnings: Vec<String>,
    ) -> Scene {
        let spheres: Vec<Sphere> = patches.iter().map(|p| p.bounds).collect();
        Scene {
            bounds: Sphere::union(&spheres),
            patches,
            up,
            bbox,
            parts: vec![Part {
                name: String::new(),
            }],
            instances: vec![Instance {
                name: String::new(),
                part: 0,
                transform: DMat4::IDENTITY,
                shell: None,
            }],
            skipped: Vec::new(),
            warnings,
            unit: None,
            mesh_groups: Vec::new(),
        }
    }

    /// Length of the diagonal of [`Scene::bbox`].
    pub fn bbox_diagonal(&self) -> f64 {
        self.bbox.0.distance(self.bbox.1)
    }

    /// The mesh units to draw when `eps(unit)` is the error wanted for each
    /// ([`crate::mt::group::select`] over [`Scene::mesh_groups`]): every patch exactly once,
    /// by itself or by one group holding it; a group where its cut has no more triangles
    /// than its members would draw. Without groups: every patch.
    pub fn mesh_units(
        &self,
        eps: &mut dyn FnMut(crate::mt::group::Unit) -> f64,
    ) -> Vec<crate::mt::group::Unit> {
        use crate::mt::group::{self, Unit};
        let links: Vec<group::GroupLinks> =
            self.mesh_groups.iter().map(|g| g.links.clone()).collect();
        let roots = group::roots(&links, self.patches.len());
        let mut count = |u: Unit, e: f64| {
            let hierarchy = match u {
                Unit::Patch(p) => match &self.patches[p as usize].surface {
                    PatchSurface::Mesh(m) => &m.hierarchy,
                    // Groups hold mesh patches only.
                    _ => return usize::MAX,
                },
                Unit::Group(g) => &self.mesh_groups[g as usize].patch.hierarchy,
            };
            group::cut_len(hierarchy, e)
        };
        let mut out = Vec::with_capacity(roots.len());
        group::select(&links, &roots, eps, &mut count, &mut out);
        out
    }

    /// Group `g` of [`Scene::mesh_groups`] as a patch to tessellate: its first patch's part,
    /// colour and instance, the group's surface and bounds, id `patches.len() + g`.
    pub fn mesh_group_patch(&self, g: usize) -> Patch {
        let group = &self.mesh_groups[g];
        let mut first = group.links.members[0];
        while let crate::mt::group::Unit::Group(h) = first {
            first = self.mesh_groups[h as usize].links.members[0];
        }
        let crate::mt::group::Unit::Patch(p) = first else {
            unreachable!("the loop ends on a patch")
        };
        Patch {
            id: (self.patches.len() + g) as u32,
            bounds: group.bounds,
            surface: PatchSurface::Mesh(group.patch.clone()),
            ..self.patches[p as usize].clone()
        }
    }
}

/// Axis-aligned box around `points`, `None` when there are none.
pub fn bounding_box(points: impl IntoIterator<Item = DVec3>) -> Option<(DVec3, DVec3)> {
    box_of(points)
}
