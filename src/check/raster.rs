//! A CPU z-buffer rasterizer of patch IDs: an ID reference that shares no code with the GPU
//! path (no wgpu, no WGSL, f64 throughout), for checking the renderer's ID images.
//!
//! Triangles are projected with the view's own matrices (`View::view_matrix`,
//! `View::proj_matrix`), pixel (0, 0) top-left, sampled at pixel centres (half-integers),
//! depth = NDC z interpolated linearly in screen space, nearest wins. Triangles with a vertex
//! at or behind the eye plane are skipped (no clipping: the views frame the whole model, whose
//! bounding sphere lies beyond the near plane). Ties on shared edges are decided by "≥ 0"
//! rather than the GPU's top-left rule, so edge pixels may differ from a GPU image by one
//! pixel; compare away from ID boundaries (`boundary_distance`).

use glam::{DVec3, DVec4};

use super::golden::IdImage;
use crate::tessellate::PatchMesh;
use crate::view::View;

/// Patch ID + 1 per pixel of `meshes` seen from `view` (0 where nothing is).
pub fn id_image(meshes: &[PatchMesh], view: &View) -> IdImage {
    let (w, h) = (view.width as usize, view.height as usize);
    let mut ids = vec![0u32; w * h];
    let mut depth = vec![f64::INFINITY; w * h];
    let m = view.proj_matrix() * view.view_matrix();
    for mesh in meshes {
        let screen: Vec<Option<DVec3>> = mesh
            .positions
            .iter()
            .map(|p| {
                let c = m * DVec4::new(p.x as f64, p.y as f64, p.z as f64, 1.0);
                (c.w > 1e-12).then(|| {
                    let ndc = c.truncate() / c.w;
                    DVec3::new(
                        (ndc.x * 0.5 + 0.5) * w as f64,
                        (0.5 - ndc.y * 0.5) * h as f64,
                        ndc.z,
                    )
                })
            })
            .collect();
        for t in &mesh.triangles {
            let (Some(a), Some(b), Some(c)) = (
                screen.get(t[0] as usize).copied().flatten(),
                screen.get(t[1] as usize).copied().flatten(),
                screen.get(t[2] as usize).copied().flatten(),
            ) else {
                continue;
            };
            let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = (a.x.min(b.x).min(c.x) - 0.5).ceil().max(0.0) as usize;
            let y0 = (a.y.min(b.y).min(c.y) - 0.5).ceil().max(0.0) as usize;
            let x1 = (a.x.max(b.x).max(c.x) - 0.5).floor().min(w as f64 - 1.0);
            let y1 = (a.y.max(b.y).max(c.y) - 0.5).floor().min(h as f64 - 1.0);
            if x1 < 0.0 || y1 < 0.0 {
                continue;
            }
            let edge = |p: DVec3, q: DVec3, x: f64, y: f64| {
                ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) / area
            };
            for y in y0..=y1 as usize {
                for x in x0..=x1 as usize {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let (wa, wb, wc) = (edge(b, c, px, py), edge(c, a, px, py), edge(a, b, px, py));
                    if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                        continue;
                    }
                    let z = wa * a.z + wb * b.z + wc * c.z;
                    let k = y * w + x;
                    if z < depth[k] {
                        depth[k] = z;
                        ids[k] = mesh.patch_id + 1;
                    }
                }
            }
        }
    }
    IdImage {
        width: view.width,
        height: view.height,
        ids,
    }
}

/// Chebyshev distance (px) of every pixel to the nearest pixel whose ID differs from its
/// own (background included), capped at `cap`.
pub(crate) fn boundary_distance(img: &IdImage, cap: u32) -> Vec<u32> {
    let (w, h) = (img.width as usize, img.height as usize);
    let mut d = vec![cap; w * h];
    for y in 0..h {
        for x in 0..w {
            let id = img.ids[y * w + x];
            let r = cap as usize;
            'search: for dist in 1..=r {
                for yy in y.saturating_sub(dist)..=(y + dist).min(h - 1) {
                    for xx in x.saturating_sub(dist)..=(x + dist).min(w - 1) {
                        if img.ids[yy * w + xx] != id {
                            d[y * w + x] = dist as u32;
                            break 'search;
                        }
                    }
                }
            }
        }
    }
    d
}

/// Pixels at least `band` px from every ID boundary of `reference` whose ID differs in
/// `actual`.
pub fn differing_away_from_boundaries(reference: &IdImage, actual: &IdImage, band: u32) -> usize {
    let d = boundary_distance(reference, band + 1);
    reference
        .ids
        .iter()
        .zip(&actual.ids)
        .zip(&d)
        .filter(|((r, a), d)| **d > band && r != a)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A unit square facing the camera, and a smaller one in front of it.
    #[test]
    fn nearer_triangles_win_and_pixels_are_centred() {
        let quad = |id: u32, s: f32, z: f32| PatchMesh {
            patch_id: id,
            positions: vec![
                Vec3::new(-s, -s, z),
                Vec3::new(s, -s, z),
                Vec3::new(s, s, z),
                Vec3::new(-s, s, z),
            ],
            normals: vec![Vec3::Z; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..PatchMesh::default()
        };
        let bounds = crate::model::Sphere {
            center: DVec3::ZERO,
            radius: 2.0,
        };
        let view = View::new(
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::ZERO,
            DVec3::Y,
            40f64.to_radians(),
            (64, 48),
            &bounds,
        );
        let img = id_image(&[quad(0, 1.0, 0.0), quad(7, 0.3, 0.5)], &view);
        let f = img.footprints();
        let (big, small) = (f[1].expect("big square"), f[8].expect("small square"));
        assert!((big.centroid[0] - 32.0).abs() < 0.5 && (big.centroid[1] - 24.0).abs() < 0.5);
        assert!((small.centroid[0] - 32.0).abs() < 0.5, "{small:?}");
        assert_eq!(img.ids[24 * 64 + 32], 8);
        assert_eq!(img.ids[0], 0);
        // Drawn in the other order, the nearer square still wins.
        let swapped = id_image(&[quad(7, 0.3, 0.5), quad(0, 1.0, 0.0)], &view);
        assert_eq!(swapped, img);
        let d = boundary_distance(&img, 3);
        assert_eq!(d[0], 3);
        assert_eq!(differing_away_from_boundaries(&img, &swapped, 1), 0);
    }
}
