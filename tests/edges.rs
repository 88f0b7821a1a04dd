//! Edges of the model (issue 32): `render --edges feature|all|off` draws the border polylines
//! of the frame as dark lines, depth-tested; `feature` leaves out edges between faces that
//! meet smoothly. Judged from outside the classification: the models' edges are known
//! analytically (a 20 mm cube, a box with one rounded edge — `tools/edge_models.py`), the
//! drawn segments are matched to them on the CPU (`render::edges::segments`, the shader's
//! twin), and the images are read back and sampled along each edge's projection.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DVec3, Vec3};
use patchwork::lod::{FrameLoop, LodOptions};
use patchwork::render::edges::segments;
use patchwork::render::{BorderGeometry, Edges, RenderOptions, ResidentGeometry, Shading};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::View;

const SIZE: (u32, u32) = (400, 300);
const FOV_DEG: f64 = 45.0;
/// Edge pixels are near black (`EDGE_COLOR` 0.06) where a line covers the pixel, about half
/// that where 4× MSAA puts half its samples on a 1 px line (≈ 135 over the background); flat
/// surfaces' brightest channel is 212, the background 255: a pixel whose channels are all
/// below this is an edge's.
const DARK: u8 = 170;

/// A straight edge of a model, with the unit normals of its two faces (outwards).
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: DVec3,
    b: DVec3,
    faces: [DVec3; 2],
}

/// The 12 edges of the cube [0, 20]³ with their faces' normals.
fn cube_edges() -> Vec<Edge> {
    let mut edges = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for (su, sv) in [(0.0, 0.0), (0.0, 20.0), (20.0, 0.0), (20.0, 20.0)] {
            let mut a = DVec3::ZERO;
            a[u] = su;
            a[v] = sv;
            let mut b = a;
            b[axis] = 20.0;
            let normal = |k: usize, s: f64| {
                let mut n = DVec3::ZERO;
                n[k] = if s > 0.0 { 1.0 } else { -1.0 };
                n
            };
            edges.push(Edge {
                a,
                b,
                faces: [normal(u, su), normal(v, sv)],
            });
        }
    }
    edges
}

