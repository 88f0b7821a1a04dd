//! The WGSL fat-border expansion (run in a compute twin on the adapter) and its Rust CPU twin
//! give the same positions.

mod common;

use glam::Vec3;
use patchwork::check::crack::SplitMix64;
use patchwork::render::fat_border::{STRAIGHT_FLAG, expand, is_straight};
use patchwork::render::shaders::FAT_BORDER_TWIN;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TwinInput {
    prev: [f32; 4],
    cur: [f32; 4],
    next: [f32; 4],
    eye_eps: [f32; 4],
    code: [u32; 4],
}

fn inputs() -> Vec<(Vec3, Vec3, Vec3, Vec3, f32, u32)> {
    let mut rng = SplitMix64::new(42);
    let mut r = |s: f64| ((rng.next_f64() * 2.0 - 1.0) * s) as f32;
    let mut out = Vec::new();
    for _ in 0..500 {
        let cur = Vec3::new(r(3.0), r(3.0), r(3.0));
        let prev = cur + Vec3::new(r(0.3), r(0.3), r(0.3));
        let next = cur + Vec3::new(r(0.3), r(0.3), r(0.3));
        let eye = Vec3::new(r(20.0), r(20.0), r(20.0));
        let eps = (r(0.05)).abs() + 1e-4;
        for slot in 0..=6 {
            // Both branches of the shader, whatever the joint.
            out.push((prev, cur, next, eye, eps, slot));
            out.push((prev, cur, next, eye, eps, slot | STRAIGHT_FLAG));
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
            out.push((prev, cur, next, Vec3::new(1.0, 2.0, 9.0), 0.02, slot | flag));
        }
    }
    // Degenerate cases: collapsed segments, a segment seen end-on, a 180° turn.
    let z = Vec3::ZERO;
    let eye = Vec3::new(0.0, 0.0, 5.0);
    for (p, c, n) in [
        (z, z, z),
        (z, z, Vec3::X),
        (Vec3::new(0.0, 0.0, -1.0), z, Vec3::new(0.0, 0.0, 1.0)),
        (Vec3::X, z, Vec3::X),
    ] {
        for slot in (0..=6).chain((0..=6).map(|s| s | STRAIGHT_FLAG)) {
            out.push((p, c, n, eye, 0.01, slot));
        }
    }
    out
}

#[test]
fn compute_twin_matches_cpu_twin() {
    let renderer = common::renderer();
    let gpu = renderer.gpu();
    let device = &gpu.device;
    let cases = inputs();
    let data: Vec<TwinInput> = cases
        .iter()
        .map(|&(p, c, n, e, eps, slot)| TwinInput {
            prev: p.extend(1.0).into(),
            cur: c.extend(1.0).into(),
            next: n.extend(1.0).into(),
            eye_eps: e.extend(eps).into(),
            code: [slot, 0, 0, 0],
        })
        .collect();
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin inputs"),
        contents: bytemuck::cast_slice(&data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_size = (cases.len() * 16) as u64;
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
        entry_point: Some("cs_expand"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_size);
    gpu.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    let bytes = readback.get_mapped_range(..).expect("mapped").to_vec();
    let gpu_out: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);

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
