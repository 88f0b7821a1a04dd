//! CPU overlays drawn onto a frame before it is presented (wireframe with a depth test).

use super::*;

/// Draws the visible edges of `meshes` onto `frame` (dark grey): an edge pixel is drawn where
/// its depth is within 0.5 % of the depth buffer's (hidden edges stay hidden).
pub fn draw_wireframe<'a>(
    frame: &mut Frame,
    view: &View,
    meshes: impl IntoIterator<Item = &'a PatchMesh>,
) {
    let Some(depth) = frame.depth.clone() else {
        return;
    };
    let (w, h) = (frame.width as usize, frame.height as usize);
    for m in meshes {
        let world = m.world();
        let m = world.as_ref();
        let projected: Vec<Option<(f64, f64, f64)>> = m
            .positions
            .iter()
            .map(|p| view.project(p.as_dvec3()))
            .collect();
        for t in &m.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                // Each interior edge is listed twice; draw it once.
                if a > b && m.triangles.len() > 1 {
                    continue;
                }
                let (Some(pa), Some(pb)) = (projected[a as usize], projected[b as usize]) else {
                    continue;
                };
                let steps = ((pb.0 - pa.0).abs().max((pb.1 - pa.1).abs()).ceil() as usize).max(1);
                if steps > 4 * (w + h) {
                    continue;
                }
                for s in 0..=steps {
                    let f = s as f64 / steps as f64;
                    let (x, y) = (pa.0 + (pb.0 - pa.0) * f, pa.1 + (pb.1 - pa.1) * f);
                    if x < 0.0 || y < 0.0 || x as usize >= w || y as usize >= h {
                        continue;
                    }
                    let i = y as usize * w + x as usize;
                    let d = pa.2 + (pb.2 - pa.2) * f;
                    if (d as f32) <= depth[i] * 1.005 {
                        frame.color[4 * i..4 * i + 3].copy_from_slice(&[40, 40, 40]);
                    }
                }
            }
        }
    }
}
