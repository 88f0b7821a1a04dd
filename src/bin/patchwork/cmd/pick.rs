//! `stats --pick X,Y`: what pixels of `render`'s image show (`patchwork::render::pick`: the
//! ID buffer names the patch, a ray cast against its triangles gives the point), and the
//! distance between consecutive picks.

use serde_json::{Value, json};

use patchwork::model::Scene;
use patchwork::render::Renderer;
use patchwork::render::pick::{Hit, describe, pick};
use patchwork::tessellate::PatchMesh;
use patchwork::view::View;

use crate::error::CliError;
use crate::out::{data, note};

/// `X,Y`: a pixel's column and row from the top left (checked against the image later, so
/// that a pixel outside it is a typed error naming the image's size).
pub fn parse_pixel(s: &str) -> Result<(i64, i64), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("expected X,Y (pixels), got {s:?}"))?;
    let n = |v: &str, what: &str| {
        v.trim()
            .parse::<i64>()
            .map_err(|_| format!("bad {what} in {s:?} (whole pixels)"))
    };
    Ok((n(x, "column")?, n(y, "row")?))
}

/// Picks `pixels` of the image `render` draws of `meshes` (tessellated for `view`), prints
/// each pick and the distance from the one before, and returns them as JSON.
pub fn run(
    scene: &Scene,
    meshes: &[PatchMesh],
    view: &View,
    pixels: &[(i64, i64)],
) -> Result<Value, CliError> {
    let mut renderer = Renderer::new()?;
    note!("adapter: {}", renderer.gpu().describe());
    let gpu = renderer.upload(meshes);
    let hits = pick(&mut renderer, &gpu, meshes, view, pixels)?;
    let mut out = Vec::new();
    let mut last: Option<Hit> = None;
    for (&(x, y), hit) in pixels.iter().zip(&hits) {
        let distance = match (last, hit) {
            (Some(a), Some(b)) => Some(a.point.distance(b.point)),
            _ => None,
        };
        let unit = scene.unit.unwrap_or("units");
        match hit.and_then(|h| Some((h, describe(scene, h.patch)?))) {
            Some((h, d)) => {
                let p = h.point;
                data!("{:<18}{}", format!("pick {x},{y}"), d.line(&h, unit));
                out.push(json!({
                    "x": x, "y": y,
                    "hit": {
                        "patch": h.patch,
                        "part": d.part,
                        "instance": d.instance,
                        "face": d.face,
                        "surface": d.surface,
                        "point": [p.x, p.y, p.z],
                        "on_triangles": h.on_triangles,
                    },
                    "distance_from_previous": distance,
                }));
            }
            None => {
                data!(
                    "{:<18}nothing at {x},{y} (background)",
                    format!("pick {x},{y}")
                );
                out.push(json!({ "x": x, "y": y, "hit": null, "distance_from_previous": null }));
            }
        }
        if let Some(d) = distance {
            data!("distance          {d:.4} {unit} (from the pick before)");
        }
        last = *hit;
    }
    Ok(Value::Array(out))
}
