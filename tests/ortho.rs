//! Orthographic views (`--ortho`): sizes do not depend on depth, fat borders are pushed back
//! along the one viewing axis (the silhouette grows by ε = γ pixels, no more), and the crack
//! check on the stress tessellation finds the same story as under perspective: cracks without
//! fat borders and with fat borders of half width, none with full-width ones.

mod common;

use glam::DVec3;
use patchwork::check::crack::contour_margin;
use patchwork::check::golden::border_shading;
use patchwork::check::{CheckOptions, run_check};
use patchwork::model::Scene;
use patchwork::render::{FatBorders, RenderOptions, Shading};
use patchwork::tessellate::tessellate_scene;
use patchwork::view::{Framing, NamedView, Projection, View};

/// `.bpt` text of an axis-aligned cube of side `side` centred at `c`: six bilinear patches.
fn cube_bpt(c: DVec3, side: f64) -> String {
    let h = side / 2.0;
    let mut out = String::new();
    // Each face: corner, and two edge directions spanning it.
    let faces = [
        (DVec3::new(-h, -h, -h), DVec3::X, DVec3::Z),
        (DVec3::new(-h, h, -h), DVec3::Z, DVec3::X),
        (DVec3::new(-h, -h, -h), DVec3::Z, DVec3::Y),
        (DVec3::new(h, -h, -h), DVec3::Y, DVec3::Z),
        (DVec3::new(-h, -h, -h), DVec3::Y, DVec3::X),
        (DVec3::new(-h, -h, h), DVec3::X, DVec3::Y),
    ];
    for (o, u, v) in faces {
        out.push_str("1 1\n");
        for i in 0..2 {
            for j in 0..2 {
                let p = c + o + u * side * i as f64 + v * side * j as f64;
                out.push_str(&format!("{} {} {}\n", p.x, p.y, p.z));
            }
        }
    }
    out
}

/// Two equal unit cubes side by side along x, the second 6 units deeper along +y (z-up; the
/// front view looks along +y): patches 0–5 the near cube, 6–11 the far one.
fn two_cubes() -> (Scene, std::path::PathBuf) {
    let text = format!(
        "12\n{}{}",
        cube_bpt(DVec3::new(-1.5, -3.0, 0.0), 1.0),
        cube_bpt(DVec3::new(1.5, 3.0, 0.0), 1.0)
    );
    let path = common::scratch("ortho").join("two-cubes.bpt");
    std::fs::write(&path, text).expect("scratch file");
    let scene = patchwork::prep::load(&path).expect("the cubes load");
    (scene, path)
}

