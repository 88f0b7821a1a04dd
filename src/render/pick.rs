//! Picking: what a pixel of an image shows — the patch, and the point of it under the pixel.
//!
//! The patch comes from the ID buffer the renderer draws anyway (one sample at the pixel's
//! centre; a fat border counts for its patch), so a pick names exactly what the image shows
//! there, hidden surfaces and all resolved by the GPU's depth test. The point is then found
//! on the CPU: the ray through the pixel's centre cast against that patch's triangles (the
//! drawn tessellation, within the patch's ε of the true surface; the nearest hit); where the
//! ray misses them — the pixel shows the patch's fat border, beside its triangles — the point
//! is read back from the linear depth image instead (on the fat border, pushed back by at
//! most ε).

use glam::{DVec3, DVec4};
use thiserror::Error;

use super::{GpuMeshes, RenderError, RenderOptions, Renderer, Shading};
use crate::model::{PatchSurface, Scene};
use crate::tessellate::PatchMesh;
use crate::view::View;

/// What one pixel shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The patch's id (its index in the scene).
    pub patch: u32,
    /// The world point under the pixel's centre.
    pub point: DVec3,
    /// Whether `point` is on the patch's triangles (else read from the depth image: the
    /// pixel shows the patch's fat border).
    pub on_triangles: bool,
}

/// A picked patch in the model's words.
#[derive(Clone, Debug, PartialEq)]
pub struct Picked<'a> {
    /// The part's name (empty when the file names none).
    pub part: &'a str,
    /// The placed solid's occurrence path (`Instance::name`; empty when unnamed).
    pub instance: &'a str,
    /// The STEP / IGES entity id of the face, for a trimmed face.
    pub face: Option<u64>,
    /// The surface type: `plane`, `cylinder`, … (`model::trimmed::surface_kind`),
    /// `bezier 3x3`, `mesh`.
    pub surface: String,
}

/// What patch `patch` of `scene` is (`None`: no such patch).
pub fn describe(scene: &Scene, patch: u32) -> Option<Picked<'_>> {
    let p = scene.patches.get(patch as usize)?;
    let (face, surface) = match &p.surface {
        PatchSurface::Trimmed(f) => (
            Some(f.id),
            crate::model::trimmed::surface_kind(&f.surface).to_owned(),
        ),
        PatchSurface::Bezier(b) => {
            let (du, dv) = b.degree();
            (None, format!("bezier {du}x{dv}"))
        }
        PatchSurface::Mesh(_) => (None, "mesh".to_owned()),
    };
    Some(Picked {
        part: scene
            .parts
            .get(p.part as usize)
            .map_or("", |x| x.name.as_str()),
        instance: scene
            .instances
            .get(p.instance as usize)
            .map_or("", |x| x.name.as_str()),
        face,
        surface,
    })
}

impl Picked<'_> {
    /// One line for people: `part "nut" (assembly/nut_1), face #12 plane, patch 3, point
    /// (1.0000, 2.0000, 3.0000) mm`.
    pub fn line(&self, hit: &Hit, unit: &str) -> String {
        let p = hit.point;
        format!(
            "part {:?}{}, {}{}, patch {}, point ({:.4}, {:.4}, {:.4}) {unit}{}",
            self.part,
            match self.instance {
                "" => String::new(),
                i => format!(" ({i})"),
            },
            self.face.map_or(String::new(), |f| format!("face #{f} ")),
            self.surface,
            hit.patch,
            p.x,
            p.y,
            p.z,
            match hit.on_triangles {
                true => "",
                false => " (on its fat border)",
            },
        )
    }
}

