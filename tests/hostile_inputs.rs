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

/// The same panic for `.F.` in a SURFACE_CURVE's pcurve list: that entity is unreadable (and
/// said so), but its edge is its 3D curve, so the two faces using it are drawn (they were
/// skipped until edges fell back to the 3D curve: `io::step::convert_edge`) — and within
/// tolerance of their surfaces, as every face of the screw.
#[test]
fn an_enumeration_among_pcurves_leaves_the_edge_its_3d_curve() {
    let path = data("step/hostile/enum_in_pcurves.step");
    let options = LoadOptions::new(Hierarchies::CachedOrOriginal, None);
    let loaded = prep::load_with_options(&path, &options, &patchwork::util::NoProgress)
        .expect("the other faces load");
    let warnings = loaded.scene.warnings.join("\n");
    assert!(
        warnings.contains("could not read: SURFACE_CURVE ×1"),
        "{warnings}"
    );
    assert!(
        loaded.scene.skipped.is_empty(),
        "{:?}",
        loaded.scene.skipped
    );
    let faces = std::fs::read_to_string(&path)
        .expect("readable")
        .matches("ADVANCED_FACE")
        .count();
    assert_eq!(loaded.scene.patches.len(), faces);
    let tol = 0.01 * loaded.scene.bbox_diagonal();
    let meshes = patchwork::tessellate::tessellate_scene_tolerance(&loaded.scene, tol);
    for (m, (_, f)) in meshes
        .iter()
        .zip(&patchwork::check::fidelity::measure_meshes(
            &loaded.scene,
            &meshes,
        ))
    {
        assert!(m.failure.is_none(), "{:?}", m.failure);
        assert!(
            f.ratio() <= 1.1 && f.outside == 0,
            "face #{}: error/tol {} (outside {})",
            f.face,
            f.ratio(),
            f.outside
        );
    }
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

/// truck-stepio resolves references recursively: an edge curve that is its own `curve_3d`
/// overflowed the stack (an abort, exit 134, that no isolation catches). Found by the `step`
/// fuzz target's SIGSEGV; the cycle is now refused on our own scan, naming where it closes.
#[test]
fn a_reference_cycle_is_refused_before_truck_follows_it() {
    let msg = load_error("step/hostile/surface_curve_cycle.step");
    assert!(
        msg.contains("#68996: refused: its references run in a cycle (through #69003)"),
        "{msg}"
    );
}

/// The same recursion on a chain of 5 000 nested surface curves, made here from the cycle
/// file: refused by height, whatever thread converts the face.
#[test]
fn a_reference_chain_thousands_deep_is_refused() {
    let text = std::fs::read_to_string(data("step/hostile/surface_curve_cycle.step"))
        .expect("read the cycle file");
    let n = 5000;
    let mut chain = String::new();
    for i in 0..n {
        let (id, next) = (if i == 0 { 69003 } else { 900_000 + i }, 900_001 + i);
        chain += &format!("#{id} = SURFACE_CURVE('',#{next},(#{next}),.CURVE_3D.);\n");
    }
    chain += &format!("#{} = LINE('',#69002,#950001);\n", 900_000 + n);
    chain += "#950001 = VECTOR('',#950002,1.);\n#950002 = DIRECTION('',(1.,0.,0.));";
    let cycle = "#69003 = SURFACE_CURVE('',#69003,(#69003),.CURVE_3D.);";
    assert!(text.contains(cycle));
    let path = common::scratch("hostile").join("deep_chain.step");
    std::fs::write(&path, text.replace(cycle, &chain)).expect("write the chain file");
    let options = LoadOptions::new(Hierarchies::CachedOrOriginal, None);
    let msg = prep::load_with_options(&path, &options, &patchwork::util::NoProgress)
        .map(|_| ())
        .expect_err("refused")
        .to_string();
    // face → bound → loop → oriented edge → edge curve → 5 000 curves → line → vector →
    // direction.
    assert!(
        msg.contains("#68996: refused: its references nest 5007 deep (the limit is 64)"),
        "{msg}"
    );
}

/// A trim-curve control point at z = −10²⁰⁴ (fuzz, trimmed target): its edge's points
/// overflowed f32 to infinity, the model's box collapsed to a point, and the face was
/// tessellated at ε = 6·10⁻¹⁷ (494 344 triangles, 19 s, 48 s in the fuzz target). Now the
/// face is refused by the same f32 rule as Bézier control points and mesh vertices.
#[test]
fn a_face_reaching_past_f32_is_refused() {
    let msg = load_error("step/hostile/point_past_f32_range.step");
    assert!(
        msg.contains("#68996: its points reach beyond ±1e19 (to inf)"),
        "{msg}"
    );
}
