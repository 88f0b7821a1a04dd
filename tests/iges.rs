//! IGES 5.3 import: the shipped files load with every trimmed surface, render crack-free with
//! fat borders and within their tolerance of the trimmed faces; holes, transformation
//! matrices, colours, units, subfigures and non-default delimiters read as written (small
//! files made by `tests/data/iges/generate.py`); each kind of bad file is its typed error with
//! the DE or line, never a panic.

mod common;

use std::path::{Path, PathBuf};

use glam::DVec3;
use patchwork::check::fidelity::measure_scene;
use patchwork::check::{CheckOptions, run_check};
use patchwork::io::LoadError;
use patchwork::io::iges::IgesError;
use patchwork::model::trimmed::Curve3D;
use patchwork::model::{PatchSurface, Scene, TrimmedFace};
use patchwork::render::FatBorders;
use patchwork::tessellate::tessellate_scene_tolerance;
use patchwork::view::DEFAULT_PIXEL_ERROR;

/// The shipped IGES files and their trimmed surfaces (144).
const SHIPPED: [(&str, usize); 2] = [
    ("corpus/bearing.iges.gz", 213),
    ("corpus/example_45_faces.iges", 45),
];

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data/iges").join(name)
}

fn load(name: &str) -> Result<Scene, LoadError> {
    patchwork::prep::load(&data(name))
}

fn face(scene: &Scene, k: usize) -> &TrimmedFace {
    match &scene.patches[k].surface {
        PatchSurface::Trimmed(f) => f,
        other => panic!("patch {k} is not a trimmed face: {other:?}"),
    }
}

/// Area of the scene's tessellation (world units²).
fn area(scene: &Scene) -> f64 {
    tessellate_scene_tolerance(scene, 1e-3)
        .iter()
        .flat_map(|m| {
            m.triangles.iter().map(|t| {
                let p = t.map(|i| m.positions[i as usize].as_dvec3());
                0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
            })
        })
        .sum()
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    a.distance(b) <= tol
}

const SQUARE_WITH_HOLE: f64 = 100.0 - 4.0 * std::f64::consts::PI;

#[test]
fn shipped_files_load_every_trimmed_surface() {
    for (file, faces) in SHIPPED {
        let scene = common::load(file);
        assert_eq!(scene.patches.len(), faces, "{file}");
        assert!(scene.skipped.is_empty(), "{file}: {:?}", scene.skipped);
        assert_eq!(scene.instances.len(), 1, "{file}");
    }
}

#[test]
fn hole_matrix_and_colour_are_read() {
    let scene = load("square_hole.igs").expect("loads");
    assert_eq!(scene.patches.len(), 1);
    assert_eq!(face(&scene, 0).loops.len(), 2, "outer boundary and hole");
    let a = area(&scene);
    assert!(
        (a - SQUARE_WITH_HOLE).abs() < 0.01 * SQUARE_WITH_HOLE,
        "area {a}, a 10 mm square less a 2 mm hole is {SQUARE_WITH_HOLE}"
    );
    // The 124 turns the square 90° about z and moves it 100 mm along x (the scene's box is
    // grown by the load-time probe's tolerance, 2 % of the face's radius).
    let (lo, hi) = scene.bbox;
    assert!(
        close(lo, DVec3::new(90.0, 0.0, 0.0), 0.5) && close(hi, DVec3::new(100.0, 10.0, 0.0), 0.5),
        "bbox {lo} .. {hi}"
    );
    let c = scene.patches[0].color.expect("the 314 colour");
    assert!(
        (c[0] - 0.2).abs() < 1e-6 && (c[1] - 0.4).abs() < 1e-6 && (c[2] - 0.6).abs() < 1e-6,
        "{c:?}"
    );
    // The boundaries are the parameter-space curves lifted onto the surface.
    for le in face(&scene, 0).loops.iter().flatten() {
        assert!(
            matches!(le.edge.curve, Curve3D::PCurve(_)),
            "edge {} is not the lifted parameter-space curve",
            le.edge.id
        );
    }
}

#[test]
fn a_parameter_space_curve_that_strays_gives_way_to_the_model_space_curve() {
    let scene = load("square_hole_stray_pcurve.igs").expect("loads");
    let a = area(&scene);
    assert!(
        (a - SQUARE_WITH_HOLE).abs() < 0.01 * SQUARE_WITH_HOLE,
        "area {a}: the 2 mm model-space hole, not the 3 mm parameter-space one"
    );
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("1 of 2 boundaries (142) drawn by their model-space curve")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn inches_are_scaled_to_millimetres() {
    let mm = load("square_hole.igs").expect("loads");
    let inch = load("square_hole_inch.igs").expect("loads");
    for (a, b) in [(mm.bbox.0, inch.bbox.0), (mm.bbox.1, inch.bbox.1)] {
        assert!(close(a * 25.4, b, 0.05 * 25.4), "{a} in → {b} mm");
    }
}

#[test]
fn non_default_delimiters_and_hollerith_strings() {
    let plain = load("square_hole.igs").expect("loads");
    let other = load("square_hole_delimiters.igs").expect("loads with / and # delimiters");
    assert_eq!(other.patches.len(), 1);
    assert!(close(plain.bbox.0, other.bbox.0, 1e-9) && close(plain.bbox.1, other.bbox.1, 1e-9));
    assert_eq!(plain.patches[0].color, other.patches[0].color);
    assert!((area(&plain) - area(&other)).abs() < 1e-9);
}

#[test]
fn planes_are_trimmed_by_their_model_space_curves() {
    for file in ["plane_108.igs", "plane_190.igs"] {
        let scene = load(file).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            patchwork::check::fidelity::surface_kind(&face(&scene, 0).surface),
            "plane",
            "{file}"
        );
        let a = area(&scene);
        assert!(
            (a - SQUARE_WITH_HOLE).abs() < 0.01 * SQUARE_WITH_HOLE,
            "{file}: area {a}"
        );
        assert!(
            scene
                .warnings
                .iter()
                .any(|w| w.contains("2 of 2 boundaries")),
            "{file}: {:?}",
            scene.warnings
        );
    }
}