#[derive(Debug, Error)]
pub enum PickError {
    #[error("pixel {x},{y} is outside the {width}x{height} image (0..{width}, 0..{height})")]
    OutOfImage {
        x: i64,
        y: i64,
        width: u32,
        height: u32,
    },
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// The ray through pixel position `(x, y)` (pixels, y down; a pixel's centre is at
/// `+ 0.5`): a point on it and its unit direction, away from the viewer.
pub(crate) fn pixel_ray(view: &View, x: f64, y: f64) -> (DVec3, DVec3) {
    let inverse = (view.proj_matrix() * view.view_matrix()).inverse();
    let ndc = (
        2.0 * x / view.width as f64 - 1.0,
        1.0 - 2.0 * y / view.height as f64,
    );
    let at = |z: f64| {
        let p: DVec4 = inverse * DVec4::new(ndc.0, ndc.1, z, 1.0);
        p.truncate() / p.w
    };
    let (a, b) = (at(0.0), at(0.5));
    (a, (b - a).normalize())
}

/// Nearest intersection parameter `t > 0` of the ray `origin + t · dir` with triangle `tri`
/// (Möller–Trumbore, both sides).
fn ray_triangle(origin: DVec3, dir: DVec3, tri: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() <= 1e-300 {
        return None;
    }
    let s = origin - tri[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// The nearest point where the ray hits `mesh`'s triangles (world space).
pub(crate) fn ray_cast(mesh: &PatchMesh, origin: DVec3, dir: DVec3) -> Option<DVec3> {
    let world = mesh.world();
    let m = world.as_ref();
    m.triangles
        .iter()
        .filter_map(|t| {
            let tri = t.map(|i| m.positions[i as usize].as_dvec3());
            ray_triangle(origin, dir, tri)
        })
        .min_by(|a, b| a.total_cmp(b))
        .map(|t| origin + dir * t)
}

/// What pixels `pixels` (column, row from the top left) of `geometry` drawn for `view` show:
/// `None` for the background. `meshes` are the patch meshes `geometry` was uploaded from.
pub fn pick(
    renderer: &mut Renderer,
    geometry: &GpuMeshes,
    meshes: &[PatchMesh],
    view: &View,
    pixels: &[(i64, i64)],
) -> Result<Vec<Option<Hit>>, PickError> {
    let (w, h) = (view.width, view.height);
    if let Some(&(x, y)) = pixels
        .iter()
        .find(|(x, y)| !(0..w as i64).contains(x) || !(0..h as i64).contains(y))
    {
        return Err(PickError::OutOfImage {
            x,
            y,
            width: w,
            height: h,
        });
    }
    let opts = RenderOptions {
        shading: Shading::Flat,
        msaa: 1,
        depth: true,
        ids: true,
        ..RenderOptions::default()
    };
    let frame = renderer.render(geometry, view, &opts)?;
    Ok(pixels
        .iter()
        .map(|&(x, y)| hit_at(&frame, view, meshes, x as u32, y as u32))
        .collect())
}

/// What pixel `(x, y)` of `frame` (drawn for `view` with its ID image, from `meshes`)
/// shows; `None` for the background, a pixel outside the image or a frame without IDs. The
/// point: on the patch's triangles; else from the frame's depth image when it has one; else
/// the patch's vertex nearest to the ray.
pub(crate) fn hit_at<'a>(
    frame: &super::Frame,
    view: &View,
    meshes: impl IntoIterator<Item = &'a PatchMesh>,
    x: u32,
    y: u32,
) -> Option<Hit> {
    if x >= frame.width || y >= frame.height {
        return None;
    }
    let k = y as usize * frame.width as usize + x as usize;
    let patch = frame.ids.as_ref()?.get(k)?.checked_sub(1)?;
    let (origin, dir) = pixel_ray(view, x as f64 + 0.5, y as f64 + 0.5);
    let mesh = meshes.into_iter().find(|m| m.patch_id == patch)?;
    if let Some(point) = ray_cast(mesh, origin, dir) {
        return Some(Hit {
            patch,
            point,
            on_triangles: true,
        });
    }
    let point = match frame.depth.as_ref().and_then(|d| d.get(k)) {
        // The linear depth along the viewing axis, back on the ray.
        Some(&d) if d.is_finite() => {
            origin + dir * ((d as f64 - view.view_depth(origin)) / dir.dot(view.forward()))
        }
        _ => {
            let world = mesh.world();
            let off = |p: DVec3| (p - origin).cross(dir).length();
            world
                .positions
                .iter()
                .map(|p| p.as_dvec3())
                .min_by(|a, b| off(*a).total_cmp(&off(*b)))?
        }
    };
    Some(Hit {
        patch,
        point,
        on_triangles: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Sphere;

    #[test]
    fn a_pixel_ray_runs_through_what_projects_there() {
        let bounds = Sphere {
            center: DVec3::ZERO,
            radius: 2.0,
        };
        let persp = View::new(
            DVec3::new(5.0, -4.0, 3.0),
            DVec3::ZERO,
            DVec3::Z,
            0.8,
            (320, 200),
            &bounds,
        );
        for view in [persp, persp.orthographic(&bounds)] {
            for p in [
                DVec3::ZERO,
                DVec3::new(0.7, -0.3, 1.1),
                DVec3::new(-1.0, 1.0, 0.5),
            ] {
                let (x, y, _) = view.project(p).expect("in front");
                let (o, d) = pixel_ray(&view, x, y);
                let off = (p - o) - d * (p - o).dot(d);
                assert!(off.length() < 1e-9, "{p:?}: {off:?}");
                assert!((p - o).dot(d) > 0.0, "away from the viewer");
            }
        }
    }

    #[test]
    fn rays_hit_triangles_inside_and_miss_outside() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let down = DVec3::new(0.0, 0.0, -1.0);
        let t = ray_triangle(DVec3::new(0.25, 0.25, 2.0), down, tri);
        assert_eq!(t, Some(2.0));
        assert_eq!(ray_triangle(DVec3::new(0.75, 0.75, 2.0), down, tri), None);
        assert_eq!(ray_triangle(DVec3::new(0.25, 0.25, -2.0), down, tri), None);
    }
}
