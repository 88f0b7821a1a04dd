//! Triangle strips, measured in one run: `cargo bench --bench strips` prints (and writes
//! `target/strips.md`):
//! 1. static stripification — strips, indices per triangle and time — of the whole bunny
//!    (144 046 triangles), of its 99 patches and of tessellated Bézier (teapot) and trimmed
//!    NURBS (as1 STEP) patches: ours (greedy start + swap-aware tunneling, the default), the
//!    paper's pure tunneling (single triangles, every tunnel taken), and meshopt's stripify
//!    on the original order and after `optimize_vertex_cache_strip` (both with restarts);
//! 2. incremental repair (Stewart §4.2) while every bunny patch's cut moves from the finest to
//!    the coarsest level and back one collapse / split at a time: time per operation and
//!    strips kept vs stripifying the final cut from scratch, and the "local only" variant;
//! 3. per resolution (½-px cuts at 1×, 2×, 4× the framing distance): indices sent by a list,
//!    by static per-arc strips, by MTS and by re-stripifying each cut, with the times of MTS
//!    extraction (with and without coherence, over a 20-frame dolly) and of re-stripifying.

use std::fmt::Write as _;
use std::time::Instant;

use patchwork::model::{PatchSurface, Scene, UpAxis};
use patchwork::mt::MtHierarchy;
use patchwork::strips::mts::MultiresStrips;
use patchwork::strips::tunnel::{CutStrips, TunnelOptions, stripify};
use patchwork::strips::{RESTART, arc_strips};
use patchwork::view::{self, View};

fn meshopt_strips(tris: &[[u32; 3]], vertex_cache: bool) -> (usize, usize) {
    let flat: Vec<u32> = tris.iter().flatten().copied().collect();
    let n = flat.iter().copied().max().map_or(0, |m| m as usize + 1);
    let input = if vertex_cache {
        meshopt::optimize_vertex_cache_strip(&flat, n)
    } else {
        flat
    };
    let s = meshopt::stripify(&input, n, RESTART).expect("stripify");
    let strips = if s.is_empty() {
        0
    } else {
        s.iter().filter(|&&i| i == RESTART).count() + 1
    };
    (s.len(), strips)
}

/// Sums over patches: (triangles, indices, strips, seconds).
#[derive(Default, Clone, Copy)]
struct Sum {
    tris: usize,
    idx: usize,
    strips: usize,
    secs: f64,
}

impl Sum {
    fn add(&mut self, tris: usize, idx: usize, strips: usize, secs: f64) {
        self.tris += tris;
        self.idx += idx;
        self.strips += strips;
        self.secs += secs;
    }
    fn ipt(&self) -> f64 {
        self.idx as f64 / self.tris.max(1) as f64
    }
}

fn static_row(md: &mut String, name: &str, meshes: &[Vec<[u32; 3]>]) {
    let pure = TunnelOptions {
        greedy_start: false,
        swap_aware: false,
        ..TunnelOptions::default()
    };
    let (mut ours, mut paper, mut mo, mut mv) = (
        Sum::default(),
        Sum::default(),
        Sum::default(),
        Sum::default(),
    );
    for tris in meshes {
        let t = Instant::now();
        let s = stripify(tris, &TunnelOptions::default());
        ours.add(
            tris.len(),
            s.indices.len(),
            s.strips,
            t.elapsed().as_secs_f64(),
        );
        let t = Instant::now();
        let s = stripify(tris, &pure);
        paper.add(
            tris.len(),
            s.indices.len(),
            s.strips,
            t.elapsed().as_secs_f64(),
        );
        let t = Instant::now();
        let (i, n) = meshopt_strips(tris, false);
        mo.add(tris.len(), i, n, t.elapsed().as_secs_f64());
        let t = Instant::now();
        let (i, n) = meshopt_strips(tris, true);
        mv.add(tris.len(), i, n, t.elapsed().as_secs_f64());
    }
    let _ = writeln!(
        md,
        "| {name} | {} | {} | {} / {:.3} / {:.0} | {} / {:.3} / {:.0} | {} / {:.3} / {:.1} | {} / {:.3} / {:.1} | **{:.3}×** |",
        meshes.len(),
        ours.tris,
        ours.strips,
        ours.ipt(),
        ours.secs * 1e3,
        paper.strips,
        paper.ipt(),
        paper.secs * 1e3,
        mo.strips,
        mo.ipt(),
        mo.secs * 1e3,
        mv.strips,
        mv.ipt(),
        mv.secs * 1e3,
        ours.ipt() / mv.ipt(),
    );
}