#[test]
fn untrimmed_surfaces_are_whole_patches() {
    let scene = load("untrimmed.igs").expect("loads");
    assert_eq!(scene.patches.len(), 1);
    let a = area(&scene);
    assert!((a - 16.0).abs() < 1e-6, "area {a} of a 4 mm square");
}

#[test]
fn subfigure_instances_place_their_definition() {
    let scene = load("subfigures.igs").expect("loads");
    assert_eq!(scene.patches.len(), 2);
    assert_eq!(scene.instances.len(), 2);
    let a = area(&scene);
    // Placed at scale 1 and 2 (no 124 on the definition's face).
    assert!(
        (a - 5.0 * SQUARE_WITH_HOLE).abs() < 0.01 * 5.0 * SQUARE_WITH_HOLE,
        "area {a}"
    );
    let (lo, hi) = scene.bbox;
    assert!(
        close(lo, DVec3::ZERO, 0.5) && close(hi, DVec3::new(20.0, 40.0, 0.0), 0.5),
        "bbox {lo} .. {hi}"
    );
}

fn iges_error(name: &str) -> IgesError {
    match load(name) {
        Err(LoadError::Iges { path, source }) => {
            assert_eq!(path, data(name));
            source
        }
        other => panic!("{name}: expected an IGES error, got {other:?}"),
    }
}

#[test]
fn each_error_class_names_its_entity_or_line() {
    match iges_error("bad_pointer.igs") {
        IgesError::BadPointer {
            de: 1, target: 99, ..
        } => {}
        e => panic!("bad_pointer.igs: {e:?}"),
    }
    match iges_error("cycle.igs") {
        IgesError::Cycle { de: 33, .. } => {}
        e => panic!("cycle.igs: {e:?}"),
    }
    match iges_error("truncated.igs") {
        IgesError::Truncated { de: 3, .. } => {}
        e => panic!("truncated.igs: {e:?}"),
    }
    match iges_error("missing_parameter.igs") {
        IgesError::MissingParameter { de: 3, index, .. } => assert_eq!(index, 26),
        e => panic!("missing_parameter.igs: {e:?}"),
    }
    let e = load("short_line.igs").expect_err("a 79-column line");
    assert_eq!(e.line(), Some(6), "{e}");
    assert!(e.to_string().contains("short_line.igs:") || e.to_string().contains("line 6"));
}

#[test]
fn a_bad_face_is_skipped_with_its_de() {
    let scene = load("one_bad_face.igs").expect("the good face loads");
    assert_eq!(scene.patches.len(), 1);
    assert_eq!(scene.skipped.len(), 1, "{:?}", scene.skipped);
    assert_eq!(scene.skipped[0].face, 49);
    assert!(
        scene.skipped[0].reason.contains("97"),
        "{}",
        scene.skipped[0].reason
    );
}

#[test]
fn unknown_entities_are_counted_in_one_warning() {
    let scene = load("square_hole.igs").expect("loads");
    let w: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("unsupported IGES entities"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", scene.warnings);
    assert!(w[0].contains("type 402 ×1, type 406 ×1"), "{}", w[0]);
}

#[test]
fn cut_and_corrupted_files_never_panic() {
    let path = common::root().join("models/corpus/example_45_faces.iges");
    let bytes = std::fs::read(&path).expect("reads");
    let p = Path::new("cut.iges");
    for k in (0..bytes.len()).step_by(bytes.len() / 97) {
        let _ = patchwork::io::iges::read(&bytes[..k], p);
    }
    // Corrupt one field per directory entry and parameter line in turn.
    let mut rng = patchwork::check::crack::SplitMix64::new(7);
    for _ in 0..300 {
        let mut b = bytes.clone();
        let at = (rng.next_u64() as usize) % b.len();
        b[at] = b"9-,;H 0.E"[(rng.next_u64() % 9) as usize];
        let _ = patchwork::io::iges::read(&b, p);
    }
}

#[test]
fn shipped_files_are_within_their_tolerance_of_the_trimmed_faces() {
    for (file, _) in SHIPPED {
        let scene = common::load(file);
        let faces = measure_scene(&scene, &common::framing(&scene), DEFAULT_PIXEL_ERROR);
        assert_eq!(faces.len(), scene.patches.len(), "{file}");
        let (patch, worst) = faces[0];
        assert!(
            worst.ratio() <= 1.0 && worst.outside == 0,
            "{file}: face #{} (patch {patch}) is {:.2}× its tolerance from the trimmed face, \
             {} samples outside its trim",
            worst.face,
            worst.ratio(),
            worst.outside
        );
    }
}

#[test]
fn shipped_files_render_without_cracks_with_fat_borders() {
    let mut renderer = common::renderer();
    for (file, _) in SHIPPED {
        let scene = common::load(file);
        let opts = CheckOptions {
            views: 8,
            seed: 3,
            variants: vec![FatBorders::Off, FatBorders::Six],
            save_failures: Some(common::scratch(&format!(
                "iges-cracks-{}",
                file.replace('/', "-")
            ))),
            ..CheckOptions::default()
        };
        let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
        let on = r.total(FatBorders::Six).cracks();
        let off = r.total(FatBorders::Off).cracks();
        assert_eq!(on, 0, "{file}: cracks with fat borders");
        assert!(
            off > 0,
            "{file}: no cracks without fat borders either: the check could not fail"
        );
    }
}
