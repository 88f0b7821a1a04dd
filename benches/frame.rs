//! Frame time of the teapot: `Renderer::render` (GPU draw + readback) of meshes tessellated and
//! uploaded beforehand, at 1024×768, lit shading, MSAA 1 and 4, fat borders off / 6 / 4 / 2, on
//! three views (default framing, from above, from the side).
//!
//! One criterion group per view × MSAA, with the four fat-border variants side by side, so the
//! ratio fat borders / off can be read per group. Goal: frame time with fat borders ≤ 1.10× off.
//!
//! Panics if no renderer can be created: a bench must not silently skip.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, SamplingMode, criterion_group, criterion_main};
use patchwork::render::{FatBorders, RenderOptions, Renderer, Shading};
use patchwork::tessellate::{MeshStats, tessellate_scene};
use patchwork::view::{DEFAULT_FOV_Y_DEG, DEFAULT_PIXEL_ERROR, View, pleasant_direction};

const SIZE: (u32, u32) = (1024, 768);
const MSAA: [u32; 2] = [1, 4];
const VARIANTS: [FatBorders; 4] = [
    FatBorders::Off,
    FatBorders::Six,
    FatBorders::Four,
    FatBorders::Two,
];

fn bench_frame(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::io::load(&path)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    let up = scene.up.vector();
    let fov = DEFAULT_FOV_Y_DEG.to_radians();

    // A horizontal "front" direction (towards the viewer) perpendicular to `up`.
    let pleasant = pleasant_direction(up);
    let front = (pleasant - up * pleasant.dot(up)).normalize();
    let views: [(&str, View); 3] = [
        ("framing", View::framing(&scene.bounds, up, fov, SIZE)),
        // Nearly straight down; slightly tilted so `up` is not parallel to the view direction.
        (
            "above",
            View::framing_from(&scene.bounds, up, up + 0.2 * front, fov, SIZE),
        ),
        // Horizontal, from the front: the teapot in profile (spout and handle left and right).
        (
            "side",
            View::framing_from(&scene.bounds, up, front, fov, SIZE),
        ),
    ];

    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("cannot create renderer: {e}"));
    println!("\nadapter: {}", renderer.gpu().describe());
    println!(
        "teapot: {} patches, {}x{}, fov {DEFAULT_FOV_Y_DEG}°, pixel error {DEFAULT_PIXEL_ERROR}, lit",
        scene.patches.len(),
        SIZE.0,
        SIZE.1
    );
    println!(
        "{:>8} {:>10} {:>10} {:>10} {:>12} {:>12}",
        "view", "triangles", "vertices", "border v", "eps min", "eps max"
    );

    for (name, view) in &views {
        let meshes = tessellate_scene(&scene, view, DEFAULT_PIXEL_ERROR);
        let s = MeshStats::of(&meshes);
        println!(
            "{:>8} {:>10} {:>10} {:>10} {:>12.3e} {:>12.3e}",
            name, s.triangles, s.vertices, s.border_vertices, s.eps_min, s.eps_max
        );
        let gpu_meshes = renderer.upload(&meshes);

        for msaa in MSAA {
            let mut group = c.benchmark_group(format!("frame/{name}/msaa{msaa}"));
            group.sampling_mode(SamplingMode::Flat);
            for fat_borders in VARIANTS {
                let opts = RenderOptions {
                    fat_borders,
                    msaa,
                    shading: Shading::Lit,
                    ..RenderOptions::default()
                };
                // Builds the pipelines for this target and surfaces any error before timing.
                renderer
                    .render(&gpu_meshes, view, &opts)
                    .unwrap_or_else(|e| panic!("render {name} msaa {msaa} fat {fat_borders}: {e}"));
                group.bench_with_input(
                    BenchmarkId::from_parameter(format!("fat_{}", fat_borders.name())),
                    &opts,
                    |b, opts| {
                        b.iter(|| {
                            let frame = renderer
                                .render(black_box(&gpu_meshes), black_box(view), opts)
                                .unwrap_or_else(|e| panic!("render failed: {e}"));
                            black_box(frame)
                        })
                    },
                );
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_frame
}
criterion_main!(benches);
