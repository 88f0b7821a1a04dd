//! Section planes (`render --section`, `render::section`): a cylinder cut along its axis and
//! across it shows a flat cap in the part's colour where the cut is (filled, one colour, at the
//! plane's depth, outlined as the rectangle / disc it is), a plane that misses the model changes
//! no pixel, the crack check holds on the capped image, and bad planes are typed errors.

mod common;

use std::process::Command;

use glam::DVec3;
use patchwork::check::crack::{SENTINEL, check_render_options, classify, reference_meshes};
use patchwork::model::Scene;
use patchwork::render::{FatBorders, Frame, RenderOptions, SectionPlane, Sections};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::View;

const PIXEL_ERROR: f64 = 0.5;

fn cylinder() -> Scene {
    common::load("cylinder.step")
}

fn plane(point: DVec3, normal: DVec3) -> Sections {
    Sections::new(&[SectionPlane::new(point, normal, "test").expect("a valid plane")])
        .expect("one plane")
}

/// An orthographic view 60 units tall looking from `eye` at `target`.
fn ortho(scene: &Scene, eye: DVec3, target: DVec3, up: DVec3) -> View {
    View::new(eye, target, up, 0.5, (160, 160), &scene.bounds)
        .with_ortho_height(60.0, &scene.bounds)
}

fn render(scene: &Scene, view: &View, sections: Sections, fat_borders: FatBorders) -> Frame {
    let mut r = common::renderer();
    let meshes = tessellate_scene(scene, view, PIXEL_ERROR);
    let gpu = r.upload(&meshes);
    let opts = RenderOptions {
        msaa: 1,
        depth: true,
        fat_borders,
        sections,
        ..RenderOptions::default()
    };
    r.render(&gpu, view, &opts).expect("renders")
}

