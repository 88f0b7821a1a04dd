//! Section planes: up to three planes that cut the model open, and the caps that close the cut.
//!
//! **Clipping.** A plane is a point P and a normal N; the half-space N points into,
//! {p : N·(p − P) > 0}, is removed, so what is kept is the intersection of the planes' back
//! half-spaces. The fragment shaders (`fs_color`, `fs_depth`, `fs_id` in `shaders/scene.wgsl`)
//! discard every fragment whose drawn position lies in a removed half-space — surfaces and fat
//! borders alike, so no fat border sticks out of the cut.
//!
//! **Capping** (the idea of Rossignac, Megahed and Schneider, "Interactive inspection of
//! solids: cross-sections and interferences", SIGGRAPH 1992, §3: a pixel whose ray enters the
//! solid through the cutting plane sees the cap). We test it with the surface's outward
//! normal rather than with a stencil parity count: where the nearest kept fragment of a closed
//! solid faces away from the viewer (n·v < 0 for its outward normal n), the viewer looks into
//! the solid through the cut, and the pixel shows the cap. Its colour is the part's, shaded
//! with the normal of the plane the ray entered through (flat: one normal per plane), and its
//! linear depth (`fs_depth`) is where the ray meets that plane (`Sections::cap_point` is the
//! CPU twin). The hardware depth stays the back face's own, so visibility between parts is
//! decided by real surfaces and a back face hidden behind a front face never claims the cap.
//! So edges (`render::edges`) on back faces would show through a cap; with planes in use,
//! `fs_edge` hides those drawn from a patch facing away from the viewer.
//!
//! Why not stencil parity: it counts every surface crossing along the ray, so a crack in the
//! independently tessellated patches flips the parity and speckles the cap, and fat borders
//! (which overlap the surfaces) cannot take part in the count. The normal test needs neither a
//! watertight mesh nor a second pass; fat borders carry their border vertex's normal, so the
//! fat borders of inner back faces are caps too and leave no speckles.
//!
//! **What it needs.** Outward normals: STEP faces get them from the face's sense
//! (`ADVANCED_FACE.same_sense`, [`crate::model::trimmed::TrimmedFace::domain_left`], applied by
//! the trimmed tessellator); meshes use the normals their file gives. Open shells and
//! inconsistently oriented meshes show the cap colour wherever their inside shows. Near a
//! contour (n·v ≈ 0) the test follows the interpolated normal.

use glam::DVec3;
use thiserror::Error;

/// Why a section plane was refused.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SectionError {
    /// Not six comma-separated numbers.
    #[error("{value:?}: {reason} (expected X,Y,Z,NX,NY,NZ)")]
    Parse { value: String, reason: String },
    /// A coordinate that is NaN or infinite.
    #[error("{value:?}: every number must be finite")]
    NotFinite { value: String },
    /// A normal of length zero (or too short to normalise).
    #[error("{value:?}: the normal NX,NY,NZ must not be zero")]
    ZeroNormal { value: String },
    /// More planes than [`Sections::MAX`].
    #[error("at most {max} planes, got {count}", max = Sections::MAX)]
    TooMany { count: usize },
}

/// One section plane: the half-space `normal` points into, seen from `point`, is removed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionPlane {
    pub point: DVec3,
    /// Unit length.
    pub normal: DVec3,
}

impl SectionPlane {
    /// A plane through `point` with normal `normal` (normalised); refused when a number is
    /// not finite or the normal is zero. `what` names the plane in the error.
    pub fn new(point: DVec3, normal: DVec3, what: &str) -> Result<Self, SectionError> {
        if !(point.is_finite() && normal.is_finite()) {
            return Err(SectionError::NotFinite { value: what.into() });
        }
        let normal = normal
            .try_normalize()
            .ok_or_else(|| SectionError::ZeroNormal { value: what.into() })?;
        Ok(SectionPlane { point, normal })
    }

    /// Signed distance of `p` from the plane, positive on the removed side.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p - self.point)
    }
}

impl std::str::FromStr for SectionPlane {
    type Err = SectionError;
    /// `X,Y,Z,NX,NY,NZ`.
    fn from_str(s: &str) -> Result<Self, SectionError> {
        let parse = |reason: String| SectionError::Parse {
            value: s.into(),
            reason,
        };
        let v = s
            .split(',')
            .map(|x| {
                x.trim()
                    .parse::<f64>()
                    .map_err(|_| parse(format!("{:?} is not a number", x.trim())))
            })
            .collect::<Result<Vec<f64>, _>>()?;
        if v.len() != 6 {
            return Err(parse(format!("{} numbers", v.len())));
        }
        SectionPlane::new(
            DVec3::new(v[0], v[1], v[2]),
            DVec3::new(v[3], v[4], v[5]),
            s,
        )
    }
}

/// The section planes of a render (none by default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sections {
    planes: [Option<SectionPlane>; Sections::MAX],
}

impl Sections {
    /// Most planes at once (the size of the shader's uniform array).
    pub const MAX: usize = 3;

    /// No plane: nothing clipped, nothing capped.
    pub const NONE: Sections = Sections {
        planes: [None; Sections::MAX],
    };

