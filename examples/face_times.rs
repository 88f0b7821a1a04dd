//! The slowest trimmed faces of STEP/IGES files: every face (each shared face once) through the
//! trimmed tessellator at T = REL × the scene's bounding-box diagonal, as `export --tolerance T`
//! asks; prints the slowest faces with their time, triangles and error / ε, and the slowest of
//! all files last. `cargo run --release --example face_times -- [--rel 3e-3] [--top 5] FILE...`

use std::collections::HashSet;
use std::time::Instant;

use patchwork::model::PatchSurface;
use patchwork::tessellate::{PatchMesh, Tessellators};

fn main() {
    let mut rel = 3e-3;
    let mut top = 5usize;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rel" => rel = args.next().and_then(|v| v.parse().ok()).unwrap_or(rel),
            "--top" => top = args.next().and_then(|v| v.parse().ok()).unwrap_or(top),
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
            if !seen.insert(f.id) {
                continue;
            }
            let t0 = Instant::now();
            t.unplaced(p, tol, &mut out);
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            rows.push((
                ms,
                f.id,
                out.triangles.len(),
                out.error / tol,
                out.failure.clone(),
            ));
        }
        let total = start.elapsed().as_secs_f64() * 1e3;
        rows.sort_by(|a, b| b.0.total_cmp(&a.0));
        println!("{path}: {} faces, {total:.0} ms, T {tol:.4e}", rows.len());
        for (ms, id, tris, ratio, fail) in rows.iter().take(top) {
            println!(
                "  face #{id}: {ms:.1} ms, {tris} triangles, error/eps {ratio:.3}{}",
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
    if let Some((ms, what)) = slowest {
        println!("slowest face: {what}, {ms:.1} ms");
    }
}