/// Whether `p` lies on the segment `e` (within `tol`).
fn on(e: &Edge, p: Vec3, tol: f64) -> bool {
    let p = p.as_dvec3();
    let ab = e.b - e.a;
    let t = ((p - e.a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(e.a + ab * t) <= tol
}

/// For each of `edges`, the total length of the drawn segments lying on it; panics when a
/// segment lies on none of them.
fn covered(drawn: &[[Vec3; 2]], edges: &[Edge]) -> Vec<f64> {
    let mut length = vec![0.0; edges.len()];
    for s in drawn {
        let k = edges
            .iter()
            .position(|e| on(e, s[0], 1e-4) && on(e, s[1], 1e-4))
            .unwrap_or_else(|| panic!("segment {s:?} lies on no edge of the model"));
        length[k] += s[0].distance(s[1]) as f64;
    }
    length
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_patchwork"))
}

/// `patchwork render MODEL --edges MODE` with flat shading and an explicit camera; the image.
fn render(model: &str, edges: &str, eye: DVec3, target: DVec3, name: &str) -> image::RgbImage {
    let out = common::scratch("edges").join(format!("{name}.png"));
    let v = |p: DVec3| format!("{},{},{}", p.x, p.y, p.z);
    let o = bin()
        .arg("render")
        .arg(common::root().join("models").join(model))
        .args(["-o", out.to_str().expect("utf-8")])
        .args(["--edges", edges, "--shading", "flat", "-q"])
        .args(["--size", &format!("{}x{}", SIZE.0, SIZE.1)])
        .args(["--eye", &v(eye), "--target", &v(target), "--up", "0,0,1"])
        .args(["--fov", &FOV_DEG.to_string()])
        .output()
        .expect("patchwork runs");
    assert!(
        o.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    image::open(&out).expect("image written").to_rgb8()
}

/// The camera of [`render`] as a [`View`].
fn view_of(model: &str, eye: DVec3, target: DVec3) -> View {
    let scene = common::load(model);
    View::new(
        eye,
        target,
        DVec3::Z,
        FOV_DEG.to_radians(),
        SIZE,
        &scene.bounds,
    )
}

/// The darkest luminance in the 3 × 3 pixels around pixel position `(x, y)`.
fn darkest_near(img: &image::RgbImage, (x, y): (f64, f64)) -> u8 {
    let (cx, cy) = (x.floor() as i64, y.floor() as i64);
    let mut dark = u8::MAX;
    for j in cy - 1..=cy + 1 {
        for i in cx - 1..=cx + 1 {
            if i >= 0 && j >= 0 && (i as u32) < img.width() && (j as u32) < img.height() {
                let p = img.get_pixel(i as u32, j as u32).0;
                dark = dark.min(p.into_iter().max().unwrap_or(0));
            }
        }
    }
    dark
}

/// Pixel positions of points of `e` at fractions `from..=to` (steps of 0.05).
fn samples(view: &View, e: &Edge, from: f64, to: f64) -> Vec<(f64, f64)> {
    let n = ((to - from) / 0.05).round() as usize;
    (0..=n)
        .filter_map(|k| {
            let t = from + (to - from) * k as f64 / n as f64;
            view.project(e.a.lerp(e.b, t)).map(|(x, y, _)| (x, y))
        })
        .collect()
}

/// Distance in pixels from `p` to the projection of `e`.
fn pixels_from(view: &View, e: &Edge, p: (f64, f64)) -> f64 {
    let (Some(a), Some(b)) = (view.project(e.a), view.project(e.b)) else {
        return f64::INFINITY;
    };
    let (a, b, p) = (
        glam::DVec2::new(a.0, a.1),
        glam::DVec2::new(b.0, b.1),
        glam::DVec2::new(p.0, p.1),
    );
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Whether `e` faces the eye on at least one side (on a convex solid: it is not hidden).
fn seen(e: &Edge, eye: DVec3) -> bool {
    e.faces.iter().any(|n| n.dot(eye - e.a) > 0.0)
}

/// Checks `img` along `edges`: every sample of a visible edge has a dark pixel within one
/// pixel; no sample of a hidden one does (samples within 3 px of a visible edge's
/// projection are left out: there the visible edge's pixels are). Returns the messages of
/// what failed.
fn check_image(
    img: &image::RgbImage,
    view: &View,
    visible: &[Edge],
    hidden: &[Edge],
) -> Vec<String> {
    let mut failed = Vec::new();
    for e in visible {
        for p in samples(view, e, 0.1, 0.9) {
            let d = darkest_near(img, p);
            if d >= DARK {
                failed.push(format!(
                    "visible edge {e:?}: no edge pixel at {p:?} (darkest {d})"
                ));
            }
        }
    }
    for e in hidden {
        for p in samples(view, e, 0.05, 0.95) {
            if visible.iter().any(|v| pixels_from(view, v, p) < 3.0) {
                continue;
            }
            let d = darkest_near(img, p);
            if d < DARK {
                failed.push(format!("hidden edge {e:?}: edge pixel at {p:?} ({d})"));
            }
        }
    }
    failed
}

const CUBE_EYE: DVec3 = DVec3::new(50.0, -40.0, 45.0);
const CUBE_TARGET: DVec3 = DVec3::new(10.0, 10.0, 10.0);

#[test]
fn a_cube_draws_its_twelve_edges_once_from_each_face() {
    let scene = common::load("edges/cube.step");
    let view = view_of("edges/cube.step", CUBE_EYE, CUBE_TARGET);
    let meshes = tessellate_scene(&scene, &view, 0.5);
    let points = BorderGeometry::of(&meshes).points;
    for mode in [Edges::Feature, Edges::All] {
        let drawn = segments(&points, mode);
        let length = covered(&drawn, &cube_edges());
        // Every edge drawn along its whole length by each of its two faces.
        for (e, l) in cube_edges().iter().zip(&length) {
            assert!(
                (l - 40.0).abs() < 1e-3,
                "{mode:?}: edge {e:?} drawn over {l} mm"
            );
        }
        assert_eq!(length.len(), 12);
    }
    assert!(segments(&points, Edges::Off).is_empty());
}

#[test]
fn cube_edges_show_where_visible_and_stay_hidden_behind_faces() {
    let view = view_of("edges/cube.step", CUBE_EYE, CUBE_TARGET);
    let (visible, hidden): (Vec<Edge>, Vec<Edge>) =
        cube_edges().into_iter().partition(|e| seen(e, CUBE_EYE));
    assert_eq!((visible.len(), hidden.len()), (9, 3));
    for mode in ["feature", "all"] {
        let img = render(
            "edges/cube.step",
            mode,
            CUBE_EYE,
            CUBE_TARGET,
            &format!("cube-{mode}"),
        );
        let failed = check_image(&img, &view, &visible, &hidden);
        assert!(failed.is_empty(), "--edges {mode}:\n{}", failed.join("\n"));
    }
    // Without edges no sample is dark: the judge sees the lines, not the shading.
    let img = render("edges/cube.step", "off", CUBE_EYE, CUBE_TARGET, "cube-off");
    let failed = check_image(&img, &view, &[], &cube_edges());
    assert!(failed.is_empty(), "--edges off:\n{}", failed.join("\n"));
    // And the judge fails a drawing that misses an edge: with --edges off every visible
    // edge is reported.
    assert!(check_image(&img, &view, &visible, &[]).len() >= 9 * 17);
}

#[test]
fn edges_off_draws_the_same_image_as_before() {
    let eye = CUBE_EYE;
    let with_flag = render("edges/cube.step", "off", eye, CUBE_TARGET, "off-flag");
    let out = common::scratch("edges").join("off-default.png");
    let v = |p: DVec3| format!("{},{},{}", p.x, p.y, p.z);
    let o = bin()
        .arg("render")
        .arg(common::root().join("models/edges/cube.step"))
        .args([
            "-o",
            out.to_str().expect("utf-8"),
            "--shading",
            "flat",
            "-q",
        ])
        .args(["--size", &format!("{}x{}", SIZE.0, SIZE.1)])
        .args([
            "--eye",
            &v(eye),
            "--target",
            &v(CUBE_TARGET),
            "--up",
            "0,0,1",
        ])
        .args(["--fov", &FOV_DEG.to_string()])
        .output()
        .expect("patchwork runs");
    assert!(o.status.success());
    let default = image::open(&out).expect("written").to_rgb8();
    assert!(with_flag == default, "--edges off is the default drawing");
}

/// The box of `tools/edge_models.py`: 40 × 30 × 20 mm, its top front edge rounded with
/// radius 6 mm. The two edges where the round meets the top and the front are smooth; the
/// other straight edges sharp.
fn fillet_tangent_edges() -> [Edge; 2] {
    let along = |y: f64, z: f64, faces: [DVec3; 2]| Edge {
        a: DVec3::new(0.0, y, z),
        b: DVec3::new(40.0, y, z),
        faces,
    };
    // Normals of the top (+z) and the front (−y): the round's own along each line.
    [
        along(6.0, 20.0, [DVec3::Z, DVec3::Z]),
        along(0.0, 14.0, [-DVec3::Y, -DVec3::Y]),
    ]
}

fn fillet_sharp_edges() -> Vec<Edge> {
    let x = |y: f64, z: f64, faces| Edge {
        a: DVec3::new(0.0, y, z),
        b: DVec3::new(40.0, y, z),
        faces,
    };
    let z = |px: f64, py: f64, top: f64, faces| Edge {
        a: DVec3::new(px, py, 0.0),
        b: DVec3::new(px, py, top),
        faces,
    };
    let y = |px: f64, pz: f64, from: f64, faces| Edge {
        a: DVec3::new(px, from, pz),
        b: DVec3::new(px, 30.0, pz),
        faces,
    };
    vec![
        x(30.0, 20.0, [DVec3::Z, DVec3::Y]),
        x(0.0, 0.0, [-DVec3::Y, -DVec3::Z]),
        x(30.0, 0.0, [DVec3::Y, -DVec3::Z]),
        z(40.0, 0.0, 14.0, [DVec3::X, -DVec3::Y]),
        z(0.0, 0.0, 14.0, [-DVec3::X, -DVec3::Y]),
        z(40.0, 30.0, 20.0, [DVec3::X, DVec3::Y]),
        z(0.0, 30.0, 20.0, [-DVec3::X, DVec3::Y]),
        y(40.0, 20.0, 6.0, [DVec3::X, DVec3::Z]),
        y(0.0, 20.0, 6.0, [-DVec3::X, DVec3::Z]),
        y(40.0, 0.0, 0.0, [DVec3::X, -DVec3::Z]),
        y(0.0, 0.0, 0.0, [-DVec3::X, -DVec3::Z]),
    ]
}

const FILLET_EYE: DVec3 = DVec3::new(80.0, -60.0, 55.0);
const FILLET_TARGET: DVec3 = DVec3::new(20.0, 15.0, 10.0);

#[test]
fn a_rounded_edge_is_smooth_feature_hides_its_tangent_edges_and_all_shows_them() {
    let model = "edges/box_fillet.step";
    let scene = common::load(model);
    let view = view_of(model, FILLET_EYE, FILLET_TARGET);
    let meshes = tessellate_scene(&scene, &view, 0.5);
    let points = BorderGeometry::of(&meshes).points;
    let tangent = fillet_tangent_edges();
    let sharp = fillet_sharp_edges();
    let on_any = |s: &[Vec3; 2], edges: &[Edge]| {
        edges.iter().any(|e| on(e, s[0], 1e-4) && on(e, s[1], 1e-4))
    };
    let length_on = |drawn: &[[Vec3; 2]], e: &Edge| -> f64 {
        drawn
            .iter()
            .filter(|s| on_any(s, std::slice::from_ref(e)))
            .map(|s| s[0].distance(s[1]) as f64)
            .sum()
    };
    let feature = segments(&points, Edges::Feature);
    let all = segments(&points, Edges::All);
    for e in &tangent {
        assert_eq!(
            length_on(&feature, e),
            0.0,
            "feature draws smooth edge {e:?}"
        );
        let l = length_on(&all, e);
        assert!((l - 80.0).abs() < 1e-3, "all draws {e:?} over {l} mm");
    }
    for e in &sharp {
        for (mode, drawn) in [("feature", &feature), ("all", &all)] {
            let l = length_on(drawn, e);
            let full = 2.0 * e.a.distance(e.b);
            assert!(
                (l - full).abs() < 1e-3,
                "{mode} draws sharp {e:?} over {l} mm"
            );
        }
    }
    // The only segments `all` adds are the tangent edges'.
    assert!(
        all.iter()
            .filter(|s| !feature.contains(s))
            .all(|s| on_any(s, &tangent))
    );

    // On the image: the tangent edges show with `all` only, the sharp ones in both.
    let visible_sharp: Vec<Edge> = sharp
        .iter()
        .copied()
        .filter(|e| seen(e, FILLET_EYE))
        .collect();
    assert!(visible_sharp.len() >= 6);
    let img = render(model, "all", FILLET_EYE, FILLET_TARGET, "fillet-all");
    let mut shown: Vec<Edge> = visible_sharp.clone();
    shown.extend(tangent);
    let failed = check_image(&img, &view, &shown, &[]);
    assert!(failed.is_empty(), "--edges all:\n{}", failed.join("\n"));
    let img = render(
        model,
        "feature",
        FILLET_EYE,
        FILLET_TARGET,
        "fillet-feature",
    );
    let failed = check_image(&img, &view, &visible_sharp, &tangent);
    assert!(failed.is_empty(), "--edges feature:\n{}", failed.join("\n"));
}

/// A binary STL of the cube [0, 20]³ (two triangles per face, no normals): its 12 edges are
/// creases (90°), the faces' diagonals are not.
fn write_stl_cube(path: &Path) {
    let c = |i: u32| {
        Vec3::new(
            (i & 1) as f32 * 20.0,
            ((i >> 1) & 1) as f32 * 20.0,
            ((i >> 2) & 1) as f32 * 20.0,
        )
    };
    // Faces as corner quads (outward winding).
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&12u32.to_le_bytes());
    for q in quads {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            bytes.extend_from_slice(&[0u8; 12]);
            for v in t {
                for x in c(v).to_array() {
                    bytes.extend_from_slice(&x.to_le_bytes());
                }
            }
            bytes.extend_from_slice(&[0u8; 2]);
        }
    }
    std::fs::write(path, bytes).expect("scratch writable");
}

#[test]
fn a_mesh_draws_its_creases_not_its_diagonals() {
    let path: PathBuf = common::scratch("edges").join("cube.stl");
    write_stl_cube(&path);
    let scene = patchwork::prep::load(&path).expect("loads");
    let view = View::new(
        CUBE_EYE,
        CUBE_TARGET,
        DVec3::Z,
        FOV_DEG.to_radians(),
        SIZE,
        &scene.bounds,
    );
    let meshes = tessellate_scene(&scene, &view, 0.5);
    let points = BorderGeometry::of(&meshes).points;
    for mode in [Edges::Feature, Edges::All] {
        // Panics on a segment off the 12 edges (a diagonal, a cut between patches).
        let length = covered(&segments(&points, mode), &cube_edges());
        for (e, l) in cube_edges().iter().zip(&length) {
            assert!(
                (l - 40.0).abs() < 1e-3,
                "{mode:?}: crease {e:?} drawn over {l}"
            );
        }
    }
}

/// The frame loop's path: resident geometry, instanced parts drawn once per placement
/// (`vs_edge_placed`). Its edges land where those of world-space copies do, and are there.
#[test]
fn placed_parts_draw_their_edges_where_copies_do() {
    let scene = common::load("as1-oc-214.stp");
    let mut renderer = common::renderer();
    let view = View::framing(&scene.bounds, scene.up.vector(), FOV_DEG.to_radians(), SIZE);
    let lod = FrameLoop::new(&scene, &view, LodOptions::default());
    assert!(lod.shared_meshes().any(|(_, m)| m.instance.is_some()));
    let mut draw = |instances: bool, edges: Edges| {
        renderer.instances = instances;
        let mut resident = ResidentGeometry::new(&renderer);
        resident
            .update(&renderer, lod.shared_meshes(), lod.generation())
            .expect("fits");
        let opts = RenderOptions {
            shading: Shading::Flat,
            edges,
            ..RenderOptions::default()
        };
        let frame = renderer.render(&resident, &view, &opts).expect("renders");
        frame
            .color
            .chunks_exact(4)
            .map(|p| p[..3].iter().all(|&c| c < DARK))
            .collect::<Vec<bool>>()
    };
    let placed = draw(true, Edges::Feature);
    let copies = draw(false, Edges::Feature);
    let off = draw(true, Edges::Off);
    let count = |m: &[bool]| m.iter().filter(|&&d| d).count();
    let differ = placed.iter().zip(&copies).filter(|(a, b)| a != b).count();
    assert!(
        count(&off) == 0,
        "{} dark pixels without edges",
        count(&off)
    );
    assert!(count(&copies) > 1000, "{} edge pixels", count(&copies));
    assert!(
        differ * 50 <= count(&copies),
        "{differ} of {} edge pixels differ between placements and copies",
        count(&copies)
    );
}

/// Where a model's surface shows, its edges show in full: every sample of every segment the
/// frame draws (`segments`, on curved faces too) that the depth image says is not behind
/// another surface has an edge pixel within one pixel. Without the pull towards the viewer
/// the lines lie in their own triangles and behind their neighbours' (a concave edge's
/// chords stand in front of it): about a fifth of such samples then show no line.
#[test]
fn edges_show_wherever_their_surface_does() {
    let mut renderer = common::renderer();
    for model in ["nist_ctc_01_asme1_rd.stp", "teapot.bpt", "screw.step"] {
        let scene = common::load(model);
        let view = View::framing(
            &scene.bounds,
            scene.up.vector(),
            FOV_DEG.to_radians(),
            (600, 450),
        );
        let meshes = tessellate_scene(&scene, &view, 0.5);
        let gpu = renderer.upload(&meshes);
        let opts = RenderOptions {
            shading: Shading::Flat,
            edges: Edges::All,
            msaa: 4,
            ..RenderOptions::default()
        };
        let color = renderer.render(&gpu, &view, &opts).expect("renders");
        let depth = renderer
            .render(
                &gpu,
                &view,
                &RenderOptions {
                    depth: true,
                    msaa: 1,
                    ..opts
                },
            )
            .expect("renders")
            .depth
            .expect("depth asked");
        let img = image::RgbImage::from_fn(color.width, color.height, |x, y| {
            let p = color.pixel(x, y);
            image::Rgb([p[0], p[1], p[2]])
        });
        let (w, h) = (color.width as i64, color.height as i64);
        let (mut seen, mut missing) = (0, Vec::new());
        // 7 samples per segment: straight edges are one segment each since issue 31 item 3
        // (3 per segment left screw.step 269 visible samples, too few to judge by).
        for s in segments(&BorderGeometry::of(&meshes).points, Edges::All) {
            for t in [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875] {
                let p = s[0].lerp(s[1], t).as_dvec3();
                let Some((x, y, d)) = view.project(p) else {
                    continue;
                };
                // In front of (or on) the nearest surface around it, within 2 pixels' depth.
                let (cx, cy) = (x.floor() as i64, y.floor() as i64);
                let mut nearest = f64::INFINITY;
                for j in cy - 1..=cy + 1 {
                    for i in cx - 1..=cx + 1 {
                        if (0..w).contains(&i) && (0..h).contains(&j) {
                            nearest = nearest.min(depth[(j * w + i) as usize] as f64);
                        }
                    }
                }
                if !(x >= 1.0 && y >= 1.0 && x < (w - 1) as f64 && y < (h - 1) as f64)
                    || d > nearest + 2.0 * view.pixel_size_at(d)
                {
                    continue;
                }
                seen += 1;
                if darkest_near(&img, (x, y)) >= DARK {
                    missing.push((x, y));
                }
            }
        }
        eprintln!(
            "{model}: {} of {seen} visible samples show no line",
            missing.len()
        );
        assert!(seen > 300, "{model}: {seen} visible samples");
        assert!(
            missing.len() * 100 <= seen,
            "{model}: {} of {seen} visible edge samples show no line, e.g. {:?}",
            missing.len(),
            &missing[..missing.len().min(5)]
        );
    }
}