    /// At most [`Sections::MAX`] planes.
    pub fn new(planes: &[SectionPlane]) -> Result<Self, SectionError> {
        if planes.len() > Self::MAX {
            return Err(SectionError::TooMany {
                count: planes.len(),
            });
        }
        let mut s = Sections::NONE;
        for (slot, p) in s.planes.iter_mut().zip(planes) {
            *slot = Some(*p);
        }
        Ok(s)
    }

    pub fn planes(&self) -> impl Iterator<Item = &SectionPlane> {
        self.planes.iter().flatten()
    }

    pub fn len(&self) -> usize {
        self.planes().count()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether `p` lies in a removed half-space (the shaders' `section_removes`).
    pub fn removes(&self, p: DVec3) -> bool {
        self.planes().any(|s| s.distance(p) > 0.0)
    }

    /// The plane records of the shader's globals: (N, −N·P) per plane, unused ones zero.
    pub fn gpu(&self) -> [[f32; 4]; Sections::MAX] {
        let mut out = [[0.0; 4]; Sections::MAX];
        for (o, p) in out.iter_mut().zip(self.planes()) {
            let n = p.normal;
            *o = [n.x as f32, n.y as f32, n.z as f32, -n.dot(p.point) as f32];
        }
        out
    }

    /// CPU twin of the shader's `section_cap`: where the ray towards a kept point `at`
    /// (direction `dir`, from the viewer: the eye at `at − dir` under a perspective, from
    /// infinitely far under an orthographic projection) last entered the kept region through a
    /// plane, and that plane's index; `None` when it entered through none.
    #[cfg(test)]
    pub(crate) fn cap_point(
        &self,
        at: DVec3,
        dir: DVec3,
        perspective: bool,
    ) -> Option<(DVec3, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in self.planes.iter().enumerate() {
            let Some(p) = p else { continue };
            let nd = p.normal.dot(dir);
            if nd >= 0.0 {
                continue; // the ray leaves this half-space or runs along the plane
            }
            // at + s·dir on the plane; s ≤ 0 since `at` is kept.
            let s = -p.distance(at) / nd;
            if perspective && s <= -1.0 {
                continue; // the eye itself is on the kept side of this plane
            }
            if best.is_none_or(|(b, _)| s > b) {
                best = Some((s, i));
            }
        }
        best.map(|(s, i)| (at + dir * s, i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(s: &str) -> SectionPlane {
        s.parse().expect("a valid plane")
    }

    #[test]
    fn parses_six_numbers_and_normalises() {
        let p = plane("1, 2, 3, 0, 0, 2");
        assert_eq!(p.point, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(p.normal, DVec3::Z);
    }

    #[test]
    fn refuses_zero_normals_nan_and_short_lists() {
        assert!(matches!(
            "0,0,0,0,0,0".parse::<SectionPlane>(),
            Err(SectionError::ZeroNormal { .. })
        ));
        assert!(matches!(
            "0,0,NaN,0,0,1".parse::<SectionPlane>(),
            Err(SectionError::NotFinite { .. })
        ));
        assert!(matches!(
            "0,0,0,0,1".parse::<SectionPlane>(),
            Err(SectionError::Parse { .. })
        ));
        assert!(matches!(
            "0,0,x,0,0,1".parse::<SectionPlane>(),
            Err(SectionError::Parse { .. })
        ));
    }

    #[test]
    fn at_most_three_planes() {
        let p = plane("0,0,0,1,0,0");
        assert_eq!(Sections::new(&[p; 3]).map(|s| s.len()), Ok(3));
        assert_eq!(
            Sections::new(&[p; 4]),
            Err(SectionError::TooMany { count: 4 })
        );
    }

    #[test]
    fn removes_the_side_the_normal_points_into() {
        let s = Sections::new(&[plane("0,0,0,1,0,0"), plane("0,0,0,0,1,0")]).expect("2 planes");
        assert!(s.removes(DVec3::new(1.0, -1.0, 0.0)));
        assert!(s.removes(DVec3::new(-1.0, 1.0, 0.0)));
        assert!(!s.removes(DVec3::new(-1.0, -1.0, 5.0)));
        assert_eq!(s.gpu()[0], [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(s.gpu()[2], [0.0; 4]);
    }

    #[test]
    fn cap_point_is_where_the_ray_entered_last() {
        // Two planes x ≤ 0 and y ≤ 0 kept; eye at (5, 1, 0) looking at (-1, -1, 0): it
        // crosses y = 0 at x = 2 (still removed by x) and x = 0 at y = -2/3: the entry.
        let s = Sections::new(&[plane("0,0,0,1,0,0"), plane("0,0,0,0,1,0")]).expect("2 planes");
        let eye = DVec3::new(5.0, 1.0, 0.0);
        let at = DVec3::new(-1.0, -1.0, 0.0);
        let (p, i) = s.cap_point(at, at - eye, true).expect("entered");
        assert_eq!(i, 0);
        assert!((p - DVec3::new(0.0, -2.0 / 3.0, 0.0)).length() < 1e-12);
        // An eye already on the kept side of both planes entered through none.
        let eye = DVec3::new(-3.0, -3.0, 0.0);
        assert_eq!(s.cap_point(at, at - eye, true), None);
        // Orthographic: the same direction from infinitely far.
        let (p, i) = s
            .cap_point(at, DVec3::new(-1.0, 0.0, 0.0), false)
            .expect("entered");
        assert_eq!((p, i), (DVec3::new(0.0, -1.0, 0.0), 0));
    }
}
