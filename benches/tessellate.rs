//! Tessellation of the whole teapot for the default framing view (1024×768, fov 45°), sweeping
//! the pixel error. One benchmark per pixel error, with `Throughput::Elements(triangles)` so
//! criterion reports triangles/s.
//!
//! * `tessellate_scene`: the library entry point (rayon over patches).
//! * `tessellate_single_thread`: one reused `BezierTessellator` and one reused `PatchMesh`,
//!   a sequential loop over the patches — the single-thread cost.
//!
//! Before measuring, a table of triangles, vertices, border vertices, ε range and worst
//! measured error/ε per pixel error is printed.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use patchwork::model::Scene;
use patchwork::tessellate::{MeshStats, PatchMesh, Tessellators, tessellate_scene};
use patchwork::view::{DEFAULT_FOV_Y_DEG, View};

const PIXEL_ERRORS: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
const SIZE: (u32, u32) = (1024, 768);

fn setup() -> (Scene, View) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::prep::load(&path)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    let view = View::framing(
        &scene.bounds,
        scene.up.vector(),
        DEFAULT_FOV_Y_DEG.to_radians(),
        SIZE,
    );
    (scene, view)
}

fn print_table(scene: &Scene, view: &View) {
    println!(
        "\nteapot: {} patches, default framing view {}x{}, fov {DEFAULT_FOV_Y_DEG}°",
        scene.patches.len(),
        SIZE.0,
        SIZE.1
    );
    println!(
        "{:>8} {:>10} {:>10} {:>10} {:>12} {:>12} {:>10}",
        "px err", "triangles", "vertices", "border v", "eps min", "eps max", "worst e/ε"
    );
    for px in PIXEL_ERRORS {
        let s = MeshStats::of(&tessellate_scene(scene, view, px));
        println!(
            "{:>8} {:>10} {:>10} {:>10} {:>12.3e} {:>12.3e} {:>10.3}",
            px,
            s.triangles,
            s.vertices,
            s.border_vertices,
            s.eps_min,
            s.eps_max,
            s.worst_error_ratio
        );
    }
    println!();
}

/// Sequential tessellation with one reused tessellator and mesh; returns the triangle count.
fn tessellate_sequential(
    scene: &Scene,
    view: &View,
    px: f64,
    t: &mut Tessellators,
    mesh: &mut PatchMesh,
) -> usize {
    let mut triangles = 0;
    for patch in &scene.patches {
        let eps = view.eps_obj(&patch.bounds, px);
        t.patch(patch, eps, mesh);
        triangles += black_box(&*mesh).triangles.len();
    }
    triangles
}

fn bench_tessellate(c: &mut Criterion) {
    let (scene, view) = setup();
    print_table(&scene, &view);

    let mut group = c.benchmark_group("tessellate_scene");
    for px in PIXEL_ERRORS {
        let triangles = MeshStats::of(&tessellate_scene(&scene, &view, px)).triangles;
        group.throughput(Throughput::Elements(triangles as u64));
        group.bench_with_input(BenchmarkId::from_parameter(px), &px, |b, &px| {
            b.iter(|| tessellate_scene(black_box(&scene), black_box(&view), black_box(px)))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("tessellate_single_thread");
    let mut t = Tessellators::new();
    let mut mesh = PatchMesh::default();
    for px in PIXEL_ERRORS {
        let triangles = tessellate_sequential(&scene, &view, px, &mut t, &mut mesh);
        group.throughput(Throughput::Elements(triangles as u64));
        group.bench_with_input(BenchmarkId::from_parameter(px), &px, |b, &px| {
            b.iter(|| {
                tessellate_sequential(
                    black_box(&scene),
                    black_box(&view),
                    black_box(px),
                    &mut t,
                    &mut mesh,
                )
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_tessellate
}
criterion_main!(benches);
