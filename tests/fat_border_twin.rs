//! The WGSL fat-border expansion (run in a compute twin on the adapter) and its Rust CPU twin
//! give the same positions: one displaced vertex from its inputs, and every vertex of a
//! variant's draw pulled from border points (ring neighbours, templates, collapsed fans);
//! for perspective viewers (an eye point, w = 1) and orthographic ones (a direction, w = 0).

mod common;

use glam::{Vec3, Vec4};
use patchwork::check::crack::SplitMix64;
use patchwork::render::fat_border::{
    CAP_FLAG, INFO_CLOSING, INFO_STRAIGHT, SLOTS_PER_POINT, STRAIGHT_FLAG, WIDTH_MASK, WIDTH_SHIFT,
    expand, is_straight, position, position_placed,
};
use patchwork::render::shaders::FAT_BORDER_TWIN;
use patchwork::render::{BorderGeometry, FatBorders};
use patchwork::tessellate::PatchMesh;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TwinInput {
    prev: [f32; 4],
    cur_eps: [f32; 4],
    next: [f32; 4],
    viewer: [f32; 4],
    code: [u32; 4],
}

fn inputs() -> Vec<(Vec3, Vec3, Vec3, Vec4, f32, u32)> {
    let mut rng = SplitMix64::new(42);
    let mut r = |s: f64| ((rng.next_f64() * 2.0 - 1.0) * s) as f32;
    let mut out = Vec::new();
    for _ in 0..500 {
        let cur = Vec3::new(r(3.0), r(3.0), r(3.0));
        let prev = cur + Vec3::new(r(0.3), r(0.3), r(0.3));
        let next = cur + Vec3::new(r(0.3), r(0.3), r(0.3));
        let eye = Vec3::new(r(20.0), r(20.0), r(20.0));
        // An orthographic viewer: the direction towards it, at infinity.
        let towards = Vec3::new(r(1.0), r(1.0), r(1.0)).normalize_or(Vec3::Z);
        let eps = (r(0.05)).abs() + 1e-4;
        // Full width, or a narrower half-width across the view (bits 4..9).
        let width = [0, 1, 17, 62][(out.len() / 28) % 4] << WIDTH_SHIFT;
        for viewer in [eye.extend(1.0), towards.extend(0.0)] {
            for slot in 0..=6 {
                // Both branches of the shader, whatever the joint.
                out.push((prev, cur, next, viewer, eps, slot | width));
                out.push((prev, cur, next, viewer, eps, slot | STRAIGHT_FLAG | width));
                // The 2-triangle variant's capped slots 1, 3, 4, 6.
                out.push((prev, cur, next, viewer, eps, slot | CAP_FLAG | width));
            }
        }
    }
    // Joints on both sides of the straight threshold, flagged as the CPU decides.
    for k in 0..60 {
        let angle = 0.003 * k as f32; // 0 .. 10°, the threshold is acos(0.99) ≈ 8.1°
        let cur = Vec3::new(0.3, -0.2, 0.1);
        let prev = cur - Vec3::new(0.1, 0.0, 0.0);
        let next = cur + 0.1 * Vec3::new(angle.cos(), angle.sin(), 0.0);
        let flag = if is_straight(prev, cur, next) {
            STRAIGHT_FLAG
        } else {
            0
        };
        for slot in 0..=6 {
            out.push((
                prev,
                cur,
                next,
                Vec4::new(1.0, 2.0, 9.0, 1.0),
                0.02,
                slot | flag,
            ));
        }
    }
    // Degenerate cases: collapsed segments, a segment seen end-on, a 180° turn.
    let z = Vec3::ZERO;
    let eye = Vec4::new(0.0, 0.0, 5.0, 1.0);
    for (p, c, n) in [
        (z, z, z),
        (z, z, Vec3::X),
        (Vec3::new(0.0, 0.0, -1.0), z, Vec3::new(0.0, 0.0, 1.0)),
        (Vec3::X, z, Vec3::X),
    ] {
        let flagged = |f: u32| (0..=6).map(move |s| s | f);
        for slot in flagged(0)
            .chain(flagged(STRAIGHT_FLAG))
            .chain(flagged(CAP_FLAG))
        {
            out.push((p, c, n, eye, 0.01, slot));
            // Orthographic, looking along the end-on segment.
            out.push((p, c, n, Vec4::new(0.0, 0.0, 1.0, 0.0), 0.01, slot));
        }
    }
    out
}

