//! The slowest trimmed faces of STEP/IGES files: every face (each shared face once) through the
//! trimmed tessellator at T = REL × the scene's bounding-box diagonal, as `export --tolerance T`
//! asks; prints the slowest faces with their time, triangles and error / ε, and the slowest of
//! all files last. `cargo run --release --example face_times -- [--rel 3e-3] [--top 5] FILE...`
//! With `--near X,Y,Z` the faces are ordered by the distance of their mesh to that point
//! instead (unplaced coordinates: which face drew a point a judge names). `--kind K` keeps
//! the faces whose surface is of kind K only (plane, cylinder, cone, sphere, torus, swept,
//! bspline: the names of `benches/occt_faces.rs`).

use std::collections::HashSet;
use std::time::Instant;

use patchwork::model::PatchSurface;
use patchwork::tessellate::{PatchMesh, Tessellators};

fn main() {
    let mut rel = 3e-3;
    let mut top = 5usize;
    let mut near: Option<glam::Vec3> = None;
    let mut only_kind: Option<String> = None;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rel" => rel = args.next().and_then(|v| v.parse().ok()).unwrap_or(rel),
            "--top" => top = args.next().and_then(|v| v.parse().ok()).unwrap_or(top),
            "--kind" => only_kind = args.next(),
            "--near" => {
                let v: Vec<f32> = (args.next().unwrap_or_default().split(','))
                    .filter_map(|c| c.trim().parse().ok())
                    .collect();
                near = (v.len() == 3).then(|| glam::Vec3::new(v[0], v[1], v[2]));
            }
            _ => files.push(a),
        }
    }
    if files.is_empty() {
        eprintln!("usage: face_times [--rel R] [--top N] FILE...");
        std::process::exit(2);
    }
    let mut slowest: Option<(f64, String)> = None;
    for path in &files {
        let scene = match patchwork::prep::load(std::path::Path::new(path)) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        let tol = rel * scene.bbox_diagonal();
        let mut seen = HashSet::new();
        let mut t = Tessellators::new();
        let mut out = PatchMesh::default();
        let mut rows = Vec::new();
        let start = Instant::now();
        for p in &scene.patches {
            let PatchSurface::Trimmed(f) = &p.surface else {
                continue;
            };
            if !seen.insert(f.id) || only_kind.as_ref().is_some_and(|k| k != f.kind()) {
                continue;
            }
            let t0 = Instant::now();
            t.unplaced(p, tol, &mut out);
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            // Ordered by nearness: the key is minus the distance of the nearest triangle centre
            // or vertex.
            let key = near.map_or(ms, |q| {
                let centres = out.triangles.iter().map(|t| {
                    t.iter()
                        .map(|&i| out.positions[i as usize])
                        .sum::<glam::Vec3>()
                        / 3.0
                });
                let d = (out.positions.iter().copied().chain(centres))
                    .map(|v| v.distance(q))
                    .fold(f32::MAX, f32::min);
                -f64::from(d)
            });
            rows.push((
                key,
                f.id,
                out.triangles.len(),
                out.error / tol,
                out.failure.clone(),
            ));
        }
        let total = start.elapsed().as_secs_f64() * 1e3;
        rows.sort_by(|a, b| b.0.total_cmp(&a.0));
        let triangles: usize = rows.iter().map(|r| r.2).sum();
        println!(
            "{path}: {} faces, {total:.0} ms, {triangles} triangles, T {tol:.4e}",
            rows.len()
        );
        for (ms, id, tris, ratio, fail) in rows.iter().take(top) {
            println!(
                "  face #{id}: {:.1} {}, {tris} triangles, error/eps {ratio:.3}{}",
                ms.abs(),
                if near.is_some() {
                    "from the point"
                } else {
                    "ms"
                },
                fail.as_ref()
                    .map(|f| format!(", FAILED {f}"))
                    .unwrap_or_default()
            );
        }
        if let Some((ms, id, ..)) = rows.first()
            && slowest.as_ref().is_none_or(|s| *ms > s.0)
        {
            slowest = Some((*ms, format!("{path} face #{id}")));
        }
    }
    if let Some((ms, what)) = slowest.filter(|_| near.is_none()) {
        println!("slowest face: {what}, {ms:.1} ms");
    }
}