fn save(frame: &Frame, name: &str) {
    let path = common::scratch("section").join(format!("{name}.png"));
    frame
        .to_rgba_image()
        .save(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// Checks the cap: every pixel whose centre `inside(x, y)` says is ≥ 1.5 px within the cap
/// shows one colour (not the background) at depth `depth`; every pixel `outside` shows the
/// background. Returns the cap colour.
fn check_cap(
    frame: &Frame,
    name: &str,
    depth: f64,
    inside: impl Fn(f64, f64) -> bool,
    outside: impl Fn(f64, f64) -> bool,
) -> [u8; 4] {
    let depths = frame.depth.as_ref().expect("depth was asked for");
    let bg = [255, 255, 255, 255];
    let mut cap: Option<[u8; 4]> = None;
    let mut inside_pixels = 0;
    for y in 0..frame.height {
        for x in 0..frame.width {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let px = frame.pixel(x, y);
            if inside(cx, cy) {
                inside_pixels += 1;
                let c = *cap.get_or_insert(px);
                if px != c || c == bg {
                    save(frame, &format!("{name}-actual"));
                    panic!(
                        "{name}: pixel ({x}, {y}) inside the cap is {px:?}, not the cap's {c:?}"
                    );
                }
                let d = f64::from(depths[(y * frame.width + x) as usize]);
                assert!(
                    (d - depth).abs() < 1e-3 * depth,
                    "{name}: pixel ({x}, {y}) inside the cap at depth {d}, the plane is at {depth}"
                );
            } else if outside(cx, cy) && px != bg {
                save(frame, &format!("{name}-actual"));
                panic!("{name}: pixel ({x}, {y}) outside the cap is {px:?}, not the background");
            }
        }
    }
    assert!(
        inside_pixels > 1000,
        "{name}: only {inside_pixels} cap pixels"
    );
    cap.expect("cap pixels")
}

#[test]
fn cylinder_cut_along_its_axis_shows_a_capped_rectangle() {
    let scene = cylinder();
    // Looking along +x at the cut x = 0 (the x < 0 half kept, its seam at x = +10 removed... and
    // the x > 0 half kept in the second run: its seam's fat border runs down the cap's middle).
    for (sign, name) in [(1.0, "rectangle"), (-1.0, "rectangle-seam")] {
        let eye = DVec3::new(100.0 * sign, 0.0, 20.0);
        let view = ortho(&scene, eye, DVec3::new(0.0, 0.0, 20.0), DVec3::Z);
        let frame = render(
            &scene,
            &view,
            plane(DVec3::ZERO, DVec3::X * sign),
            FatBorders::Six,
        );
        save(&frame, name);
        // The cap is the rectangle |y| ≤ 10, 0 ≤ z ≤ 40 on the plane x = 0.
        let (x0, y0, depth) = view.project(DVec3::new(0.0, -10.0, 40.0)).expect("in view");
        let (x1, y1, _) = view.project(DVec3::new(0.0, 10.0, 0.0)).expect("in view");
        let (lo, hi) = (
            DVec3::new(x0.min(x1), y0.min(y1), 0.0),
            DVec3::new(x0.max(x1), y0.max(y1), 0.0),
        );
        let within =
            |x: f64, y: f64, m: f64| x > lo.x + m && x < hi.x - m && y > lo.y + m && y < hi.y - m;
        check_cap(
            &frame,
            name,
            depth,
            |x, y| within(x, y, 1.5),
            |x, y| !within(x, y, -1.5),
        );
        // Without the plane the same pixels show the lit outside of the cylinder: not one
        // colour (so the check above can tell a cap from the surface).
        let uncut = render(&scene, &view, Sections::NONE, FatBorders::Six);
        let colours: std::collections::HashSet<[u8; 4]> = (0..uncut.height)
            .flat_map(|y| (0..uncut.width).map(move |x| (x, y)))
            .filter(|&(x, y)| within(x as f64 + 0.5, y as f64 + 0.5, 1.5))
            .map(|(x, y)| uncut.pixel(x, y))
            .collect();
        assert!(
            colours.len() > 10,
            "{name}: the uncut side shows {} colours",
            colours.len()
        );
    }
}

#[test]
fn cylinder_cut_across_shows_a_capped_disc() {
    let scene = cylinder();
    // Looking down at the cut z = 20, the lower half kept.
    let view = ortho(
        &scene,
        DVec3::new(0.0, 0.0, 100.0),
        DVec3::new(0.0, 0.0, 20.0),
        DVec3::Y,
    );
    let frame = render(
        &scene,
        &view,
        plane(DVec3::new(0.0, 0.0, 20.0), DVec3::Z),
        FatBorders::Six,
    );
    save(&frame, "disc");
    let (cx, cy, depth) = view.project(DVec3::new(0.0, 0.0, 20.0)).expect("in view");
    let (ex, _, _) = view.project(DVec3::new(10.0, 0.0, 20.0)).expect("in view");
    let r = (ex - cx).abs();
    let dist = |x: f64, y: f64| ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
    let cap = check_cap(
        &frame,
        "disc",
        depth,
        |x, y| dist(x, y) < r - 1.5,
        |x, y| dist(x, y) > r + 1.5,
    );
    // Uncut, the top face at z = 40 shows (flat too, but 20 units nearer).
    let uncut = render(&scene, &view, Sections::NONE, FatBorders::Six);
    let d = uncut.depth.as_ref().expect("depth")[(cy as u32 * uncut.width + cx as u32) as usize];
    assert!(
        (f64::from(d) - (depth - 20.0)).abs() < 1e-2,
        "uncut depth {d}, cap depth {depth}"
    );
    // The cap is lit by the plane's normal, facing the viewer as the top face does: the same
    // flat colour.
    assert_eq!(uncut.pixel(cx as u32, cy as u32), cap);
}

#[test]
fn a_plane_that_misses_the_model_changes_nothing() {
    let scene = cylinder();
    let view = common::golden_view(&scene, None);
    let plain = render(&scene, &view, Sections::NONE, FatBorders::Six);
    // Beyond the model on the removed side, and on the kept side with the whole model behind.
    for s in [
        plane(DVec3::new(50.0, 0.0, 0.0), DVec3::X),
        plane(DVec3::new(0.0, 0.0, -5.0), DVec3::NEG_Z),
    ] {
        let cut = render(&scene, &view, s, FatBorders::Six);
        assert!(plain.color == cut.color, "{s:?}: the image changed");
        assert!(plain.depth == cut.depth, "{s:?}: the depth changed");
    }
    // And a plane through it does change it (the comparison above can fail).
    let cut = render(&scene, &view, plane(DVec3::ZERO, DVec3::X), FatBorders::Six);
    assert!(plain.color != cut.color);
}

/// The crack check (`check::crack::classify`) on sectioned images: the watertight reference
/// and the independently tessellated model, both cut and capped by the same planes.
#[test]
fn crack_check_holds_on_capped_images() {
    for (model, planes) in [
        (
            "cylinder.step",
            vec![SectionPlane::new(DVec3::ZERO, DVec3::new(1.0, -1.0, 0.3), "a").expect("plane")],
        ),
        (
            "screw.step",
            vec![
                SectionPlane::new(DVec3::ZERO, DVec3::new(0.0, -1.0, 0.0), "a").expect("plane"),
                SectionPlane::new(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.2), "b").expect("plane"),
            ],
        ),
    ] {
        let scene = common::load(model);
        let c = scene.bounds.center;
        let planes: Vec<SectionPlane> = (planes.iter())
            .map(|p| SectionPlane::new(c + p.point, p.normal, "p").expect("plane"))
            .collect();
        let sections = Sections::new(&planes).expect("planes");
        let view = common::golden_view(&scene, None);
        let mut r = common::renderer();
        let (reference, _) = reference_meshes(&scene, &view, PIXEL_ERROR);
        let ref_gpu = r.upload(&reference);
        let opts = |fb| RenderOptions {
            sections,
            ..check_render_options(fb)
        };
        let ref_frame = r
            .render(&ref_gpu, &view, &opts(FatBorders::Off))
            .expect("renders");
        let meshes = tessellate_scene(&scene, &view, PIXEL_ERROR);
        let gpu = r.upload(&meshes);
        let actual = r
            .render(&gpu, &view, &opts(FatBorders::Six))
            .expect("renders");
        let (counts, mask) =
            classify(&ref_frame, &actual, &view, PIXEL_ERROR, SENTINEL).expect("classifies");
        // The cut is open to the camera: the reference shows caps (flat, the check colour,
        // at the planes' depth), so the population the check judges includes them.
        let full = r
            .render(&ref_gpu, &view, &check_render_options(FatBorders::Off))
            .expect("renders");
        assert!(
            ref_frame.color != full.color,
            "{model}: the planes cut nothing"
        );
        if counts.cracks() > 0 || counts.growth > 0 {
            let dir = common::scratch("section");
            let stem = model.split('.').next().unwrap_or(model);
            save(&actual, &format!("{stem}-crack-actual"));
            mask.save(dir.join(format!("{stem}-crack-diff.png")))
                .expect("writes the mask");
        }
        assert_eq!(counts.cracks(), 0, "{model}: {counts:?}");
        assert_eq!(counts.growth, 0, "{model}: {counts:?}");
        assert!(counts.inside > 5000, "{model}: {counts:?}");
    }
}

fn patchwork(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(args)
        .env("PATCHWORK_CACHE", "off")
        .output()
        .expect("runs patchwork")
}

#[test]
fn cli_renders_sections_and_refuses_bad_planes() {
    let model = common::root().join("models/cylinder.step");
    let model = model.to_str().expect("utf-8 path");
    let dir = common::scratch("section");
    let out = |n: &str| dir.join(n).to_str().expect("utf-8 path").to_owned();
    let (plain, cut) = (out("cli-plain.png"), out("cli-cut.png"));
    let base = ["render", model, "--size", "120x90", "--msaa", "1"];
    let o = patchwork(&[&base[..], &["-o", &plain]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = patchwork(&[&base[..], &["-o", &cut, "--section", "0,0,20,-1,-1,1"]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |p: &str| image::open(p).expect("a PNG").to_rgba8().into_raw();
    assert!(read(&plain) != read(&cut), "--section changed nothing");
    let bad = out("cli-bad.png");
    for (planes, says) in [
        (vec!["0,0,0,0,0,0"], "must not be zero"),
        (vec!["0,0,NaN,1,0,0"], "finite"),
        (vec!["0,0,1,0"], "expected X,Y,Z,NX,NY,NZ"),
        (vec!["0,0,0,1,0,0"; 4], "at most 3 planes, got 4"),
    ] {
        let mut args = vec!["render", model, "-o", &bad];
        for p in &planes {
            args.extend(["--section", p]);
        }
        let o = patchwork(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{planes:?}: {err}");
        assert!(
            err.contains("--section") && err.contains(says),
            "{planes:?}: {err}"
        );
        assert!(
            !std::path::Path::new(&bad).exists(),
            "{planes:?} wrote an image"
        );
    }
}

/// Edges behind a cap are hidden by it: the cap is at its plane's depth in the hardware depth
/// too, not only in the linear-depth target. Looking down at the cylinder cut at z = 20 in
/// perspective, its bottom circle (z = 0) projects inside the cap's disc; with `--edges all` it
/// showed through the cap as a dark ring when the cap kept its back face's depth.
#[test]
fn edges_behind_a_cap_do_not_show_through_it() {
    let scene = cylinder();
    let view = View::new(
        DVec3::new(0.0, 0.0, 100.0),
        DVec3::new(0.0, 0.0, 20.0),
        DVec3::Y,
        0.5,
        (160, 160),
        &scene.bounds,
    );
    let mut r = common::renderer();
    let meshes = tessellate_scene(&scene, &view, PIXEL_ERROR);
    let gpu = r.upload(&meshes);
    let opts = RenderOptions {
        msaa: 1,
        depth: true,
        fat_borders: FatBorders::Six,
        sections: plane(DVec3::new(0.0, 0.0, 20.0), DVec3::Z),
        edges: patchwork::render::Edges::All,
        ..RenderOptions::default()
    };
    let frame = r.render(&gpu, &view, &opts).expect("renders");
    save(&frame, "edges-behind-cap");
    let (cx, cy, _) = view.project(DVec3::new(0.0, 0.0, 20.0)).expect("in view");
    let (ex, _, _) = view.project(DVec3::new(10.0, 0.0, 20.0)).expect("in view");
    let (bx, _, _) = view.project(DVec3::new(10.0, 0.0, 0.0)).expect("in view");
    let (r_cap, r_bottom) = ((ex - cx).abs(), (bx - cx).abs());
    assert!(
        r_bottom < r_cap - 5.0,
        "the bottom circle ({r_bottom} px) should project well inside the cap ({r_cap} px)"
    );
    // In perspective the cap's specular term varies a little across it; an edge is dark.
    let centre = frame.pixel(cx as u32, cy as u32);
    let bg = [255, 255, 255, 255];
    assert_ne!(centre, bg, "no cap at the centre");
    let dist = |x: f64, y: f64| ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
    for y in 0..frame.height {
        for x in 0..frame.width {
            let (px, d) = (frame.pixel(x, y), dist(x as f64 + 0.5, y as f64 + 0.5));
            let off = (0..3).map(|k| px[k].abs_diff(centre[k])).max().unwrap_or(0);
            if (d < r_cap - 2.5 && off > 8) || (d > r_cap + 2.5 && px != bg) {
                save(&frame, "edges-behind-cap-actual");
                panic!(
                    "pixel ({x}, {y}), {d:.1} px from the centre (cap radius {r_cap:.1}, bottom \
                     circle {r_bottom:.1}), is {px:?}; the cap's centre is {centre:?}"
                );
            }
        }
    }
}