/// Runs entry point `entry` of the compute twin over `count` outputs with `bindings` (group,
/// binding, buffer) and reads the outputs back.
fn run_twin(
    gpu: &patchwork::render::Gpu,
    entry: &str,
    count: usize,
    bindings: &[(u32, u32, &wgpu::Buffer)],
) -> Vec<[f32; 4]> {
    let device = &gpu.device;
    let out_size = (count * 16) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("twin outputs"),
        size: out_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("twin readback"),
        size: out_size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("fat_border_twin"),
        source: wgpu::ShaderSource::Wgsl(FAT_BORDER_TWIN.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("twin"),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let mut all = vec![(0, 1, &output)];
    all.extend_from_slice(bindings);
    let groups: Vec<(u32, wgpu::BindGroup)> = [0u32, 1]
        .iter()
        .filter(|g| all.iter().any(|b| b.0 == **g))
        .map(|&g| {
            let entries: Vec<wgpu::BindGroupEntry<'_>> = all
                .iter()
                .filter(|b| b.0 == g)
                .map(|b| wgpu::BindGroupEntry {
                    binding: b.1,
                    resource: b.2.as_entire_binding(),
                })
                .collect();
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(g),
                entries: &entries,
            });
            (g, bind)
        })
        .collect();
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        for (g, bind) in &groups {
            pass.set_bind_group(*g, bind, &[]);
        }
        pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_size);
    gpu.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    let bytes = readback.get_mapped_range(..).expect("mapped").to_vec();
    bytemuck::pod_collect_to_vec(&bytes)
}

#[test]
fn compute_twin_matches_cpu_twin() {
    let renderer = common::renderer();
    let gpu = renderer.gpu();
    let cases = inputs();
    let data: Vec<TwinInput> = cases
        .iter()
        .map(|&(p, c, n, e, eps, slot)| TwinInput {
            prev: p.extend(1.0).into(),
            cur_eps: c.extend(eps).into(),
            next: n.extend(1.0).into(),
            viewer: e.into(),
            code: [slot, 0, 0, 0],
        })
        .collect();
    let input = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("twin inputs"),
            contents: bytemuck::cast_slice(&data),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let gpu_out = run_twin(gpu, "cs_expand", cases.len(), &[(0, 0, &input)]);

    let mut worst: f32 = 0.0;
    for (k, &(p, c, n, e, eps, slot)) in cases.iter().enumerate() {
        let cpu = expand(p, c, n, e, eps, slot);
        let g = Vec3::new(gpu_out[k][0], gpu_out[k][1], gpu_out[k][2]);
        assert!(g.is_finite(), "case {k}: GPU gave {g:?}");
        let err = (cpu - g).length();
        worst = worst.max(err / eps);
        // f32 rounding of a few normalisations: far below ε, the only scale that matters.
        assert!(
            err <= 1e-4 * eps + 4e-6 * (1.0 + c.length()),
            "case {k} code {slot}: cpu {cpu:?} gpu {g:?} (ε {eps})"
        );
    }
    eprintln!(
        "largest |cpu − gpu| / ε over {} cases: {worst:e}",
        cases.len()
    );
}