/// Width and height in pixels of the patch-ID region of patches `ids` (0-based).
fn extent(ids: &[u32], w: usize, patches: std::ops::Range<u32>) -> (usize, usize) {
    let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
    for (k, &id) in ids.iter().enumerate() {
        if id > 0 && patches.contains(&(id - 1)) {
            let (x, y) = (k % w, k / w);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
    }
    assert!(x0 <= x1, "patches {patches:?} not drawn");
    (x1 - x0 + 1, y1 - y0 + 1)
}

/// From the front, orthographic: the near and the far cube are drawn the same size (and
/// exactly `side / pixel size` wide). The same measure under the perspective projection finds
/// the near cube clearly larger: it is what fails under a perspective projection.
#[test]
fn orthographic_sizes_do_not_depend_on_depth() {
    let (scene, _) = two_cubes();
    let mut renderer = common::renderer();
    let fov = 45f64.to_radians();
    let opts = RenderOptions {
        shading: Shading::Ids,
        fat_borders: FatBorders::Off,
        ids: true,
        ..RenderOptions::default()
    };
    let mut sizes = Vec::new();
    for ortho in [true, false] {
        let framing = Framing {
            view: Some(NamedView::Front),
            ortho,
            ..Framing::default()
        };
        let view = View::framed(&scene.bounds, scene.up.vector(), &framing, fov, (400, 300));
        assert_eq!(view.is_orthographic(), ortho);
        let meshes = tessellate_scene(&scene, &view, 0.5);
        let gpu = renderer.upload(&meshes);
        let frame = renderer.render(&gpu, &view, &opts).expect("render");
        let ids = frame.ids.as_ref().expect("ids asked for");
        let (near, far) = (extent(ids, 400, 0..6), extent(ids, 400, 6..12));
        eprintln!("ortho {ortho}: near cube {near:?} px, far cube {far:?} px");
        if let Projection::Orthographic { height } = view.projection {
            let side_px = 300.0 / height;
            for (w, h) in [near, far] {
                assert!((w as f64 - side_px).abs() <= 1.0, "{w} vs {side_px}");
                assert!((h as f64 - side_px).abs() <= 1.0, "{h} vs {side_px}");
            }
        }
        sizes.push((near, far));
    }
    let ((near, far), (pnear, pfar)) = (sizes[0], sizes[1]);
    assert!(near.0.abs_diff(far.0) <= 1 && near.1.abs_diff(far.1) <= 1);
    assert!(
        pnear.0 > pfar.0 + 10 && pnear.1 > pfar.1 + 10,
        "perspective: near {pnear:?} far {pfar:?}"
    );
}

/// Orthographic fat borders at γ = 4 and 16 px: the silhouette grows by at most ⌈γ/2⌉ + 1 px,
/// as under perspective (measured 2 px at γ = 4; exactly γ when every fat border was ε wide).
/// Pushed back along the perspective direction from the eye point (the shader ignoring the
/// orthographic viewer), border vertices off the axis drift outwards by up to a third of ε:
/// the fins outside the silhouette almost double.
#[test]
fn orthographic_fat_borders_grow_the_silhouette_by_gamma() {
    let scene = common::teapot();
    let mut renderer = common::renderer();
    let out = common::scratch("ortho");
    let fov = 45f64.to_radians();
    let framing = Framing {
        ortho: true,
        ..Framing::default()
    };
    let view = View::framed(&scene.bounds, scene.up.vector(), &framing, fov, (400, 300));
    // Fin pixels (fat borders outside the reference silhouette): measured 185 and 1 969;
    // pushed back along the perspective direction from the eye point (the shader ignoring the
    // orthographic viewer) 373 and 3 469, with growth 2 and 9 px.
    for (gamma, max_fins) in [(4.0, 280), (16.0, 2_600)] {
        let (m, images) = border_shading(&mut renderer, &scene, &view, gamma).expect("render");
        eprintln!(
            "γ = {gamma}: growth on {} px off {} px, fins {} px, contrast {:.3}",
            m.growth_on_px, m.growth_off_px, m.fin_pixels, m.fin_contrast
        );
        for (suffix, img) in ["reference", "on", "off"].iter().zip(&images) {
            let path = out.join(format!("teapot-gamma{gamma}-{suffix}.png"));
            patchwork::io::png::write_rgba(&path, img).expect("scratch image");
        }
        // Fat borders as wide as the teapot's border errors (under half of ε, see
        // tests/fat_border_shading.rs): as under perspective, ⌈γ / 2⌉ + 1 px.
        let band = (gamma / 2.0).ceil() as u32 + 1;
        assert!(
            m.growth_on_px <= band,
            "γ {gamma}: the silhouette grew by {} px > {band}",
            m.growth_on_px
        );
        assert!(
            m.fin_pixels <= max_fins,
            "γ {gamma}: {} fin pixels > {max_fins}",
            m.fin_pixels
        );
        // The fat borders do widen it (at least the ε / 4 floor): the measure can fail.
        assert!(
            m.growth_on_px + 1 >= (gamma / 4.0) as u32,
            "{}",
            m.growth_on_px
        );
    }
}

/// The crack check in orthographic views on the stress tessellation (borders pulled back
/// across the view as far as ε allows): cracks without fat borders and with half-width ones,
/// none with the paper's.
#[test]
fn orthographic_stress_check_is_crack_free_with_fat_borders() {
    let scene = common::teapot();
    let mut renderer = common::renderer();
    let opts = CheckOptions {
        views: 4,
        seed: 5,
        size: (384, 288),
        ortho: true,
        variants: vec![FatBorders::Off, FatBorders::Six],
        stress: true,
        narrowed_width: Some(0.5),
        save_failures: Some(common::scratch("ortho-stress")),
        ..CheckOptions::default()
    };
    let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
    let (off, six, half) = (
        r.total(FatBorders::Off),
        r.total(FatBorders::Six),
        r.total_narrowed(FatBorders::Six),
    );
    eprintln!(
        "orthographic stress: crack pixels off {}, ×0.5 {}, ×1 {}, inside {}",
        off.cracks(),
        half.cracks(),
        six.cracks(),
        off.inside
    );
    assert!(off.cracks() * 100 > off.inside, "{off:?}");
    assert!(half.cracks() > 20, "{half:?}");
    // At most one pixel a view (the fan-apex T-junction, see tests/cracks.rs), and no
    // growth beyond the contour margin.
    let margin = contour_margin(opts.pixel_error) as u32;
    for v in &r.views {
        let c = v
            .counts
            .iter()
            .find(|(fb, _)| *fb == FatBorders::Six)
            .expect("measured")
            .1;
        assert!(c.cracks() <= 1, "view {}: {c:?}", v.index);
        assert!(c.growth_max_px <= margin + 1, "view {}: {c:?}", v.index);
    }
}

/// `stats --ortho --json`: one ε for every patch (the pixel's world size is the same at every
/// depth) and the projection named; without `--ortho` ε spreads with the distance.
#[test]
fn stats_ortho_has_one_eps() {
    let stats = |extra: &[&str]| -> serde_json::Value {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_patchwork"))
            .arg("stats")
            .arg(common::root().join("models/teapot.bpt"))
            .args(["--json", "--view", "front"])
            .args(extra)
            .output()
            .expect("patchwork runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).expect("JSON")
    };
    let (ortho, persp) = (stats(&["--ortho"]), stats(&[]));
    let eps = |v: &serde_json::Value| (v["eps_min"].as_f64(), v["eps_max"].as_f64());
    let (lo, hi) = eps(&ortho);
    assert_eq!(lo, hi, "{ortho}");
    assert_eq!(ortho["projection"]["kind"], "orthographic");
    let height = ortho["projection"]["height"].as_f64().expect("height");
    // ε = γ · height / H (0.5 px, 768 px tall).
    assert!((lo.expect("eps") - 0.5 * height / 768.0).abs() < 1e-12);
    let (plo, phi) = eps(&persp);
    assert!(plo.expect("eps") < 0.9 * phi.expect("eps"), "{persp}");
    assert_eq!(persp["projection"]["kind"], "perspective");
}
