//! Inputs that used to crash or exhaust memory inside dependencies (issue 21), each kept under
//! `tests/data/`: the load is a typed error naming the file and the rule or limit, or a model
//! with the bad entity skipped and named in a warning — never a panic, never gigabytes.

mod common;

use std::path::PathBuf;

use patchwork::io::{self, LoadError};
use patchwork::prep::{self, Hierarchies, LoadOptions};

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data").join(name)
}

fn load_error(name: &str) -> String {
    let path = data(name);
    let options = LoadOptions::new(Hierarchies::CachedOrOriginal, None);
    let e = prep::load_with_options(&path, &options, &patchwork::util::NoProgress)
        .map(|_| ())
        .expect_err(name);
    assert_eq!(e.path(), path);
    let msg = e.to_string();
    assert!(msg.contains(path.file_name().and_then(|n| n.to_str()).unwrap_or("?")));
    msg
}

/// truck-geometry expanded a knot multiplicity of 10⁹ into gigabytes (then the OOM killer).
#[test]
fn a_knot_multiplicity_of_a_billion_is_refused_by_rule() {
    let msg = load_error("step/hostile/knots_1e9.step");
    assert!(
        msg.contains("knot multiplicities sum to 1000000026")
            && msg.contains("control points + degree + 1 = 27"),
        "{msg}"
    );
}

/// ruststep panicked ("unreachable: Invalid key while deserializing PlaceHolder",
/// tables.rs:333) on `.F.` in a B-spline's control-point list.
#[test]
fn an_enumeration_among_control_points_is_refused() {
    let msg = load_error("step/hostile/enum_in_points.step");
    assert!(
        msg.contains("control point 0 is not an entity reference"),
        "{msg}"
    );
}

/// The same panic for `.F.` in a SURFACE_CURVE's pcurve list: that entity is unreadable, the
/// two faces using it are skipped, the rest of the screw loads.
#[test]
fn an_enumeration_among_pcurves_makes_one_entity_unreadable() {
    let path = data("step/hostile/enum_in_pcurves.step");
    let options = LoadOptions::new(Hierarchies::CachedOrOriginal, None);
    let loaded = prep::load_with_options(&path, &options, &patchwork::util::NoProgress)
        .expect("the other faces load");
    let warnings = loaded.scene.warnings.join("\n");
    assert!(
        warnings.contains("could not read: SURFACE_CURVE ×1"),
        "{warnings}"
    );
    assert_eq!(loaded.scene.skipped.len(), 2, "{:?}", loaded.scene.skipped);
    assert!(!loaded.scene.patches.is_empty());
}

/// A GLB header declaring 0xFFFFFFFF bytes used to allocate 4 GiB up front.
#[test]
fn a_glb_header_of_4_gib_is_refused_without_allocating() {
    let msg = load_error("mesh/huge_header.glb");
    assert!(msg.contains("not a valid glTF"), "{msg}");
    let e = io::read(&data("mesh/huge_header.glb"))
        .map(|_| ())
        .expect_err("refused");
    assert!(matches!(e, LoadError::Unreadable { .. }), "{e}");
}