/// Meshes whose rings mix straight joints (gently bent runs), sharp corners, and rings of one
/// and two points; random ε and colours.
fn ring_meshes() -> Vec<PatchMesh> {
    let mut rng = SplitMix64::new(7);
    let mut r = |s: f64| ((rng.next_f64() * 2.0 - 1.0) * s) as f32;
    (0..6u32)
        .map(|id| {
            let mut positions = Vec::new();
            let mut borders = Vec::new();
            for ring in 0..3 {
                let n = [48usize, 1, 2, 7][(id as usize + ring) % 4];
                let base = positions.len() as u32;
                let centre = Vec3::new(r(2.0), r(2.0), r(2.0));
                let bend = r(0.2);
                for k in 0..n {
                    let a = k as f32 / n as f32 * std::f32::consts::TAU;
                    // Mostly straight runs (a polygon with few sides and wobbles) or circles.
                    let rad = if ring == 0 {
                        1.0 + bend * (3.0 * a).sin()
                    } else {
                        0.5
                    };
                    positions.push(centre + Vec3::new(rad * a.cos(), rad * a.sin(), r(0.05)));
                }
                borders.push((base..base + n as u32).collect());
            }
            let count = positions.len();
            PatchMesh {
                patch_id: id,
                normals: (0..count)
                    .map(|_| Vec3::new(r(1.0), r(1.0), 1.0).normalize())
                    .collect(),
                positions,
                borders,
                eps_target: 0.001 + (r(0.02)).abs() as f64,
                // Some patches with fat borders narrower than ε across the view.
                border_error: (id % 3 == 1).then_some(0.0004),
                color: (id % 2 == 0).then_some([0.2, 0.5, 0.9]),
                ..PatchMesh::default()
            }
        })
        .collect()
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Pull {
    viewer: [f32; 4],
    len_count: [u32; 4],
}

#[test]
fn pulled_vertices_match_the_cpu_twin() {
    let renderer = common::renderer();
    let gpu = renderer.gpu();
    let meshes = ring_meshes();
    let g = BorderGeometry::of(&meshes);
    let straight = g
        .points
        .iter()
        .filter(|p| p.info & INFO_STRAIGHT != 0 && p.info & INFO_CLOSING == 0)
        .count();
    assert!(
        straight > 10 && straight < g.points.len() - 10,
        "{straight}"
    );
    let narrow = g.points.iter().filter(|p| p.info & WIDTH_MASK != 0).count();
    assert!(narrow > 10 && narrow < g.points.len() - 10, "{narrow}");
    let points = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("twin points"),
            contents: bytemuck::cast_slice(&g.points),
            usage: wgpu::BufferUsages::STORAGE,
        });
    // Every vertex of every point (the closing points' too), but not past the last point.
    let count = (g.points.len() - 1) * SLOTS_PER_POINT;
    let mut checked = 0;
    let orthographic = Vec3::new(0.3, -0.4, 0.8).normalize().extend(0.0);
    for viewer in [
        Vec4::new(3.0, -2.0, 9.0, 1.0),
        Vec4::new(-0.5, 0.2, 0.3, 1.0),
        orthographic,
    ] {
        for variant in FatBorders::ALL_ON {
            let codes = g.index_count(variant) / g.points.len();
            let pull = Pull {
                viewer: viewer.into(),
                len_count: [codes as u32, count as u32, 0, 0],
            };
            let params = gpu
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("twin pull"),
                    contents: bytemuck::bytes_of(&pull),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
            let out = run_twin(gpu, "cs_pull", count, &[(0, 2, &params), (1, 0, &points)]);
            for (i, o) in out.iter().enumerate() {
                let (p, j) = position(&g.points, variant, i, viewer);
                assert_eq!(o[3].to_bits() as usize, j, "{variant} vertex {i}: point");
                let gpu_p = Vec3::new(o[0], o[1], o[2]);
                let eps = g.points[j].eps;
                let err = (p - gpu_p).length();
                assert!(
                    err <= 1e-4 * eps + 4e-6 * (1.0 + p.length()),
                    "{variant} vertex {i}: cpu {p:?} gpu {gpu_p:?} (ε {eps})"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PullPlaced {
    rows: [[f32; 4]; 3],
    eps_added: [f32; 4],
}

/// Instanced parts: a shared mesh's points drawn with a placement (a rotation, scale 2 and a
/// translation). The compute twin of `fat_border_vertex_placed` gives the CPU twin's
/// positions, and those are the positions of the same rings placed in f64 first and expanded
/// as every other border (the world-space copies' path), up to f32 rounding.
#[test]
fn placed_pulled_vertices_match_the_cpu_twin_and_the_placed_rings() {
    use glam::{DMat4, DQuat, DVec3};
    let renderer = common::renderer();
    let gpu = renderer.gpu();
    let meshes = ring_meshes();
    let g = BorderGeometry::of(&meshes);
    let m = DMat4::from_scale_rotation_translation(
        DVec3::splat(2.0),
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7),
        DVec3::new(5.0, -3.0, 1.5),
    );
    assert!(patchwork::tessellate::is_similarity(&m));
    let rows = [0, 1, 2].map(|k| m.row(k).as_vec4().to_array());
    let eps_added = 2e-4f32;
    // The world-space copies: the rings placed in f64, ε of the shared mesh plus the addition.
    let copies: Vec<PatchMesh> = meshes
        .iter()
        .map(|mesh| PatchMesh {
            positions: mesh
                .positions
                .iter()
                .map(|p| m.transform_point3(p.as_dvec3()).as_vec3())
                .collect(),
            eps_target: mesh.eps_target + eps_added as f64,
            // A placement that adds to ε draws its fat borders the whole ε wide.
            border_error: None,
            ..mesh.clone()
        })
        .collect();
    let world = BorderGeometry::of(&copies);
    assert_eq!(world.points.len(), g.points.len());
    let points = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("twin points"),
            contents: bytemuck::cast_slice(&g.points),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let placed = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("twin placement"),
            contents: bytemuck::bytes_of(&PullPlaced {
                rows,
                eps_added: [eps_added, 0.0, 0.0, 0.0],
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let count = (g.points.len() - 1) * SLOTS_PER_POINT;
    let mut checked = 0;
    for eye in [Vec3::new(13.0, -8.0, 20.0), Vec3::new(4.0, -2.5, 2.0)] {
        for variant in FatBorders::ALL_ON {
            let codes = g.index_count(variant) / g.points.len();
            let pull = Pull {
                viewer: eye.extend(1.0).into(),
                len_count: [codes as u32, count as u32, 0, 0],
            };
            let params = gpu
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("twin pull"),
                    contents: bytemuck::bytes_of(&pull),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
            let out = run_twin(
                gpu,
                "cs_pull_placed",
                count,
                &[(0, 2, &params), (0, 3, &placed), (1, 0, &points)],
            );
            for (i, o) in out.iter().enumerate() {
                let (p, j) =
                    position_placed(&g.points, variant, i, eye.extend(1.0), &rows, eps_added);
                assert_eq!(o[3].to_bits() as usize, j, "{variant} vertex {i}: point");
                let gpu_p = Vec3::new(o[0], o[1], o[2]);
                let eps = g.points[j].eps + eps_added;
                let tol = 1e-4 * eps + 4e-6 * (1.0 + p.length());
                let err = (p - gpu_p).length();
                assert!(err <= tol, "{variant} vertex {i}: cpu {p:?} gpu {gpu_p:?}");
                // The world-space path (where a ring's straight joints agree: the flags are
                // decided on the points, placed or not).
                if world.points[j].info == g.points[j].info {
                    let (w, k) = position(&world.points, variant, i, eye.extend(1.0));
                    assert_eq!(k, j);
                    let err = (p - w).length();
                    assert!(err <= tol, "{variant} vertex {i}: placed {p:?} copy {w:?}");
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}
