//! Loads STEP files and prints, per tolerance (1e-2, 3e-3, 1e-3 of the bbox diagonal),
//! triangles, time, worst measured error / tolerance, and failures: `cargo run --release
//! --example step_probe -- models/*.stp`.

use patchwork::tessellate::tessellate_scene_tolerance;
fn main() {
    for path in std::env::args().skip(1) {
        let t = std::time::Instant::now();
        let scene = match patchwork::prep::load(std::path::Path::new(&path)) {
            Ok(s) => s,
            Err(e) => {
                println!("{e}");
                continue;
            }
        };
        let load = t.elapsed();
        let diag = scene.bbox_diagonal();
        println!(
            "{path}: {} patches, {} skipped, diag {diag:.3}, load {:.0} ms",
            scene.patches.len(),
            scene.skipped.len(),
            load.as_secs_f64() * 1e3
        );
        for s in &scene.skipped {
            println!("  skipped #{}: {}", s.face, s.reason);
        }
        for w in &scene.warnings {
            println!("  warn {w}");
        }
        for rel in [1e-2, 3e-3, 1e-3] {
            let tol = rel * diag;
            let t = std::time::Instant::now();
            let m = tessellate_scene_tolerance(&scene, tol);
            let dt = t.elapsed();
            let tris: usize = m.iter().map(|m| m.triangles.len()).sum();
            let worst = m.iter().map(|m| m.error / tol).fold(0.0, f64::max);
            let trim = m.iter().map(|m| m.trim_error / tol).fold(0.0, f64::max);
            let failed: Vec<_> = m.iter().filter_map(|m| m.failure.clone()).collect();
            let over = m.iter().filter(|m| m.error > tol).count();
            println!(
                "  rel {rel:e}: {tris} tris, {:.1} ms, worst err/tol {worst:.3}, trim/tol {trim:.3}, over {over}, failed {}",
                dt.as_secs_f64() * 1e3,
                failed.len()
            );
            for f in failed.iter().take(5) {
                println!("    {f}");
            }
        }
    }
}