fn mesh_patches(scene: &Scene) -> Vec<&patchwork::model::mesh::MeshPatch> {
    scene
        .patches
        .iter()
        .filter_map(|p| match &p.surface {
            PatchSurface::Mesh(m) => Some(&**m),
            _ => None,
        })
        .collect()
}

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## 1. Static strips: strips / indices per triangle / ms\n\n\
         | mesh | pieces | triangles | ours (greedy + swap-aware tunneling) | paper's tunneling (single start, every tunnel) | meshopt, original order | meshopt after optimize_vertex_cache_strip | ours ÷ meshopt (vcache) |\n\
         |---|---|---|---|---|---|---|---|"
    );
    let mut whole = patchwork::io::mesh::read_gltf(&root.join("models/bunny.glb")).expect("bunny");
    whole.weld();
    static_row(
        &mut md,
        "bunny, whole",
        std::slice::from_ref(&whole.triangles),
    );
    eprintln!("bunny whole done");
    let t = Instant::now();
    let fine = patchwork::prep::mesh_scene(
        whole.clone(),
        1500,
        0.0,
        UpAxis::Y,
        false,
        &patchwork::prep::NoProgress,
    );
    let build_s = t.elapsed().as_secs_f64();
    let patches = mesh_patches(&fine);
    let pieces: Vec<Vec<[u32; 3]>> = patches.iter().map(|m| m.triangles.clone()).collect();
    static_row(&mut md, "bunny, 99 patches", &pieces);
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    for (file, label) in [
        ("teapot.bpt", "teapot (Bézier), ½ px"),
        ("as1-oc-214.stp", "as1 (trimmed NURBS), ½ px"),
    ] {
        let scene = patchwork::prep::load(&root.join("models").join(file)).expect("model");
        let v = View::framing(&scene.bounds, scene.up.vector(), fov, (1024, 768));
        let meshes = patchwork::tessellate::tessellate_scene(&scene, &v, view::DEFAULT_PIXEL_ERROR);
        let pieces: Vec<Vec<[u32; 3]>> = meshes
            .iter()
            .map(|m| m.triangles.clone())
            .filter(|t| !t.is_empty())
            .collect();
        static_row(&mut md, label, &pieces);
    }
    eprintln!("static done");

    // 2. Incremental repair along every patch's whole node order and back.
    let _ = writeln!(
        md,
        "\n## 2. Incremental repair (bunny, 99 unreduced patch hierarchies built in {build_s:.1} s; \
         every node applied then undone one at a time)\n\n\
         | variant | operations | µs per operation | mean strips (sum over patches) | strips at the coarsest level | from scratch there | strips back at the finest | from scratch there |\n\
         |---|---|---|---|---|---|---|---|"
    );
    let variants = [
        ("T 20, E 5 (default)", TunnelOptions::default()),
        (
            "T 50, E 10",
            TunnelOptions {
                repair_len: 50,
                extra: 10,
                ..TunnelOptions::default()
            },
        ),
        (
            "T 10, E 5",
            TunnelOptions {
                repair_len: 10,
                extra: 5,
                ..TunnelOptions::default()
            },
        ),
        (
            "local only (T 1, E 0)",
            TunnelOptions {
                repair_len: 1,
                extra: 0,
                ..TunnelOptions::default()
            },
        ),
    ];
    for (name, opts) in variants {
        let (mut ops, mut secs, mut strip_sum, mut samples) = (0usize, 0.0f64, 0usize, 0usize);
        let (mut coarse, mut coarse_scratch, mut back, mut back_scratch) = (0, 0, 0, 0);
        for m in &patches {
            let h: &MtHierarchy = &m.hierarchy;
            let mut cs = CutStrips::new(h, opts.clone());
            let top = h.order.len();
            let t = Instant::now();
            while cs.step(h, true) {
                ops += 1;
                strip_sum += cs.strips.strip_count();
                samples += 1;
            }
            secs += t.elapsed().as_secs_f64();
            coarse += cs.strips.strip_count();
            let mut cut = Vec::new();
            h.cut(f64::MAX, &mut cut);
            coarse_scratch += stripify(&cut, &TunnelOptions::default()).strips;
            let t = Instant::now();
            while cs.step(h, false) {
                ops += 1;
                strip_sum += cs.strips.strip_count();
                samples += 1;
            }
            secs += t.elapsed().as_secs_f64();
            let _ = top;
            back += cs.strips.strip_count();
            back_scratch += stripify(&m.triangles, &TunnelOptions::default()).strips;
        }
        let per_patch_mean = strip_sum as f64 / samples.max(1) as f64 * patches.len() as f64;
        let _ = writeln!(
            md,
            "| {name} | {ops} | {:.1} | {:.0} | {coarse} | {coarse_scratch} | {back} | {back_scratch} |",
            secs * 1e6 / ops.max(1) as f64,
            per_patch_mean
        );
        eprintln!("{name} done");
    }

    // 3. Per resolution: what each option sends.
    let scene = patchwork::prep::mesh_scene(
        whole.clone(),
        1500,
        patchwork::mt::DEFAULT_ARC_SIZE,
        UpAxis::Y,
        false,
        &patchwork::prep::NoProgress,
    );
    let patches = mesh_patches(&scene);
    let t = Instant::now();
    let mut mts: Vec<MultiresStrips> = patches
        .iter()
        .map(|m| MultiresStrips::build(&m.hierarchy, &TunnelOptions::default()))
        .collect();
    let mts_build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let arcs: Vec<(patchwork::strips::StripIndices, Vec<u32>)> = patches
        .iter()
        .map(|m| arc_strips(&m.hierarchy, &TunnelOptions::default()))
        .collect();
    let arc_build = t.elapsed().as_secs_f64();
    let occ: usize = mts.iter().map(|m| m.occurrences()).sum();
    let arc_idx: usize = arcs.iter().map(|a| a.0.indices.len()).sum();
    let _ = writeln!(
        md,
        "\n## 3. Indices sent per resolution (bunny, 99 patches reduced to {} triangles per arc; \
         MTS built in {:.2} s, {occ} occurrences; per-arc strips built in {:.2} s, {arc_idx} indices)\n\n\
         | distance | triangles | list | static per-arc strips | MTS | re-stripified cut (tunneling) | MTS extract ms (walk all / coherent, dolly step) | re-stripify ms |\n\
         |---|---|---|---|---|---|---|---|",
        patchwork::mt::DEFAULT_ARC_SIZE,
        mts_build,
        arc_build
    );
    let base = View::framing(&scene.bounds, scene.up.vector(), fov, (1024, 768));
    let dir = base.eye - base.target;
    let mut out = Vec::new();
    for k in [1.0f64, 2.0, 4.0] {
        let eye = base.target + dir * k;
        let v = View::new(eye, base.target, base.up, fov, (1024, 768), &scene.bounds);
        let (mut tris, mut list, mut per_arc, mut mts_idx, mut re_idx) = (0, 0, 0, 0, 0);
        let (mut re_s, mut walk_s, mut coh_s) = (0.0, 0.0, 0.0);
        for (i, (p, m)) in scene.patches.iter().zip(&patches).enumerate() {
            let eps = v.eps_obj(&p.bounds, view::DEFAULT_PIXEL_ERROR);
            let h = &m.hierarchy;
            let mut cut = Vec::new();
            h.cut(eps, &mut cut);
            tris += cut.len();
            list += 3 * cut.len();
            let mut state = h.finest_cut();
            h.move_cut(&mut state, eps);
            let mut ranges = Vec::new();
            h.cut_ranges(&state, &mut ranges);
            for &[start, count] in &ranges {
                let a = h.arc_start.partition_point(|&x| x < start);
                let b = h.arc_start.partition_point(|&x| x < start + count);
                per_arc += (arcs[i].1[b] - arcs[i].1[a]) as usize;
            }
            let level = MultiresStrips::level_for(h, eps);
            // Dolly: 20 frames approaching this distance from 5 % farther; coherent vs not.
            let steps: Vec<usize> = (0..20)
                .map(|f| {
                    let e = eps * (1.05 - 0.05 * f as f64 / 19.0);
                    MultiresStrips::level_for(h, e)
                })
                .collect();
            let t = Instant::now();
            for &l in &steps {
                mts[i].extract(l, false, &mut out);
            }
            walk_s += t.elapsed().as_secs_f64() / steps.len() as f64;
            mts[i].extract(steps[0], false, &mut out);
            let t = Instant::now();
            for &l in &steps {
                mts[i].extract(l, true, &mut out);
            }
            coh_s += t.elapsed().as_secs_f64() / steps.len() as f64;
            mts[i].extract(level, false, &mut out);
            mts_idx += out.len() + 1;
            let t = Instant::now();
            let s = stripify(&cut, &TunnelOptions::default());
            re_s += t.elapsed().as_secs_f64();
            re_idx += s.indices.len() + 1;
        }
        let f = |x: usize| format!("{x} ({:.2}/tri)", x as f64 / tris.max(1) as f64);
        let _ = writeln!(
            md,
            "| {k}× | {tris} | {} | {} | {} | {} | {:.2} / {:.2} | {:.1} |",
            f(list),
            f(per_arc),
            f(mts_idx),
            f(re_idx),
            walk_s * 1e3,
            coh_s * 1e3,
            re_s * 1e3
        );
    }
    println!("{md}");
    let path = root.join("target/strips.md");
    let _ = std::fs::write(&path, &md);
    eprintln!("written to {}", path.display());
}
