//! One trimmed face through the trimmed tessellator at several tolerances: triangles, grid,
//! achieved error / ε. `cargo run --release --example face_probe -- FILE FACE_ID [REL...]`
//! (REL: ε as a fraction of the face's bounding radius; default 1e-2 3e-3 1e-3). FACE_ID 0
//! lists every face's mesh box, or with `FACE_PROBE_POINT=x,y,z` how near each face's mesh
//! comes to that point (which face an OCCT judge's sample belongs to).

use patchwork::model::PatchSurface;
use patchwork::tessellate::{PatchMesh, TrimmedTessellator};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(path), Some(id)) = (
        args.first(),
        args.get(1).and_then(|a| a.parse::<u64>().ok()),
    ) else {
        eprintln!("usage: face_probe FILE FACE_ID [REL...]");
        std::process::exit(2);
    };
    let rels: Vec<f64> = match args.get(2..) {
        Some(r) if !r.is_empty() => r.iter().filter_map(|a| a.parse().ok()).collect(),
        _ => vec![1e-2, 3e-3, 1e-3],
    };
    let scene = match patchwork::prep::load(std::path::Path::new(path)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    if id == 0 {
        // Every face: its mesh's box at rel 1e-2 (to find a face drawn where it should not be).
        let mut t = TrimmedTessellator::new();
        let mut out = PatchMesh::default();
        let point = std::env::var("FACE_PROBE_POINT").ok().and_then(|at| {
            let c: Vec<f32> = at
                .split(',')
                .filter_map(|x| x.trim().parse().ok())
                .collect();
            match c[..] {
                [x, y, z] => Some(glam::Vec3::new(x, y, z)),
                _ => None,
            }
        });
        for p in &scene.patches {
            if let PatchSurface::Trimmed(f) = &p.surface {
                let eps = 1e-2 * f.bounds.radius;
                if t.tessellate(f, eps, &mut out).is_ok() {
                    // FACE_PROBE_POINT="x,y,z": how near the face's mesh comes to that point.
                    if let Some(q) = point {
                        let d = out
                            .positions
                            .iter()
                            .map(|v| v.distance(q))
                            .fold(f32::MAX, f32::min);
                        println!(
                            "face #{} ({}) instance {}: nearest vertex {d:.3}",
                            f.id,
                            f.kind(),
                            p.instance
                        );
                        continue;
                    }
                    let (lo, hi) = out.positions.iter().fold(
                        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
                        |(lo, hi), q| (lo.min(*q), hi.max(*q)),
                    );
                    println!("face #{} instance {}: {lo:.0} .. {hi:.0}", f.id, p.instance);
                }
            }
        }
        return;
    }
    let Some(face) = scene.patches.iter().find_map(|p| match &p.surface {
        PatchSurface::Trimmed(f) if f.id == id => Some(f.clone()),
        _ => None,
    }) else {
        eprintln!("{path}: no drawn face #{id}");
        std::process::exit(2);
    };
    println!(
        "face #{id}: {} loops, radius {:.4}, surface {:?}, closed (u, v) {:?}",
        face.loops.len(),
        face.bounds.radius,
        std::mem::discriminant(&face.surface),
        face.closed
    );
    if std::env::var_os("FACE_PROBE_LOOPS").is_some() {
        use patchwork::model::trimmed::SurfaceEval;
        let mut hint = None;
        for lp in &face.loops {
            for le in lp {
                let e = &le.edge;
                for k in 0..=8 {
                    let p = e.point(e.t0 + (e.t1 - e.t0) * k as f64 / 8.0);
                    let uv = face.project(p, hint);
                    hint = uv;
                    let d = uv.map(|uv| face.point(uv).distance(p));
                    println!(
                        "  edge #{} k {k}: p {p:.3} uv {uv:?} off {d:?} (t {} .. {}, wrap {:?}, forward {})",
                        e.id, e.t0, e.t1, e.wrap, le.forward
                    );
                }
            }
        }
    }
    if let Ok(at) = std::env::var("FACE_PROBE_AT") {
        // `u,v;u,v;…`: the surface's points there.
        use patchwork::model::trimmed::SurfaceEval;
        for pair in at.split(';') {
            let c: Vec<f64> = pair
                .split(',')
                .filter_map(|x| x.trim().parse().ok())
                .collect();
            if let [u, v] = c[..] {
                let uv = glam::DVec2::new(u, v);
                let (su, sv) = face.derivs(uv);
                let h = 1e-6;
                let fu = (face.point(uv + glam::DVec2::X * h)
                    - face.point(uv - glam::DVec2::X * h))
                    / (2.0 * h);
                let fv = (face.point(uv + glam::DVec2::Y * h)
                    - face.point(uv - glam::DVec2::Y * h))
                    / (2.0 * h);
                println!(
                    "  S({u}, {v}) = {:.6}; Su {su:.5} (fd {fu:.5}); Sv {sv:.5} (fd {fv:.5})",
                    face.point(uv)
                );
                let q = face.point(uv);
                println!("    project(S) = {:?}", face.project(q, None));
            }
        }
    }
    if std::env::var_os("FACE_PROBE_SCAN").is_some() {
        use patchwork::model::trimmed::SurfaceEval;
        let e = &face.loops[0][0].edge;
        let p = e.point(e.t0);
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for i in 0..=360 {
            for j in 0..=400 {
                let uv =
                    glam::DVec2::new(i as f64 / 360.0 * std::f64::consts::TAU, -200.0 + j as f64);
                let d = face.point(uv).distance(p);
                if d < best.0 {
                    best = (d, uv.x, uv.y);
                }
            }
        }
        for h in [
            None,
            Some((0.886, -42.55)),
            Some((0.886, -60.0)),
            Some((4.03, -62.0)),
            Some((4.03, -40.0)),
            Some((0.886, 0.5)),
        ] {
            let hint = h.map(|(u, v)| glam::DVec2::new(u, v));
            let uv = face.project(p, hint);
            println!(
                "project from {hint:?}: {uv:?} off {:?}",
                uv.map(|uv| face.point(uv).distance(p))
            );
        }
        println!("scan: nearest to {p:.3}: {best:?}");
        for v in [-60.0, -57.17, -51.0, -45.0, -40.0, 0.0, 57.17] {
            println!(
                "  v {v}: S(best u, v) = {:.3}",
                face.point(glam::DVec2::new(best.1, v))
            );
        }
    }
    let mut t = TrimmedTessellator::new();
    let mut out = PatchMesh::default();
    for rel in rels {
        let eps = rel * face.bounds.radius;
        let start = std::time::Instant::now();
        match t.tessellate(&face, eps, &mut out) {
            Ok(r) => {
                let pos: Vec<glam::DVec3> = out.positions.iter().map(|p| p.as_dvec3()).collect();
                if let Some(f) =
                    patchwork::check::fidelity::measure(&face, &pos, &out.triangles, eps)
                {
                    println!(
                        "  measure: error/eps {:.3}, surface {:.3}, outside {} of {}, missing/eps {:.3}, worst at {:?}",
                        f.ratio(),
                        f.surface_error / eps,
                        f.outside,
                        f.samples,
                        f.missing / eps,
                        f.worst_at
                    );
                    use patchwork::model::trimmed::SurfaceEval;
                    // Brute force, no code shared with the measure: the worst point's distance
                    // to the face's own mesh.
                    let brute = out
                        .triangles
                        .iter()
                        .map(|t| {
                            let [a, b, c] = t.map(|i| pos[i as usize]);
                            patchwork::geom::point_triangle_distance(f.worst_at, a, b, c)
                        })
                        .fold(f64::INFINITY, f64::min);
                    println!(
                        "  worst point to the mesh (brute force): {:.3} eps",
                        brute / eps
                    );
                    if std::env::var_os("FACE_PROBE_NEAR").is_some() {
                        // The triangles nearest the worst point, their corners' parameters.
                        let mut near: Vec<(f64, usize)> = out
                            .triangles
                            .iter()
                            .enumerate()
                            .map(|(k, t)| {
                                let [a, b, c] = t.map(|i| pos[i as usize]);
                                let d =
                                    patchwork::geom::point_triangle_distance(f.worst_at, a, b, c);
                                (d, k)
                            })
                            .collect();
                        near.retain(|x| x.0.is_finite());
                        near.sort_by(|a, b| a.0.total_cmp(&b.0));
                        for &(d, k) in near.iter().take(4) {
                            let t = out.triangles[k];
                            let uvs: Vec<String> = t
                                .iter()
                                .map(|&i| {
                                    let p = pos[i as usize];
                                    format!("{:?}", face.project(p, None).map(|uv| (uv.x, uv.y)))
                                })
                                .collect();
                            println!("    tri {k} at {:.3} eps: {}", d / eps, uvs.join(" "));
                        }
                    }
                    let uv = face.project(f.worst_at, None);
                    println!(
                        "  worst projects to {uv:?}, off {:?}",
                        uv.map(|uv| face.point(uv).distance(f.worst_at))
                    );
                }
                println!(
                    "rel {rel:e}: eps {eps:.4e}, {} triangles, grid {}x{}, error/eps {:.3}, trim/eps {:.3}, crossing {}, {:.1} ms",
                    out.triangles.len(),
                    out.resolution.nu,
                    out.resolution.nv,
                    out.error / eps,
                    r.trim_error / eps,
                    r.crossing_constraints,
                    start.elapsed().as_secs_f64() * 1e3
                )
            }
            Err(e) => println!("rel {rel:e}: {e}"),
        }
    }
}
