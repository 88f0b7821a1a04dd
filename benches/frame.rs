//! Frame time of the teapot: `Renderer::render` (GPU draw + readback) of meshes tessellated and
//! uploaded beforehand, at 1024×768, lit shading, MSAA 1 and 4, fat borders off / 6 / 4 / 2, on
//! three views (default framing, from above, from the side).
//!
//! One criterion group per view × MSAA, with the four fat-border variants side by side, so the
//! ratio fat borders / off can be read per group. Goal: frame time with fat borders ≤ 1.10× off.
//!
//! Criterion measures the variants one after the other, so a burst of load from another process
//! (on a 2-core machine llvmpipe uses every core) lands on one variant only and skews its ratio.
//! Before the criterion groups, an interleaved round-robin measurement (every round renders every
//! variant once, in a rotated order) prints the median ratio to off per view × MSAA, which is
//! much less sensitive to such bursts.
//!
//! Panics if no renderer can be created: a bench must not silently skip.

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, SamplingMode, criterion_group, criterion_main};
use patchwork::render::{FatBorders, GpuMeshes, RenderOptions, Renderer, Shading};
use patchwork::tessellate::{MeshStats, tessellate_scene};
use patchwork::view::{DEFAULT_FOV_Y_DEG, DEFAULT_PIXEL_ERROR, View, pleasant_direction};

const SIZE: (u32, u32) = (1024, 768);
const MSAA: [u32; 2] = [1, 4];
/// Rounds of the interleaved measurement.
const ROUNDS: usize = 15;
const VARIANTS: [FatBorders; 4] = [
    FatBorders::Off,
    FatBorders::Six,
    FatBorders::Four,
    FatBorders::Two,
];

fn bench_frame(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = patchwork::prep::load(&path)
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
            interleaved(&mut renderer, &gpu_meshes, name, view, msaa);
        }

        for msaa in MSAA {
            let mut group = c.benchmark_group(format!("frame/{name}/msaa{msaa}"));
            group.sampling_mode(SamplingMode::Flat);
            for fat_borders in VARIANTS {
                let opts = options(fat_borders, msaa);
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

fn options(fat_borders: FatBorders, msaa: u32) -> RenderOptions {
    RenderOptions {
        fat_borders,
        msaa,
        shading: Shading::Lit,
        ..RenderOptions::default()
    }
}

/// Round-robin timing of the four variants; prints median frame time and ratio to off.
fn interleaved(renderer: &mut Renderer, meshes: &GpuMeshes, name: &str, view: &View, msaa: u32) {
    let mut times = vec![Vec::with_capacity(ROUNDS); VARIANTS.len()];
    for fat_borders in VARIANTS {
        // Warm-up: builds the pipelines for this target and surfaces any error.
        renderer
            .render(meshes, view, &options(fat_borders, msaa))
            .unwrap_or_else(|e| panic!("render {name} msaa {msaa} fat {fat_borders}: {e}"));
    }
    for round in 0..ROUNDS {
        for k in 0..VARIANTS.len() {
            let i = (k + round) % VARIANTS.len();
            let opts = options(VARIANTS[i], msaa);
            let start = Instant::now();
            let frame = renderer
                .render(meshes, view, &opts)
                .unwrap_or_else(|e| panic!("render failed: {e}"));
            black_box(frame);
            times[i].push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let medians: Vec<f64> = times
        .iter_mut()
        .map(|t| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        })
        .collect();
    let cells: Vec<String> = VARIANTS
        .iter()
        .zip(&medians)
        .map(|(v, m)| format!("{:>3} {m:7.2} ms ×{:.2}", v.name(), m / medians[0]))
        .collect();
    println!(
        "interleaved {name:>8} msaa{msaa} (median of {ROUNDS}): {}",
        cells.join(" | ")
    );
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
