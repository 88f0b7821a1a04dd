//! STEP import and trimmed-face tessellation: assemblies in place, the tolerance held on every
//! face, no cracks with fat borders on closed solids, and bad input reported, never a panic.

mod common;

use std::path::Path;

use patchwork::check::fidelity::FaceFidelity;
use patchwork::check::{CheckOptions, run_check};
use patchwork::io::LoadError;
use patchwork::model::{PatchSurface, Scene};
use patchwork::prep::load;
use patchwork::render::FatBorders;
use patchwork::tessellate::{tessellate_scene_tolerance, tessellate_scene_with};

/// Closed solids: every face drawn, the tolerance held on every face.
const CLOSED: [&str; 5] = [
    "as1-oc-214.stp",
    "NIST_MBE_PMI_3.stp",
    "nist_ctc_01_asme1_rd.stp",
    "NIST_MBE_PMI_11.stp",
    "screw.step",
];

/// A file of one face: loaded, nothing skipped.
fn one_face(name: &str) -> Scene {
    let path = common::root().join("tests/data/step").join(name);
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 1);
    scene
}

/// A mesh's area and box.
fn area_and_box(m: &patchwork::tessellate::PatchMesh) -> (f32, glam::Vec3, glam::Vec3) {
    let (lo, hi) = m.positions.iter().fold(
        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let area = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    (area, lo, hi)
}

/// The independent measure (`check::fidelity`) holds the one face within 1.1 tol, nothing
/// drawn outside its trim.
fn assert_measured_within(scene: &Scene, meshes: &[patchwork::tessellate::PatchMesh], tol: f64) {
    let faces = patchwork::check::fidelity::measure_meshes(scene, meshes);
    let (_, f) = faces.first().expect("one trimmed face");
    assert!(
        f.ratio() <= 1.1 && f.outside == 0,
        "tol {tol}: error/tol {} (outside {}, missing {})",
        f.ratio(),
        f.outside,
        f.missing
    );
}

fn parse(text: &str) -> Result<Scene, LoadError> {
    patchwork::prep::step::parse(text.as_bytes(), Path::new("test.step"))
}

#[test]
fn assembly_places_every_part() {
    let scene = common::load("as1-oc-214.stp");
    // 18 placed shells (rod assembly, plate, 2 brackets, 6 bolts, 8 nuts) of 9 products.
    assert_eq!(scene.parts.len(), 9);
    assert_eq!(scene.patches.len(), 160);
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    // The same face placed several times, with different transforms.
    let mut by_face: std::collections::HashMap<u64, Vec<glam::DMat4>> = Default::default();
    for p in &scene.patches {
        if let PatchSurface::Trimmed(f) = &p.surface {
            by_face.entry(f.id).or_default().push(p.transform);
        }
    }
    let (_, placements) = by_face.iter().max_by_key(|(_, v)| v.len()).expect("faces");
    assert_eq!(placements.len(), 8, "a nut face is placed 8 times");
    for (i, a) in placements.iter().enumerate() {
        for b in &placements[i + 1..] {
            assert!(!a.abs_diff_eq(*b, 1e-9), "two nuts at the same place");
        }
    }
    // Parts in place: the whole assembly spans the plate (bbox diagonal ≈ 272 mm).
    let d = scene.bbox_diagonal();
    assert!((250.0..300.0).contains(&d), "diagonal {d}");
}

#[test]
fn length_units_are_converted_to_millimetres() {
    // NIST_MBE_PMI_3 is in inches; Open CASCADE reports a 602.8 mm diagonal.
    let scene = common::load("NIST_MBE_PMI_3.stp");
    let d = scene.bbox_diagonal();
    assert!((590.0..615.0).contains(&d), "diagonal {d}");
    assert!(scene.warnings.iter().any(|w| w.contains("25.4")));
}

#[test]
fn tolerance_is_held_on_every_face() {
    for file in CLOSED {
        let scene = common::load(file);
        assert!(scene.skipped.is_empty(), "{file}: {:?}", scene.skipped);
        let diag = scene.bbox_diagonal();
        for rel in [1e-2, 3e-3, 1e-3] {
            let tol = rel * diag;
            let meshes = tessellate_scene_tolerance(&scene, tol);
            for m in &meshes {
                assert!(m.failure.is_none(), "{file}: {:?}", m.failure);
                assert!(
                    !m.triangles.is_empty(),
                    "{file}: patch {} empty",
                    m.patch_id
                );
                assert!(
                    m.error <= tol && m.trim_error <= tol,
                    "{file} at {rel}: patch {} error {} trim {} > {tol}",
                    m.patch_id,
                    m.error,
                    m.trim_error
                );
            }
        }
    }
}

/// Bound on the geometric error of `m`: at the centroid and edge midpoints of every triangle
/// (the tessellator's own samples), the smaller of the distance to the surface point found by
/// projection and the tessellator's parametric error (the distance to the surface point at the
/// same parameters, at most `m.error`): both are distances to some surface point.
fn geometric_error(patch: &patchwork::model::Patch, m: &patchwork::tessellate::PatchMesh) -> f64 {
    use patchwork::model::trimmed::SurfaceEval;
    let PatchSurface::Trimmed(face) = &patch.surface else {
        return 0.0;
    };
    let to_local = patch.transform.inverse();
    let local = |i: u32| to_local.transform_point3(m.positions[i as usize].as_dvec3());
    let mut worst = 0.0f64;
    for t in &m.triangles {
        let [a, b, c] = t.map(local);
        for x in [
            (a + b + c) / 3.0,
            (a + b) / 2.0,
            (b + c) / 2.0,
            (c + a) / 2.0,
        ] {
            let projected = face
                .project(x, None)
                .map_or(f64::INFINITY, |uv| face.point(uv).distance(x));
            worst = worst.max(projected.min(m.error / patch.scale()));
        }
    }
    worst * patch.scale()
}

#[test]
fn crack_check_reference_holds_the_tolerance() {
    // The crack check's reference tessellates with shared borders (edge polylines that
    // depend on the curve and ε only, not split by the surface). A reference off by more than
    // its tolerance reports cracks that are not there (a cylinder whose closing segment was
    // never split once did, 12.5 mm off). Its error is geometric: near borders the parametric
    // measure of the tessellator overestimates when the trim curve runs diagonally in (u, v).
    for file in CLOSED {
        let scene = common::load(file);
        let diag = scene.bbox_diagonal();
        for rel in [1e-2, 1e-3] {
            let tol = rel * diag;
            let meshes = tessellate_scene_with(&scene, tol, true);
            for (patch, m) in scene.patches.iter().zip(&meshes) {
                assert!(m.failure.is_none(), "{file}: {:?}", m.failure);
                assert!(
                    !m.triangles.is_empty(),
                    "{file}: patch {} empty",
                    m.patch_id
                );
                let geo = geometric_error(patch, m);
                assert!(
                    geo <= tol && m.trim_error <= tol,
                    "{file} at {rel}: patch {} geometric error {geo} (parametric {}) trim {} > {tol}",
                    m.patch_id,
                    m.error,
                    m.trim_error
                );
            }
        }
    }
}

#[test]
fn face_meshes_have_no_holes() {
    // Inside a face every edge joins two triangles; edges used once are the border loops
    // (or collapse to a point, at a cone's apex). A triangle dropped by the domain test would
    // leave a hole no fat border covers.
    for file in CLOSED {
        let scene = common::load(file);
        for rel in [1e-2, 1e-3] {
            let meshes = tessellate_scene_tolerance(&scene, rel * scene.bbox_diagonal());
            for m in &meshes {
                // Vertices at the same position (a cone's apex reached at two parameters)
                // count as one.
                let mut first: std::collections::HashMap<[u32; 3], u32> = Default::default();
                let canon: Vec<u32> = (0..m.positions.len() as u32)
                    .map(|i| {
                        let p = m.positions[i as usize];
                        *first
                            .entry([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
                            .or_insert(i)
                    })
                    .collect();
                let key = |a: u32, b: u32| {
                    let (a, b) = (canon[a as usize], canon[b as usize]);
                    (a.min(b), a.max(b))
                };
                let mut uses: std::collections::HashMap<(u32, u32), u32> = Default::default();
                for t in &m.triangles {
                    for k in 0..3 {
                        *uses.entry(key(t[k], t[(k + 1) % 3])).or_default() += 1;
                    }
                }
                let mut border = std::collections::HashSet::new();
                for ring in &m.borders {
                    for k in 0..ring.len() {
                        border.insert(key(ring[k], ring[(k + 1) % ring.len()]));
                    }
                }
                let open: Vec<_> = uses
                    .iter()
                    .filter(|&(e, &n)| {
                        let (a, b) = (m.positions[e.0 as usize], m.positions[e.1 as usize]);
                        n == 1 && !border.contains(e) && a != b
                    })
                    .map(|(e, n)| (m.positions[e.0 as usize], m.positions[e.1 as usize], *n))
                    .collect();
                assert!(
                    open.is_empty(),
                    "{file} at {rel}: patch {} has holes along {open:?}",
                    m.patch_id
                );
            }
        }
    }
}

#[test]
fn no_cracks_with_fat_borders_on_closed_solids() {
    let mut renderer = common::renderer();
    let mut off_total = 0;
    for file in CLOSED {
        let scene = common::load(file);
        let opts = CheckOptions {
            views: 20,
            seed: 1,
            variants: vec![FatBorders::Off, FatBorders::Six],
            save_failures: Some(common::scratch(&format!("cracks-{file}"))),
            ..CheckOptions::default()
        };
        let r = run_check(&mut renderer, &scene, &opts, |_| {}).expect("rendering works");
        for v in &r.views {
            for (fb, c) in &v.counts {
                if *fb != FatBorders::Off {
                    assert_eq!(
                        c.cracks(),
                        0,
                        "{file} view {} fat borders {fb}: {c:?}",
                        v.index
                    );
                }
            }
        }
        // Planar parts with straight edges may show none (their independent borders
        // coincide); curved edges do.
        off_total += r.total(FatBorders::Off).cracks();
    }
    assert!(
        off_total > 0,
        "no cracks without fat borders: the check could not fail"
    );
}

#[test]
fn a_face_that_cannot_be_trimmed_is_skipped_with_its_reason() {
    // Two disks: #20's circle edge #23 runs between two vertices 1 and 2 mm off the circle,
    // both nearest to one point of it (no edge to heal), so face #20 is skipped with the edge
    // named, and face #10 is drawn. (One vertex 1 mm off is healed: see
    // `vertices_within_the_files_tolerance_are_accepted`.)
    let broken = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n\
        FILE_NAME('t','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\n\
        ENDSEC;\nDATA;\n\
        #1=OPEN_SHELL('',(#10,#20));\n\
        #2=DIRECTION('',(0.,0.,1.));\n#3=DIRECTION('',(1.,0.,0.));\n\
        #10=ADVANCED_FACE('',(#11),#15,.T.);\n#11=FACE_OUTER_BOUND('',#12,.T.);\n\
        #12=EDGE_LOOP('',(#13));\n#13=ORIENTED_EDGE('',*,*,#14,.T.);\n\
        #14=EDGE_CURVE('',#16,#16,#18,.T.);\n#15=PLANE('',#19);\n\
        #16=VERTEX_POINT('',#17);\n#17=CARTESIAN_POINT('',(1.,0.,0.));\n\
        #18=CIRCLE('',#19,1.);\n#19=AXIS2_PLACEMENT_3D('',#9,#2,#3);\n\
        #9=CARTESIAN_POINT('',(0.,0.,0.));\n\
        #20=ADVANCED_FACE('',(#21),#25,.T.);\n#21=FACE_OUTER_BOUND('',#22,.T.);\n\
        #22=EDGE_LOOP('',(#24));\n#24=ORIENTED_EDGE('',*,*,#23,.T.);\n\
        #23=EDGE_CURVE('',#26,#30,#28,.T.);\n#25=PLANE('',#29);\n\
        #26=VERTEX_POINT('',#27);\n#27=CARTESIAN_POINT('',(2.,0.,1.));\n\
        #30=VERTEX_POINT('',#31);\n#31=CARTESIAN_POINT('',(3.,0.,1.));\n\
        #28=CIRCLE('',#29,1.);\n#29=AXIS2_PLACEMENT_3D('',#8,#2,#3);\n\
        #8=CARTESIAN_POINT('',(0.,0.,1.));\nENDSEC;\nEND-ISO-10303-21;\n";
    let scene = parse(broken).expect("the rest of the file loads");
    assert_eq!(scene.patches.len(), 1);
    assert_eq!(scene.skipped.len(), 1, "{:?}", scene.skipped);
    assert_eq!(scene.skipped[0].face, 20);
    assert!(
        scene.skipped[0].reason.contains("#23"),
        "{}",
        scene.skipped[0].reason
    );
    // screw.step draws every face (edge #958 is a seam whose SURFACE_CURVE prefers a
    // parameter-space curve; its 3D line is used).
    let whole = common::load("screw.step");
    assert_eq!(whole.patches.len(), 10);
    assert!(whole.skipped.is_empty(), "{:?}", whole.skipped);
}

/// Tolerant like a kernel: a vertex slightly off its curve, within the file's own
/// uncertainty (×10), is accepted with a warning; the same vertex in a file that declares no
/// uncertainty is too far off and is healed as OCCT's reader heals it (located at its nearest
/// point of the circle, the vertex's tolerance grown): the disk is drawn, of the circle's
/// radius, and the warning names the edge and how far its vertex moved. It was skipped before.
#[test]
fn vertices_within_the_files_tolerance_are_accepted() {
    let disk = |vertex: &str, extra: &str| {
        format!(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n\
             FILE_NAME('t','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\n\
             ENDSEC;\nDATA;\n#1=OPEN_SHELL('',(#20));\n\
             #2=DIRECTION('',(0.,0.,1.));\n#3=DIRECTION('',(1.,0.,0.));\n\
             #20=ADVANCED_FACE('',(#21),#25,.T.);\n#21=FACE_OUTER_BOUND('',#22,.T.);\n\
             #22=EDGE_LOOP('',(#24));\n#24=ORIENTED_EDGE('',*,*,#23,.T.);\n\
             #23=EDGE_CURVE('',#26,#26,#28,.T.);\n#25=PLANE('',#29);\n\
             #26=VERTEX_POINT('',#27);\n#27=CARTESIAN_POINT('',({vertex}));\n\
             #28=CIRCLE('',#29,1.);\n#29=AXIS2_PLACEMENT_3D('',#8,#2,#3);\n\
             #8=CARTESIAN_POINT('',(0.,0.,1.));\n{extra}ENDSEC;\nEND-ISO-10303-21;\n"
        )
    };
    let uncertainty = "#30=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(0.01),#31,\
                       'distance_accuracy_value','');\n\
                       #31=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.));\n";
    let tolerant = parse(&disk("1.05,0.,1.", uncertainty)).expect("loads");
    assert_eq!(tolerant.patches.len(), 1, "{:?}", tolerant.skipped);
    let w = tolerant.warnings.join("\n");
    assert!(w.contains("#23") && w.contains("tolerance"), "{w}");
    let healed = parse(&disk("1.05,0.,1.", "")).expect("the disk is healed");
    assert_eq!(healed.patches.len(), 1, "{:?}", healed.skipped);
    let w = healed.warnings.join("\n");
    assert!(w.contains("healed") && w.contains("#23 by 5.000e-2"), "{w}");
    let healed_box = healed.bbox;
    let exact = parse(&disk("1.,0.,1.", "")).expect("loads");
    assert!(
        (healed_box.0 - exact.bbox.0).abs().max_element() < 1e-9
            && (healed_box.1 - exact.bbox.1).abs().max_element() < 1e-9,
        "the circle's disk {:?}, not the vertex's: {healed_box:?}",
        exact.bbox
    );
    assert!(
        !exact.warnings.iter().any(|w| w.contains("#23")),
        "{:?}",
        exact.warnings
    );
}

/// A placement along x without a reference direction (CATIA writes them): ISO 10303-42 takes
/// y as the reference there; truck-stepio alone takes x and gets NaN, which lost every
/// circle, cylinder or cone so placed (94 of 533 faces of a CATIA block).
#[test]
fn a_placement_along_x_without_reference_direction_is_complete() {
    let text = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n\
        FILE_NAME('t','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\n\
        ENDSEC;\nDATA;\n#1=OPEN_SHELL('',(#20));\n#2=DIRECTION('',(1.,0.,0.));\n\
        #20=ADVANCED_FACE('',(#21),#25,.T.);\n#21=FACE_OUTER_BOUND('',#22,.T.);\n\
        #22=EDGE_LOOP('',(#24));\n#24=ORIENTED_EDGE('',*,*,#23,.T.);\n\
        #23=EDGE_CURVE('',#26,#26,#28,.T.);\n#25=PLANE('',#29);\n\
        #26=VERTEX_POINT('',#27);\n#27=CARTESIAN_POINT('',(0.,0.,2.));\n\
        #28=CIRCLE('',#29,2.);\n#29=AXIS2_PLACEMENT_3D('',#8,#2,$);\n\
        #8=CARTESIAN_POINT('',(0.,0.,0.));\nENDSEC;\nEND-ISO-10303-21;\n";
    let scene = parse(text).expect("the disk loads");
    assert_eq!(scene.patches.len(), 1, "{:?}", scene.skipped);
    let (lo, hi) = scene.bbox;
    assert!(
        (hi - lo - glam::DVec3::new(0.0, 4.0, 4.0))
            .abs()
            .max_element()
            < 0.1,
        "{lo} .. {hi}"
    );
}

#[test]
fn unsupported_entities_are_summarised_and_the_rest_renders() {
    let scene = common::load("nist_ctc_01_asme1_rd.stp");
    assert_eq!(scene.patches.len(), 139);
    let w = scene.warnings.join("\n");
    assert!(w.contains("GEOMETRIC_CURVE_SET ×1"), "{w}");
}

#[test]
fn malformed_step_names_line_and_entity() {
    let text = "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\n#2=DIRECTION('',(0.,0.,1.)\n#3=PLANE('',#4);\nENDSEC;\nEND-ISO-10303-21;\n";
    match parse(text) {
        Err(e @ LoadError::Parse { line, .. }) => {
            // Detected where the next record starts, reported with the unfinished entity.
            assert_eq!(line, 7, "{e}");
            assert!(e.to_string().contains("#2"), "{e}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn empty_and_faceless_files_are_clear_errors() {
    assert!(matches!(parse("  \n"), Err(LoadError::Empty { .. })));
    let faceless = "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\nENDSEC;\nEND-ISO-10303-21;\n";
    match parse(faceless) {
        Err(e @ LoadError::NoFaces { .. }) => {
            assert!(e.to_string().contains("no B-rep shell"), "{e}")
        }
        other => panic!("expected NoFaces, got {other:?}"),
    }
    assert!(matches!(
        parse("not a step file"),
        Err(LoadError::Parse { .. })
    ));
    assert!(matches!(
        patchwork::prep::step::parse(b"ISO-10303-21;\0", Path::new("x.stp")),
        Err(LoadError::NotText { .. })
    ));
}

#[test]
fn nan_coordinates_skip_faces_not_the_file() {
    let text =
        std::fs::read_to_string(common::root().join("models/NIST_MBE_PMI_11.stp")).expect("model");
    // The x of the first 40 points becomes 1e308: finite, so the scanner takes it (1e400
    // would be refused there and never reach the geometry), but B-spline evaluation on it
    // overflows to infinities and NaN. Those faces are skipped with their reason; the others
    // are drawn; nothing panics.
    let mut poisoned = String::with_capacity(text.len());
    let mut rest = text.as_str();
    let key = "CARTESIAN_POINT('',(";
    for _ in 0..40 {
        let Some(at) = rest.find(key) else { break };
        let start = at + key.len();
        let comma = start + rest[start..].find(',').expect("a point has coordinates");
        poisoned.push_str(&rest[..start]);
        poisoned.push_str("1.E308");
        rest = &rest[comma..];
    }
    poisoned.push_str(rest);
    let scene = parse(&poisoned).expect("the faces that stay finite load");
    assert!(!scene.patches.is_empty(), "every face was lost");
    assert!(
        !scene.skipped.is_empty(),
        "no face reached the poisoned geometry"
    );
    assert!(
        scene
            .skipped
            .iter()
            .all(|f| f.reason.contains("non-finite") || f.reason.contains("projecting")),
        "{:?}",
        scene.skipped
    );
}

#[test]
fn truncated_files_never_panic() {
    let text = std::fs::read(common::root().join("models/screw.step")).expect("model");
    for k in 1..40 {
        let cut = text.len() * k / 40;
        let r = patchwork::prep::step::parse(&text[..cut], Path::new("cut.step"));
        assert!(r.is_err(), "a file cut at byte {cut} must be refused");
    }
}

#[test]
fn missing_file_is_an_io_error() {
    assert!(matches!(
        load(Path::new("models/does-not-exist.step")),
        Err(LoadError::Io { .. })
    ));
}

#[test]
fn export_writes_one_mesh_per_part_and_one_node_per_placement() {
    let out = common::scratch("export").join("as1.glb");
    let _ = std::fs::remove_file(&out);
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["export", "models/as1-oc-214.stp", "-o"])
        .arg(&out)
        .args(["--tolerance", "0.2"])
        .current_dir(common::root())
        .status()
        .expect("run patchwork");
    assert!(status.success());
    let (doc, buffers, _) = gltf::import(&out).expect("re-read the glb");
    // Geometry-bearing parts: rod, plate, bracket, bolt, nut; 18 placements (nodes with a
    // mesh), under 10 groups: the root and the sub-assemblies of the tree.
    assert_eq!(doc.meshes().count(), 5);
    assert_eq!(doc.nodes().filter(|n| n.mesh().is_some()).count(), 18);
    assert_eq!(doc.nodes().count(), 28);
    let mut triangles = 0;
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let r = prim.reader(|b| Some(&buffers[b.index()]));
            let n = r.read_positions().expect("positions").count();
            let idx: Vec<u32> = r.read_indices().expect("indices").into_u32().collect();
            assert!(idx.iter().all(|&i| (i as usize) < n));
            triangles += idx.len() / 3;
        }
    }
    assert!(triangles > 1000, "{triangles}");
    // The nuts are placed at 8 distinct places.
    let mut translations: Vec<[f32; 3]> = doc
        .nodes()
        .filter(|n| n.mesh().is_some())
        .map(|n| n.transform().decomposed().0)
        .collect();
    translations.dedup();
    assert!(translations.len() >= 10);

    // A bad tolerance is refused and leaves no file.
    let bad = common::scratch("export").join("bad.glb");
    let _ = std::fs::remove_file(&bad);
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["export", "models/as1-oc-214.stp", "-o"])
        .arg(&bad)
        .arg("--tolerance=-1")
        .current_dir(common::root())
        .status()
        .expect("run patchwork");
    assert!(!status.success());
    assert!(!bad.exists());
}

/// Geometry the file states twice must agree: every edge curve of a face lies on the face's
/// surface. A surface read wrongly (a cone's semi-angle in degrees taken as radians, as
/// truck-stepio does) moves the surface off its exact edges, which no tessellation error
/// measured against that same surface can see.
#[test]
fn every_edge_lies_on_the_surface_of_its_faces() {
    use patchwork::model::trimmed::SurfaceEval;
    for file in CLOSED {
        let scene = common::load(file);
        let mut worst = (0.0f64, 0u64);
        for p in &scene.patches {
            let PatchSurface::Trimmed(face) = &p.surface else {
                continue;
            };
            // Far below any drawing tolerance, above the files' own uncertainties (≤ 0.05 mm).
            let tol = 1e-4 * scene.bounds.radius + 0.06;
            for le in face.loops.iter().flatten() {
                let e = &le.edge;
                for k in 1..8 {
                    let t = e.t0 + (e.t1 - e.t0) * k as f64 / 8.0;
                    let q = e.point(t);
                    let d = face
                        .project(q, None)
                        .map_or(f64::INFINITY, |uv| face.point(uv).distance(q));
                    if d / tol > worst.0 {
                        worst = (d / tol, face.id);
                    }
                }
            }
        }
        assert!(
            worst.0 <= 1.0,
            "{file}: an edge of face #{} lies {:.1}× the tolerance off its surface",
            worst.1,
            worst.0
        );
    }
}

/// The apex of a cone face is a `VERTEX_LOOP`: the vertex must lie on the cone as read. NIST
/// CTC-01 writes its two cones' semi-angles in degrees (59), which truck-stepio alone reads as
/// radians: the cones then miss their apexes by tens of millimetres.
#[test]
fn vertex_loops_lie_on_their_surface() {
    use patchwork::io::step::p21;
    use patchwork::model::trimmed::SurfaceEval;
    let mut checked = 0;
    for file in CLOSED {
        let scene = common::load(file);
        let text =
            std::fs::read_to_string(common::root().join("models").join(file)).expect("readable");
        let p21 = p21::parse(&text).expect("parses");
        for p in &scene.patches {
            let PatchSurface::Trimmed(face) = &p.surface else {
                continue;
            };
            let Some(bounds) = p21
                .get(face.id)
                .and_then(|e| e.record())
                .and_then(|r| r.list_at(1))
            else {
                continue;
            };
            for b in bounds.iter().filter_map(p21::Param::as_ref) {
                let point = p21
                    .get(b)
                    .and_then(|e| e.record())
                    .and_then(|r| r.ref_at(1))
                    .and_then(|l| p21.get(l))
                    .and_then(|l| l.part("VERTEX_LOOP"))
                    .and_then(|l| l.ref_at(1))
                    .and_then(|v| p21.get(v)?.part("VERTEX_POINT")?.ref_at(1))
                    .and_then(|c| {
                        p21.get(c)?
                            .part("CARTESIAN_POINT")?
                            .list_at(1)
                            .map(<[_]>::to_vec)
                    });
                let Some(c) = point else { continue };
                let c: Vec<f64> = c.iter().filter_map(p21::Param::as_f64).collect();
                let q = glam::DVec3::new(c[0], c[1], c[2]);
                let d = face
                    .project(q, None)
                    .map_or(f64::INFINITY, |uv| face.point(uv).distance(q));
                assert!(
                    d <= 1e-6 * (1.0 + q.length()),
                    "{file}: the vertex loop of face #{} lies {d} off its surface",
                    face.id
                );
                checked += 1;
            }
        }
    }
    assert!(
        checked >= 2,
        "the CTC-01 cones' apexes were not found ({checked})"
    );
}

/// Large STEP files travel gzip-compressed (STEP shrinks about 8×): `.stp.gz` loads as the
/// file itself; a corrupt one is a clear error.
#[test]
fn gzip_compressed_step_loads_like_the_file() {
    use std::io::Write;
    let dir = common::scratch("step-gzip");
    let plain = common::root().join("models/screw.step");
    let bytes = std::fs::read(&plain).expect("readable");
    let gz = dir.join("screw.step.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(&bytes).expect("compress");
    std::fs::write(&gz, enc.finish().expect("compress")).expect("write");
    let a = load(&plain).expect("plain loads");
    let b = load(&gz).expect("gzip loads");
    assert_eq!(a.patches.len(), b.patches.len());
    assert_eq!(a.bbox, b.bbox);
    let bad = dir.join("bad.stp.gz");
    std::fs::write(&bad, &bytes[..100]).expect("write");
    let e = load(&bad).expect_err("not gzip");
    assert!(e.to_string().contains("gzip"), "{e}");
    let other = dir.join("x.bpt.gz");
    std::fs::write(&other, b"").expect("write");
    assert!(matches!(
        load(&other),
        Err(LoadError::UnsupportedFormat { .. })
    ));
}

/// A solid with a void (BREP_WITH_VOIDS) is one placed solid, as a kernel reads it: its void
/// shell joins the outer shell's instance instead of being placed as a solid of its own.
#[test]
fn a_solid_with_a_void_is_one_instance() {
    let text = std::fs::read_to_string(common::root().join("models/screw.step")).expect("screw");
    let plain = parse(&text).expect("screw loads");
    // A second shell entity with the same faces, reversed, as the void (enough to give the
    // solid two shells).
    let voided = text
        .replace(
            "#12 = MANIFOLD_SOLID_BREP('',#13);",
            "#12 = BREP_WITH_VOIDS('',#13,(#999991));\n\
             #999991 = ORIENTED_CLOSED_SHELL('',*,#999992,.F.);",
        )
        .replacen("#13 = CLOSED_SHELL('',(", "#999992 = CLOSED_SHELL('',(", 1);
    // ... and #13 itself again, under its own id.
    let shell13 = text
        .lines()
        .skip_while(|l| !l.starts_with("#13 = CLOSED_SHELL"))
        .scan(false, |done, l| {
            if *done {
                return None;
            }
            *done = l.trim_end().ends_with(';');
            Some(l)
        })
        .collect::<Vec<_>>()
        .join("\n");
    let voided = voided.replacen("DATA;", &format!("DATA;\n{shell13}"), 1);
    assert_ne!(
        voided, text,
        "screw.step changed: the test no longer adds a void"
    );
    let scene = parse(&voided).expect("voided screw loads");
    assert_eq!(plain.instances.len(), 1);
    assert_eq!(scene.instances.len(), 1, "{:?}", scene.instances);
    assert_eq!(scene.patches.len(), 2 * plain.patches.len());
    assert!(scene.patches.iter().all(|p| p.instance == 0));
}

/// A face bounded by closed B-spline curves with unclamped knots (OCCT writes them: knots
/// (1, 3, 2, …, 3, 1) over −0.145..1.119): each curve is defined on its clamped range
/// [u_p, u_{n}] = 0..1, not on the whole knot vector, so the loop runs once around and the
/// face is drawn (it was skipped as "the trimmed domain is empty"; from kicad-demo-tinytapeout).
#[test]
fn a_loop_of_unclamped_bsplines_bounds_its_face() {
    let path = common::root().join("tests/data/step/unclamped_bspline_loop.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 1);
    let view = patchwork::view::View::framing(
        &scene.bounds,
        scene.up.vector(),
        45f64.to_radians(),
        (800, 600),
    );
    let meshes = patchwork::tessellate::tessellate_scene(&scene, &view, 0.5);
    let m = &meshes[0];
    assert!(m.failure.is_none(), "{:?}", m.failure);
    // The ring between the two loops: its outer loop spans x −9.818..−8.894, y 1.965..2.965.
    let (lo, hi) = m.positions.iter().fold(
        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let near = |a: f32, b: f32| (a - b).abs() < 2e-3;
    assert!(near(lo.x, -9.8175) && near(hi.x, -8.8942), "{lo} {hi}");
    assert!(near(lo.y, 1.965) && near(hi.y, 2.965), "{lo} {hi}");
    let area: f32 = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            (b - a).cross(c - a).length() / 2.0
        })
        .sum();
    // Outer loop ≈ 0.92 × 1.0 rounded rectangle, inner ≈ 0.66 × 0.78: a ring of ~0.35 mm².
    assert!((0.2..0.6).contains(&area), "area {area}");
}

/// A cylinder whose bottom circle is three arcs, one of them 7.8e-9 mm long between two
/// distinct vertices (KiCad's OCCT export, face #3503 of kicad-demo-video): the tiny arc is a
/// chord of that length, not a whole circle. Read as a whole circle (both vertices located at
/// one parameter, taken for a closed edge) the face's loop ran around twice and its mesh was a
/// fixed 0.93 mm off the cylinder at every tolerance (error/ε 2.8 at 0.33 mm, 20 at 0.033 mm).
#[test]
fn a_tiny_arc_between_two_vertices_is_not_a_whole_circle() {
    use patchwork::check::fidelity::measure_meshes;
    let path = common::root().join("tests/data/step/tiny_arc_cylinder.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 1);
    for tol in [0.33, 0.1, 0.02] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        // The independent measure (dense samples against the trimmed face, both ways).
        let faces = measure_meshes(&scene, &meshes);
        let (_, f) = faces.first().expect("one trimmed face");
        assert!(
            f.ratio() <= 1.6,
            "tol {tol}: error/tol {} (outside {}, missing {})",
            f.ratio(),
            f.outside,
            f.missing
        );
        // Radius 1.5, height 2.8: lateral area 26.39 mm², each point covered once.
        let area: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        assert!((25.0..26.5).contains(&area), "tol {tol}: area {area}");
    }
}

/// Wide cones (semi-angle 1.212 rad, radius 135.4 at their placement) whose faces lie past the
/// apex, on the far nappe (faces #4014, #3838 and #4134 of trj4_pm2-ec-214, CAx-IF; #3838 needs
/// the guesses' full reach, a third of it was not enough; #4134 their 4× steps along the axis):
/// the first loop point was
/// searched from guesses in truck's nominal `0..1` along the axis only, so every search ended
/// on the near nappe, the loop 12–22 mm off the surface and the mesh a fixed 22 mm off (error
/// 145 ε in `stats`, 14 such cones in trj4). Judged here also by the cone's own equation,
/// which shares no code with the tessellator or the measure.
#[test]
fn a_wide_cone_past_its_apex_is_tessellated_within_tolerance() {
    use patchwork::check::fidelity::measure_meshes;
    let path = common::root().join("tests/data/step/wide_cone_past_apex.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 3);
    // All three faces: CONICAL_SURFACE(#4022: origin (0, 127.1658, 0), axis +y, 135.442, 1.212026 rad): in the
    // half plane (height h along the axis, distance ρ from it) both nappes are ρ = ±(R + h tan α).
    let (origin, axis) = (glam::DVec3::new(0.0, 127.16579870753, 0.0), glam::DVec3::Y);
    let (r, t) = (135.44212988674, 1.212025656524f64.tan());
    let off_cone = |p: glam::DVec3| {
        let h = (p - origin).dot(axis);
        let rho = (p - origin - h * axis).length();
        let n = (1.0 + t * t).sqrt();
        ((rho - r - h * t).abs() / n).min((rho + r + h * t).abs() / n)
    };
    for tol in [0.3, 0.1, 0.03, 0.01] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let faces = measure_meshes(&scene, &meshes);
        assert_eq!(faces.len(), 3);
        for (m, (_, f)) in meshes.iter().zip(&faces) {
            assert!(m.failure.is_none(), "{:?}", m.failure);
            assert!(
                m.error <= tol,
                "face #{} tol {tol}: the tessellator reports {}",
                f.face,
                m.error
            );
            assert!(
                f.ratio() <= 1.1 && f.outside == 0,
                "face #{} tol {tol}: error/tol {} (outside {}, missing {})",
                f.face,
                f.ratio(),
                f.outside,
                f.missing
            );
            // Corners, edge midpoints and centroids against the cone's equation.
            let mut worst = 0.0f64;
            for tri in &m.triangles {
                let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
                for p in [
                    a,
                    b,
                    c,
                    (a + b) / 2.0,
                    (b + c) / 2.0,
                    (c + a) / 2.0,
                    (a + b + c) / 3.0,
                ] {
                    worst = worst.max(off_cone(p));
                }
            }
            // f32 vertices ~100 mm from the origin: ~1e-5 mm of rounding.
            assert!(
                worst <= tol + 1e-4,
                "face #{} tol {tol}: {worst} mm off the cone",
                f.face
            );
        }
    }
}

/// A whole sphere whose only bound is a `VERTEX_LOOP` at its pole (face #1364 of
/// trj4_pm2-ec-214): drawn as the whole surface (bounded by its seam meridian, as a kernel
/// bounds it), not skipped as "the face has no edge loop". Judged by the sphere's own
/// equation and its area.
#[test]
fn a_sphere_bounded_by_a_vertex_loop_is_drawn_whole() {
    let path = common::root().join("tests/data/step/whole_sphere_vertex_loop.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 1);
    let r = 1.899999856949f64;
    for tol in [0.05, 0.01] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        assert!(
            m.error <= tol,
            "tol {tol}: the tessellator reports {}",
            m.error
        );
        let (mut worst, mut area) = (0.0f64, 0.0f64);
        for tri in &m.triangles {
            let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
            area += (b - a).cross(c - a).length() / 2.0;
            for p in [
                a,
                b,
                c,
                (a + b) / 2.0,
                (b + c) / 2.0,
                (c + a) / 2.0,
                (a + b + c) / 3.0,
            ] {
                worst = worst.max((p.length() - r).abs());
            }
        }
        assert!(worst <= tol + 1e-5, "tol {tol}: {worst} off the sphere");
        // Inscribed within tol, covered once: 4πr² (1 − 2 tol/r) ≤ area ≤ 4πr².
        let full = 4.0 * std::f64::consts::PI * r * r;
        assert!(
            area <= full * 1.0001 && area >= full * (1.0 - 2.0 * tol / r),
            "tol {tol}: area {area} of {full}"
        );
    }
}

/// `OFFSET_SURFACE`s of elementary bases (OCCT solids whose cylinder, sphere and cone were
/// rewritten as offsets of a cylinder r 10 by +2, a sphere r 12 by −3 and a cone by +1.5,
/// the same geometry): every face drawn, judged by the offset surfaces' own equations.
/// Before `io::step::offset` the three faces were skipped ("Lookup failed").
#[test]
fn offsets_of_elementary_surfaces_are_the_surfaces_they_describe() {
    let path = common::root().join("tests/data/step/offset_elementary.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    let tol = 0.01;
    let meshes = tessellate_scene_tolerance(&scene, tol);
    let mut judged = Vec::new();
    for (p, m) in scene.patches.iter().zip(&meshes) {
        let PatchSurface::Trimmed(face) = &p.surface else {
            continue;
        };
        let kind = patchwork::check::fidelity::surface_kind(&face.surface);
        // distance from the surface each face must lie on (cone: ρ = 10 − 0.4 z, z in 0..15)
        let off: Box<dyn Fn(glam::DVec3) -> f64> = match kind {
            "cylinder" => Box::new(|q: glam::DVec3| (q.truncate().length() - 12.0).abs()),
            "sphere" => {
                Box::new(|q: glam::DVec3| (q - glam::DVec3::new(40.0, 0.0, 0.0)).length() - 9.0)
            }
            "cone" => Box::new(|q: glam::DVec3| {
                let rho = (q - glam::DVec3::new(-40.0, 0.0, q.z)).length();
                (rho - (10.0 - 0.4 * q.z)).abs() / (1.0f64 + 0.16).sqrt()
            }),
            _ => continue,
        };
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let mut worst = 0.0f64;
        for tri in &m.triangles {
            let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
            for q in [a, b, c, (a + b + c) / 3.0] {
                worst = worst.max(off(q).abs());
            }
        }
        assert!(
            worst <= tol + 1e-5,
            "face #{} ({kind}): {worst} mm off its surface",
            face.id
        );
        judged.push(kind);
    }
    judged.sort_unstable();
    assert_eq!(judged, ["cone", "cylinder", "sphere"]);
}

/// gen-1-14 (tools/cad_generator.py, seed 1, model 14): a circle swept along a helix, written
/// by OCCT as a rational B-spline of degree 6 × 11 whose u knots (−2π, 0 ×6, 2π ×6, 4π) are not
/// clamped. truck gave ∂S/∂u = 0 on the seam at u = 2π, the tessellator took it for a pole and
/// tore the seam open (1 506 ε, 245 757 triangles); `model::knots` clamps the knots on reading.
/// Judged against the helix of the recipe (`models/generated/gen-1-14.json`), no code shared:
/// every vertex and triangle centre of the tube lies at the wire's radius from the helix.
#[test]
fn a_spring_with_unclamped_knots_lies_on_its_tube() {
    use patchwork::tessellate::{PatchMesh, TrimmedTessellator};
    let path = common::root().join("models/generated/gen-1-14.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    // The recipe's spring: helix radius, wire radius, pitch, turns (about z from (R, 0, 0)).
    let (r_helix, wire, pitch, turns) = (7.546, 0.76, 6.793, 1.83);
    let rise = pitch / std::f64::consts::TAU;
    let helix = |t: f64| glam::DVec3::new(r_helix * t.cos(), r_helix * t.sin(), rise * t);
    let dist = |q: glam::DVec3| {
        // Nearest parameter: start from the point's angle in the turn its height is in, then
        // golden-section search over ±1 rad (the distance is unimodal that close).
        let a = q.y.atan2(q.x);
        let k = ((q.z / rise - a) / std::f64::consts::TAU).round();
        let (mut lo, mut hi) = (
            a + k * std::f64::consts::TAU - 1.0,
            a + k * std::f64::consts::TAU + 1.0,
        );
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if helix(x1).distance(q) < helix(x2).distance(q) {
                hi = x2;
            } else {
                lo = x1;
            }
        }
        let t = (0.5 * (lo + hi)).clamp(0.0, turns * std::f64::consts::TAU);
        helix(t).distance(q)
    };
    // The profile circle is upright (normal +y), not normal to the helix: the tube's section
    // is the circle seen at the helix's slope, at most wire / cos(slope) from the axis.
    let slope = (rise / r_helix).atan();
    let face = scene
        .patches
        .iter()
        .find_map(|p| match &p.surface {
            PatchSurface::Trimmed(f)
                if patchwork::check::fidelity::surface_kind(&f.surface) == "nurbs" =>
            {
                Some(f)
            }
            _ => None,
        })
        .expect("the tube face is drawn");
    let mut tess = TrimmedTessellator::new();
    let mut mesh = PatchMesh::default();
    for eps in [0.1, 0.02] {
        tess.tessellate(face, eps, &mut mesh).expect("tessellates");
        assert!(
            mesh.error <= eps,
            "ε {eps}: the tessellator measured {}",
            mesh.error
        );
        assert!(
            mesh.triangles.len() < 60_000,
            "ε {eps}: {} triangles",
            mesh.triangles.len()
        );
        let (lo, hi) = (wire - eps - 1e-3, wire / slope.cos() + eps + 1e-3);
        let mut worst = (0.0f64, glam::DVec3::ZERO);
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|i| mesh.positions[i as usize].as_dvec3());
            for q in [a, b, c, (a + b + c) / 3.0] {
                let d = dist(q);
                let off = (lo - d).max(d - hi);
                if off > worst.0 {
                    worst = (off, q);
                }
            }
        }
        assert!(
            worst.0 <= 0.0,
            "ε {eps}: {:.4} mm outside the tube [{lo:.4}, {hi:.4}] at {:.3}",
            worst.0,
            worst.1
        );
    }
}

/// gen-1-45 (a spring cut by a plane): the cut face's short arc runs over the seam of the
/// wire's closed B-spline circle, from just before the curve's end to its start point. The
/// edge was located from t ≈ 0.96 back to 0, the long way round: the face's loop crossed
/// itself (16 crossing constraints) and OCCT's judge found our samples 3.15 T off.
#[test]
fn an_edge_over_the_seam_of_a_closed_bspline_is_the_short_arc() {
    use patchwork::model::trimmed::{Curve3D, TrimEdge};
    use truck_stepio::r#in::alias::re_exports::{
        BSplineCurve, KnotVec, NurbsCurve, ParametricCurve, Vector4,
    };
    // The exact unit circle as a rational quadratic, clamped, starting and ending at (1, 0, 0).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let pts = [
        (1.0, 0.0, 1.0),
        (1.0, 1.0, h),
        (0.0, 1.0, 1.0),
        (-1.0, 1.0, h),
        (-1.0, 0.0, 1.0),
        (-1.0, -1.0, h),
        (0.0, -1.0, 1.0),
        (1.0, -1.0, h),
        (1.0, 0.0, 1.0),
    ]
    .map(|(x, y, w)| Vector4::new(x * w, y * w, 0.0, w));
    let knots = KnotVec::from(vec![
        0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
    ]);
    let curve = Curve3D::NurbsCurve(NurbsCurve::new(BSplineCurve::new(knots, pts.to_vec())));
    let at = |deg: f64| {
        let a = deg.to_radians();
        glam::DVec3::new(a.cos(), a.sin(), 0.0)
    };
    let on = |q: glam::DVec3| (q.length() - 1.0).abs() < 1e-9;
    let probe = curve.subs(0.9);
    assert!(probe.y < 0.0, "the curve runs counter-clockwise");
    // 330° → 0°: 30° over the seam.
    let e = TrimEdge::new(7, curve.clone(), at(330.0), at(0.0), false, 1e-7).expect("located");
    for k in 0..=16 {
        let q = e.point(e.t0 + (e.t1 - e.t0) * f64::from(k) / 16.0);
        assert!(on(q), "{q}");
        let deg = q.y.atan2(q.x).to_degrees();
        assert!(
            (-30.0 - 1e-6..=1e-6).contains(&deg),
            "point {k} at {deg:.1}°: the long way round"
        );
    }
    assert!(e.point(e.t1).distance(at(0.0)) < 1e-9);
    // An edge that does not cross the seam keeps its range: 30° → 90°.
    let f = TrimEdge::new(8, curve, at(30.0), at(90.0), false, 1e-7).expect("located");
    assert!(f.wrap.is_none() && f.t0 < f.t1);
    let mid = f.point(0.5 * (f.t0 + f.t1));
    assert!(mid.x > 0.0 && mid.y > 0.0);
}

/// An `OFFSET_SURFACE` of a B-spline (OCCT's shell of a loft: generated model gen-1-2, reduced
/// by the judge to `models/generated/gen-1-2.step.gz`) or of an extruded spline (gen-1-19) was
/// refused, its face not drawn (OCCT judge b 2.37 T and 10.44 T). It is now read on its basis and evaluated as the offset (`model::nurbs`). Judged
/// by truck's own evaluation and search on the basis, no code shared with ours: no interior
/// vertex or triangle centre of the offset face is farther than the offset distance from the basis, and 95 % lie
/// at it within ε (nearer only where the basis curves tighter than the distance). Seen failing
/// with the offset's point left on its basis: 0 of 16 910 vertices of gen-1-2 at the distance.
#[test]
fn an_offset_of_a_bspline_is_drawn_at_its_distance() {
    use patchwork::model::nurbs::FastSurface;
    use patchwork::tessellate::{PatchMesh, TrimmedTessellator};
    use truck_stepio::r#in::alias::re_exports::SearchNearestParameter;
    use truck_stepio::r#in::alias::re_exports::{ParametricSurface, Point3, SPHint2D};
    let mut offsets = Vec::new();
    // gen-1-19's offset face (of an extrusion) is judged by OCCT in CI (the corpus judge reads
    // models/generated/); truck's search on an extrusion's unbounded v is no reference here.
    for file in ["gen-1-2.step.gz", "gen-1-19.step.gz"] {
        let scene = load(&common::root().join("models/generated").join(file)).expect("loads");
        assert!(scene.skipped.is_empty(), "{file}: {:?}", scene.skipped);
        let drawn = |swept: bool| {
            scene.patches.iter().filter_map(move |p| match &p.surface {
                PatchSurface::Trimmed(f) => match f.fast.as_deref() {
                    Some(FastSurface::Offset { distance, .. }) if !swept => {
                        Some((f.clone(), *distance))
                    }
                    Some(FastSurface::OffsetOfTruck { distance, .. }) if swept => {
                        Some((f.clone(), *distance))
                    }
                    _ => None,
                },
                _ => None,
            })
        };
        let swept = file == "gen-1-19.step.gz";
        assert!(drawn(swept).count() > 0, "{file}: no offset face drawn");
        if !swept {
            offsets.extend(drawn(false));
        }
    }
    let mut tess = TrimmedTessellator::new();
    let mut mesh = PatchMesh::default();
    for (face, d) in &offsets {
        let eps = 2e-3 * face.bounds.radius;
        assert!(
            d.abs() > 10.0 * eps,
            "an offset of {d} is no test at ε {eps}"
        );
        tess.tessellate(face, eps, &mut mesh).expect("tessellates");
        let (mut farther, mut at_distance) = (0.0f64, 0usize);
        let mut hint = SPHint2D::None;
        // Interior vertices and triangle centres: border vertices are the file's edge points,
        // which the tessellator does not choose (the shell's rim edge meets the basis at the
        // loft's open end); an extrusion's face has no interior vertices.
        let border: std::collections::HashSet<u32> =
            mesh.borders.iter().flatten().copied().collect();
        let centres = mesh.triangles.iter().map(|t| {
            t.iter()
                .map(|&i| mesh.positions[i as usize])
                .sum::<glam::Vec3>()
                / 3.0
        });
        let points: Vec<glam::Vec3> = (mesh.positions.iter().enumerate())
            .filter(|(i, _)| !border.contains(&(*i as u32)))
            .map(|(_, v)| *v)
            .chain(centres)
            .collect();
        let mut checked = 0;
        for v in &points {
            checked += 1;
            let q = Point3::new(v.x as f64, v.y as f64, v.z as f64);
            // Truck's search from the last foot point and from its own start; the nearer.
            let dist = |(u, w): (f64, f64)| {
                let foot = face.surface.subs(u, w);
                ((foot.x - q.x).powi(2) + (foot.y - q.y).powi(2) + (foot.z - q.z).powi(2)).sqrt()
            };
            let Some(best) = [hint, SPHint2D::None]
                .into_iter()
                .filter_map(|h| face.surface.search_nearest_parameter(q, h, 100))
                .min_by(|a, b| dist(*a).total_cmp(&dist(*b)))
            else {
                continue;
            };
            hint = SPHint2D::Parameter(best.0, best.1);
            // Never farther than the distance (the basis point it was moved from is that far);
            // nearer only where the basis curves tighter than the distance.
            farther = farther.max(dist(best) - d.abs());
            at_distance += usize::from((dist(best) - d.abs()).abs() <= eps + 1e-4 * d.abs());
        }
        assert!(
            checked > 100,
            "face #{}: {checked} interior vertices",
            face.id
        );
        assert!(
            farther <= eps + 1e-4 * d.abs(),
            "face #{}: a vertex {farther} farther than the offset distance {d} (ε {eps})",
            face.id
        );
        assert!(
            at_distance * 20 >= checked * 19,
            "face #{}: {at_distance} of {checked} points at the offset distance {d} (ε {eps})",
            face.id
        );
    }
}

/// A generated model whose edges are healed: loaded, nothing skipped, its warnings.
fn healed_model(path: &str) -> (Scene, String) {
    let scene = load(&common::root().join(path)).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    let w = scene.warnings.join("\n");
    (scene, w)
}

/// Face `id` of `scene` tessellated by itself at ε = 1e-3 of its radius, and ε.
fn face_mesh(scene: &Scene, id: u64) -> (patchwork::tessellate::PatchMesh, f64) {
    use patchwork::tessellate::{PatchMesh, TrimmedTessellator};
    let face = scene
        .patches
        .iter()
        .find_map(|p| match &p.surface {
            PatchSurface::Trimmed(f) if f.id == id => Some(f.clone()),
            _ => None,
        })
        .unwrap_or_else(|| panic!("face #{id} is drawn"));
    let eps = 1e-3 * face.bounds.radius;
    let mut mesh = PatchMesh::default();
    TrimmedTessellator::new()
        .tessellate(&face, eps, &mut mesh)
        .expect("tessellates");
    (mesh, eps)
}

/// gen-1-78 (tools/cad_generator.py seed 1 model 78, reduced): OCCT's offset of a box wrote
/// edge #2171, a quarter CIRCLE of radius 2.376 at x = 59.978, with its start vertex at
/// x = 39.91, 20 off the circle. The face it bounds (#2167, the quarter cylinder rounding the
/// box's edge) was skipped: "vertices not on its curve" (OCCT judge b 1.99 T). Healed as
/// OCCT heals it, the face is drawn along the whole edge of the box: judged by the cylinder's
/// own equation (axis along x through (0, 0, 7.865), radius 2.376), no code shared.
#[test]
fn an_edge_whose_vertex_is_off_its_circle_is_healed_and_its_face_drawn() {
    let (scene, w) = healed_model("models/generated/gen-1-78.step.gz");
    assert!(
        w.contains("healed") && w.contains("#2171 by 2.007e1"),
        "{w}"
    );
    let (mesh, eps) = face_mesh(&scene, 2167);
    let (mut x0, mut x1, mut off) = (f32::MAX, f32::MIN, 0.0f32);
    for v in &mesh.positions {
        x0 = x0.min(v.x);
        x1 = x1.max(v.x);
        let r = (v.y.powi(2) + (v.z - 7.865).powi(2)).sqrt();
        off = off.max((r - 2.376).abs());
        // The quarter between the box's side (y = -2.376) and its top (z = 10.241).
        assert!(
            v.y <= 1e-3 && v.z >= 7.865 - 1e-3,
            "{v} is not on the rounding quarter"
        );
    }
    assert!(
        off <= eps as f32,
        "a vertex {off} off the cylinder (ε {eps})"
    );
    assert!(
        x0.abs() < 1e-3 && (x1 - 59.978).abs() < 1e-3,
        "drawn over x {x0} .. {x1}"
    );
    let area: f32 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let quarter = 59.978 * std::f32::consts::FRAC_PI_2 * 2.376;
    assert!(
        (area - quarter).abs() < 0.01 * quarter,
        "area {area}, the whole quarter cylinder is {quarter}"
    );
}

/// A sphere bounded by a VERTEX_LOOP at its pole and a hole (the shape OCCT writes for a
/// sphere a feature cuts through: generated model gen-1-164, text fused with a sphere, kept
/// as `models/generated/gen-1-164.step.gz`, and gen-1-137). The hole alone was drawn (a cap
/// of 4.7 % of the sphere's area; OCCT judge b 9.4 T, the whole sphere missing) and `stats`
/// did not see it (trimmed error/ε 0.899: its measure reads the same loops). Judged by the
/// sphere's own area: 4πr² less the cap 2πr·r(1 − cos 30°); no vertex inside the hole.
#[test]
fn a_sphere_with_a_vertex_loop_and_a_hole_is_drawn_whole_but_the_hole() {
    let path = common::root().join("tests/data/step/sphere_vertex_loop_with_hole.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    assert_eq!(scene.patches.len(), 1);
    let r = 2.0f64;
    let cap_plane = r * (std::f64::consts::PI / 6.0).cos();
    let expected =
        4.0 * std::f64::consts::PI * r * r - 2.0 * std::f64::consts::PI * r * (r - cap_plane);
    for tol in [0.05, 0.01] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let mut area = 0.0f64;
        for tri in &m.triangles {
            let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
            area += (b - a).cross(c - a).length() / 2.0;
            for p in [a, b, c, (a + b + c) / 3.0] {
                assert!(
                    (p.length() - r).abs() <= tol + 1e-5,
                    "tol {tol}: {p} off the sphere"
                );
                assert!(p.x <= cap_plane + tol, "tol {tol}: {p} inside the hole");
            }
        }
        assert!(
            area <= expected * 1.002 && area >= expected * (1.0 - 2.0 * tol / r) * 0.998,
            "tol {tol}: area {area}, the sphere less its hole is {expected}"
        );
    }
}

/// gen-3-15 (seed 3 model 15, reduced to its part): a sphere of radius 10.15 with a 63.7°
/// wedge cut out (u from 5.172 to 2π) and the wedge's inner edge filleted. The sphere face has
/// one loop (the wedge's two meridians and the fillet's arcs near the poles) and no
/// `VERTEX_LOOP`: by the even-odd rule alone the loop's inside in (u, v) was drawn, the wedge,
/// where the face's orientation puts it on the other side (OCCT judge a 50 T, b 104 T).
/// Judged by the sphere's own equation: the mesh covers 296.3° of the sphere (its area) and
/// has no vertex inside the wedge.
#[test]
fn a_sphere_face_outside_its_only_loop_is_drawn_outside_it() {
    let (scene, _) = healed_model("models/generated/gen-3-15.step");
    let (m, eps) = face_mesh(&scene, 35);
    let r = 10.15f64;
    let (cut_from, cut_to) = (5.172f64, std::f64::consts::TAU);
    let area = f64::from(area_and_box(&m).0);
    for p in &m.positions {
        let p = p.as_dvec3();
        // The fillet arcs lie up to 0.021 off the sphere (the edges as OCCT wrote them).
        assert!((p.length() - r).abs() <= 3e-3 * r, "{p} off the sphere");
        let angle = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU);
        let latitude = (p.z / r).clamp(-1.0, 1.0).asin();
        assert!(
            latitude.abs() > 1.3 || !(cut_from + 0.01..cut_to - 0.01).contains(&angle),
            "{p} (angle {angle}, latitude {latitude}) inside the cut wedge"
        );
    }
    let sphere = 4.0 * std::f64::consts::PI * r * r;
    let kept = sphere * (cut_from / std::f64::consts::TAU);
    assert!(
        area >= 0.98 * kept && area <= 1.01 * kept,
        "area {area} (ε {eps}): 296.3° of the sphere is {kept}"
    );
}

/// gen-1-12 (seed 1 model 12, kept as `gen-1-12-lune`): a sphere of radius 11.424 over
/// 195.864° of u, a lune whose loop runs up one meridian through both poles and down the
/// other. Reading which side of its loops a sphere face lies on (gen-3-15, above) unwrapped
/// the loop's angles the short way across the poles, took the 164° the face leaves out for
/// its inside and drew the whole sphere less the lune (Open CASCADE's judge a 106 T): a loop
/// through a pole is not read so. Judged by the sphere's equation and the lune's area.
#[test]
fn a_sphere_lune_through_both_poles_is_drawn_as_the_lune() {
    let (scene, _) = healed_model("models/generated/gen-1-12-lune.step");
    let (m, eps) = face_mesh(&scene, 35);
    let r = 11.424f64;
    let span = 195.864f64.to_radians();
    let area = f64::from(area_and_box(&m).0);
    for p in &m.positions {
        let p = p.as_dvec3();
        assert!((p.length() - r).abs() <= 1e-3 * r, "{p} off the sphere");
        let angle = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU);
        let across = (p.x * p.x + p.y * p.y).sqrt();
        assert!(
            across < 1e-3 * r || angle <= span + 1e-3 || angle >= std::f64::consts::TAU - 1e-3,
            "{p} (angle {angle}) outside the lune"
        );
    }
    let lune = 4.0 * std::f64::consts::PI * r * r * span / std::f64::consts::TAU;
    assert!(
        area >= 0.99 * lune && area <= 1.001 * lune,
        "area {area} (ε {eps}): the lune is {lune}"
    );
}

/// gen-4-17-cone (seed 4 model 17 reduced to its first part, a wide cone shelled inwards by
/// 1.048): the inner cone face #162 has one loop, its small circle (radius 3.464) and the
/// seam out to a vertex at radius 43.207, with no edge round the wide end. The tessellator
/// closed the loop at the cone's apex, so it drew the disc inside the small circle and a
/// sliver along the seam, not the band out to the seam's end (`stats` 800 ε; Open CASCADE's
/// judge a 2.83 T, b 2.65 T, and on the whole model the judge passed, the outer cone a shell
/// thickness away standing in for it). Judged by the frustum's own area, π (R₁ + R₂) L with
/// L = (R₁ − R₂) / sin α, and its extent.
#[test]
fn a_cone_loop_running_out_along_its_seam_is_closed_at_the_seam_end() {
    let (scene, _) = healed_model("models/generated/gen-4-17-cone.step");
    let (m, eps) = face_mesh(&scene, 162);
    let (r_wide, r_small, half_angle) = (43.206799055881f64, 3.463799055881f64, 1.521921007542f64);
    let slant = (r_wide - r_small) / half_angle.sin();
    let band = std::f64::consts::PI * (r_wide + r_small) * slant;
    let (area, lo, hi) = area_and_box(&m);
    let area = f64::from(area);
    assert!(
        area >= 0.99 * band && area <= 1.001 * band,
        "area {area} (ε {eps}): the band is {band}"
    );
    for (a, b) in [
        (lo.x, -r_wide),
        (lo.y, -r_wide),
        (hi.x, r_wide),
        (hi.y, r_wide),
    ] {
        assert!((f64::from(a) - b).abs() < 0.01 * r_wide, "box {lo} .. {hi}");
    }
}

/// A face of a helical V-thread (face #4228 of generated model gen-1-85, part 2: R 5, pitch
/// 1.92, 4.5 turns, cut by a cone; `tests/data/step/thread_face_coarse.step.gz`). At a coarse
/// tolerance (ε 1.66, the thread's own pitch) its loop points were projected onto the surface
/// with a reach of ε, so a point landed on the next turn of the thread: the loop ran over
/// three turns, crossed itself, and half the mesh lay outside the face (OCCT judge 3.84 T at
/// 4.3 % of the diagonal; `stats` 2.68 ε). Judged by the independent measure and by the area
/// and extent of a fine mesh (the defect drew turns the face does not have).
#[test]
fn a_thread_face_at_a_coarse_tolerance_stays_on_its_own_turn() {
    let scene = one_face("thread_face_coarse.step.gz");
    let fine = tessellate_scene_tolerance(&scene, 0.005);
    let (fine_area, fine_lo, fine_hi) = area_and_box(&fine[0]);
    for tol in [1.66, 0.9, 0.475] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let (area, lo, hi) = area_and_box(m);
        // Chords cut the curved strip short (7.7 of 10.9 at ε 1.66); more than the whole is
        // surface the face does not have.
        assert!(
            area <= 1.02 * fine_area,
            "tol {tol}: area {area}, the fine mesh's {fine_area}"
        );
        let grown = (lo - fine_lo).abs().max((hi - fine_hi).abs()).max_element();
        assert!(
            grown <= tol as f32,
            "tol {tol}: extent {lo} .. {hi}, the fine mesh's {fine_lo} .. {fine_hi}"
        );
        assert_measured_within(&scene, &meshes, tol);
    }
}

/// A wide cone (semi-angle 86.2°, r 31.3 at its base) cut by a plane along a hyperbola
/// (face #35 of generated model gen-1-42, `tests/data/step/wide_cone_hyperbola_trim.step`).
/// The loop point at the vertex the base circle and the hyperbola share carries the circle's
/// parameter, so the stretch of the hyperbola up to its first sample was refined on the
/// surface (a straight line in (u, v)) instead of on the curve: the mesh ran up to 2.8 mm
/// past the cutting plane (OCCT judge 10.98 T). Judged by the plane's own equation (PLANE
/// #211 of the file: the face lies on its negative side), no code shared, and by the measure.
#[test]
fn a_cone_cut_along_a_hyperbola_stays_on_its_side_of_the_cut() {
    let scene = one_face("wide_cone_hyperbola_trim.step");
    let origin = glam::DVec3::new(-22.9253871207, -4.267602307644, 4.066401393943);
    let normal = glam::DVec3::new(-0.293127604391, -0.882333555583, 0.36818976661);
    for tol in [0.259, 0.114, 1.14] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let past = m
            .positions
            .iter()
            .map(|p| (p.as_dvec3() - origin).dot(normal))
            .fold(f64::MIN, f64::max);
        assert!(
            past <= 1e-4,
            "tol {tol}: a vertex {past} past the cutting plane"
        );
        assert_measured_within(&scene, &meshes, tol);
    }
}

/// A ruled loft's side fused with a torus and filleted (face #35 of generated model gen-7-6,
/// part 0; `tests/data/step/loft_extended_past_seam.step.gz`): the fillet grew its B-spline
/// surface past the seam (u −5.38..75.72, the seam at 0 and 70.34), so near the seam the
/// surface covers itself. The loop's first vertex, on the seam, was projected onto the
/// extension and the loop followed it (up to 24 mm off the face; OCCT judge 18 T, `stats`
/// 136 ε). Judged by Open CASCADE's area and box of the face, no code shared, and by the
/// measure, which must not raise a false alarm where the sheets overlap. With the first-point
/// fix undone the area and box still hold (the wrong sheet lies close to the right one); the
/// measure is what fails (72 ε, 1 022 samples outside).
#[test]
fn a_surface_extended_past_its_seam_is_trimmed_on_the_sheet_of_its_loop() {
    let scene = one_face("loft_extended_past_seam.step.gz");
    let occt_area = 560.99f32;
    // Open CASCADE's exact box of the face (`BRepBndLib::AddOptimal`).
    let (box_lo, box_hi) = (
        glam::Vec3::new(-14.3711, -14.1234, -3.9498),
        glam::Vec3::new(9.9110, 10.1901, 13.4920),
    );
    for tol in [0.16, 0.048, 0.8] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let (area, lo, hi) = area_and_box(m);
        assert!(
            (area - occt_area).abs() < 0.01 * occt_area,
            "tol {tol}: area {area}, Open CASCADE's {occt_area}"
        );
        let t = tol as f32;
        assert!(
            lo.cmpge(box_lo - t).all() && hi.cmple(box_hi + t).all(),
            "tol {tol}: the mesh spans {lo} .. {hi}, the face {box_lo} .. {box_hi}"
        );
        assert_measured_within(&scene, &meshes, tol);
    }
}

/// An `OFFSET_SURFACE` (by 2.345) of a `RECTANGULAR_TRIMMED_SURFACE` of a linear extrusion
/// (face #843 of generated model gen-1-146, a shelled extruded spline;
/// `tests/data/step/offset_of_trimmed_extrusion.step.gz`) was skipped ("offsets of this
/// surface are not read yet"; OCCT judge b 1.11 T). The trimmed surface only restricts its
/// basis' parameters: drawn as the basis' offset. Judged by Open CASCADE's area of the face
/// (`BRepGProp`, 1 379.93 mm²), no code shared, and by the measure.
#[test]
fn an_offset_of_a_trimmed_surface_is_the_offset_of_its_basis() {
    let scene = one_face("offset_of_trimmed_extrusion.step.gz");
    let occt_area = 1379.93f32;
    for tol in [0.05, 0.2] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let (area, _, _) = area_and_box(m);
        assert!(
            (area - occt_area).abs() < 0.01 * occt_area,
            "tol {tol}: area {area}, Open CASCADE's {occt_area}"
        );
        assert_measured_within(&scene, &meshes, tol);
    }
}

/// A torus fillet ring (R 10.3, r 3.142, v from 0.012 to π/2: face #212 of generated model
/// gen-1-104; `tests/data/step/torus_ring_seam_twice.step`) bounded by one loop: its seam
/// twice and two circles, closed in (u, v). The measure, by the side of the nearest boundary
/// alone on a surface periodic both ways, called nearly every sample outside (`stats` 18 ε
/// where the OCCT judge passes at the same tolerance), and by even-odd it missed the samples
/// on the seam (u = −1e-17 rounded to 2π against one segment, not against the other). Judged
/// by the band's own area, 2πr·(R(π/2 − v₀) + r(1 − sin v₀)), no code shared, and by the
/// measure: no false alarm.
#[test]
fn a_torus_ring_bounded_by_its_seam_twice_is_measured_inside() {
    let scene = one_face("torus_ring_seam_twice.step");
    // 3.142 is the file's minor radius (TOROIDAL_SURFACE #201), not an approximation of π.
    #[allow(clippy::approx_constant)]
    let (big, r, v0) = (10.303705913099f64, 3.142f64, 0.012072904217175f64);
    let band = std::f64::consts::TAU
        * r
        * (big * (std::f64::consts::FRAC_PI_2 - v0) + r * (1.0 - v0.sin()));
    for tol in [0.07, 0.02] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let m = &meshes[0];
        assert!(m.failure.is_none(), "{:?}", m.failure);
        let (area, _, _) = area_and_box(m);
        assert!(
            (f64::from(area) - band).abs() < 0.01 * band,
            "tol {tol}: area {area}, the band's {band}"
        );
        assert_measured_within(&scene, &meshes, tol);
    }
}

/// A cone cut by a plane parallel to a generator (`tests/data/step/cone_parabola_bare_edge.step`,
/// made with Open CASCADE), the cut's edge pointing at its bare `PARABOLA`: truck-stepio reads a
/// parabola as a hyperbola, so the edge was healed onto the wrong curve (OCCT judge 6.8 T and
/// 26 T, `stats` 555 ε). Judged by the parabolic segment's area in closed form (Archimedes:
/// ⅔ · chord · height, 765.106 mm²; Open CASCADE's `BRepGProp` agrees to 10⁻⁹) and by Open
/// CASCADE's area of the cone face, no code shared, and by the measure.
#[test]
fn a_bare_parabola_edge_bounds_its_faces() {
    let path = common::root().join("tests/data/step/cone_parabola_bare_edge.step");
    let scene = load(&path).expect("loads");
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    let chord = 2.0 * (20.0f64 * 20.0 - 8.0 * 8.0).sqrt();
    let height = (14.0f64 * 14.0 + 28.0 * 28.0).sqrt();
    let expected = [(117u64, 2.0 / 3.0 * chord * height), (17, 1335.830)];
    for tol in [0.05, 0.2] {
        let meshes = tessellate_scene_tolerance(&scene, tol);
        for (face, want) in expected {
            let i = scene
                .patches
                .iter()
                .position(|p| matches!(&p.surface, PatchSurface::Trimmed(f) if f.id == face))
                .expect("the face is drawn");
            assert!(meshes[i].failure.is_none(), "{:?}", meshes[i].failure);
            let (area, _, _) = area_and_box(&meshes[i]);
            let area = f64::from(area);
            assert!(
                (area - want).abs() < 0.005 * want,
                "tol {tol}: face #{face} area {area}, expected {want}"
            );
        }
        let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
        for (_, f) in &faces {
            assert!(
                f.ratio() <= 1.1 && f.outside == 0,
                "tol {tol}: error/tol {} (outside {})",
                f.ratio(),
                f.outside
            );
        }
    }
}

/// A hyperbola edge whose vertex lies 6.6·10⁵ mm off (a fuzz input mutated from
/// `wide_cone_hyperbola_trim.step`; `tests/data/fuzz/step/hyperbola_far_vertex.step`): truck's
/// root finder for the vertex's parameter never returned (CI's fuzz run timed out). Now a clear
/// error naming the edge, at once; the test gives it a minute, so that a hang fails it rather
/// than the suite.
#[test]
fn a_hyperbola_vertex_far_off_its_curve_is_an_error_not_a_hang() {
    let path = common::root().join("tests/data/fuzz/step/hyperbola_far_vertex.step");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(load(&path).map(|s| s.patches.len()));
    });
    let result = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("reading the file ends within a minute");
    let err = result
        .expect_err("its one face cannot be drawn")
        .to_string();
    assert!(err.contains("edge #174"), "{err}");
}

/// A fuzz input mutated from `torus_ring_seam_twice.step` (its axis tilted, a circle's vertex
/// healed 2.7 mm onto its curve; `tests/data/fuzz/step/torus_eps_out_of_reach.step`, the
/// slowest face of the fuzz corpus, 0.55 s at 10⁻⁴ of the diagonal): no mesh of the face
/// reaches ε. Its refinement stops at its work budget, the mesh says which and what error it
/// reached, and the scene's totals count it (`stats` prints them); the well-formed face
/// reaches ε and stops at no budget.
#[test]
fn a_face_that_cannot_reach_eps_stops_at_its_budget_and_says_so() {
    let path = common::root().join("tests/data/fuzz/step/torus_eps_out_of_reach.step");
    let bad = load(&path).expect("loads");
    let tol = 0.0365;
    let meshes = tessellate_scene_tolerance(&bad, tol);
    let m = &meshes[0];
    assert!(m.failure.is_none(), "{:?}", m.failure);
    assert!(m.error > tol, "error {} within {tol}", m.error);
    assert!(
        m.stopped.is_some(),
        "error/eps {} and no budget stop",
        m.error / tol
    );
    let s = patchwork::tessellate::MeshStats::of(&meshes);
    assert_eq!(s.stopped, 1);
    assert_eq!(s.worst_stopped.map(|w| w.0), Some(m.patch_id));
    let good = one_face("torus_ring_seam_twice.step");
    let meshes = tessellate_scene_tolerance(&good, tol);
    assert!(meshes[0].error <= tol && meshes[0].stopped.is_none());
}

/// Generated model 1-44's spring wire (tools/cad_generator.py seed 1 model 44, its face cut
/// out): an offset of a rational B-spline tube 0.5 mm across, tessellated at ε = 1.5 mm. It
/// was drawn as slivers along its seam (triangles with two corners at one point, the seam's
/// two sides), and the measure read 3.2 ε "missing" (geom::point_triangle_distance gave NaN
/// for a triangle (a, a, c) and `min` skipped it; `geom`'s `degenerate_triangles` keeps that
/// fixed); OCCT's judge and an exact chord distance said 0.55 T. Since triangles that wrap
/// round the surface are refined (gen-22-50's tube, below), the tube is drawn with area, no
/// sliver spans its seam, and it is measured within ε.
#[test]
fn a_tube_thinner_than_eps_is_drawn_and_measured_within() {
    let scene = one_face("offset_tube_thinner_than_eps.step.gz");
    let tol = 1.5;
    let meshes = tessellate_scene_tolerance(&scene, tol);
    assert!(meshes[0].failure.is_none(), "{:?}", meshes[0].failure);
    let degenerate = meshes[0]
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| meshes[0].positions[i as usize]);
            a == b || b == c || c == a
        })
        .count();
    assert_eq!(degenerate, 0, "slivers with a repeated corner");
    assert_measured_within(&scene, &meshes, tol);
}

/// Generated model 1-136's fillet ring (seed 1 model 136, its face cut out): a torus face
/// bounded in part by an edge that is nearly straight in 3D (a plane's cut, z = 0) but bends
/// in the torus' parameters. The measure split its edges by their 3D chords only, so that
/// edge's chord in (u, v) cut 1.9 ε of the face off: 26 mesh samples read as outside the
/// trim, where OCCT's own classifier puts them inside the face (BRepClass_FaceClassifier IN).
#[test]
fn an_edge_straight_in_3d_but_bent_in_uv_bounds_the_measure_where_it_bends() {
    let scene = one_face("torus_edge_straight_in_3d_bent_in_uv.step.gz");
    let tol = 0.602;
    let meshes = tessellate_scene_tolerance(&scene, tol);
    assert!(meshes[0].failure.is_none(), "{:?}", meshes[0].failure);
    assert_measured_within(&scene, &meshes, tol);
}

/// Generated model 1-32 (seed 1 model 32, whole): OCCT's shell of it failed and left a plane
/// face (#155) whose edge curves lie 0.572 mm off the plane. No mesh through those edges can
/// be nearer the plane: the tessellator refined it for 10 rounds, stopped at its budget with
/// error/ε 1.2 (T = 0.477 mm), and the measure said 1.2 ε, where OCCT's judge finds 1.03 T.
/// Both now count the error beyond the border's own offset (interpolated over each triangle
/// from its corners on the edges), and the measure reports the offset itself.
#[test]
fn a_face_whose_edges_lie_off_its_surface_is_judged_beyond_that_offset() {
    let scene =
        load(&common::root().join("tests/data/step/plane_edges_off_surface.step")).expect("loads");
    let tol = 0.477;
    let meshes = tessellate_scene_tolerance(&scene, tol);
    let s = patchwork::tessellate::MeshStats::of(&meshes);
    assert_eq!(s.stopped, 0, "a budget stop: {:?}", s.worst_stopped);
    assert!(
        s.worst_error_ratio <= 1.0,
        "error/eps {}",
        s.worst_error_ratio
    );
    let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
    let plane = faces
        .iter()
        .map(|f| &f.1)
        .find(|f| f.face == 155)
        .expect("face #155 measured");
    assert!(
        (plane.edge_offset - 0.572).abs() < 0.01,
        "edge offset {}",
        plane.edge_offset
    );
    for (_, f) in &faces {
        assert!(
            f.ratio() <= 1.1,
            "face #{}: error/tol {}",
            f.face,
            f.ratio()
        );
    }
}

/// gen-1-78b (seed 1 model 78 as OCCT built it on 2026-12-03, reduced): OCCT's offset of a box
/// left one vertex 20 off a corner of the box, shared by two arcs of radius 2.376 about the
/// corner (x = 59.978, y = 0, z = 7.865): #352 in the plane x = 59.978 and #2085 in z = 7.865.
/// Healed one by one, #352's nearest point was the corner's and #2085's a point 3/4 of the way
/// round its circle: the corner sphere (#2081) ran through the solid (OCCT judge 2 397 samples
/// up to 1.32 T, `stats` 1.22 ε). Healed as one vertex, both arcs meet at the corner, and the
/// sphere stays in its octant — judged by the sphere's own equation, no code shared.
#[test]
fn a_vertex_off_two_arcs_is_healed_to_where_they_meet() {
    let (scene, w) = healed_model("models/generated/gen-1-78b.step.gz");
    assert!(
        w.contains("#352 by 2.007e1") && w.contains("#2085 by 2.007e1"),
        "{w}"
    );
    let (mesh, _) = face_mesh(&scene, 2081);
    let c = glam::Vec3::new(59.978, 0.0, 7.865);
    let slack = 1e-3;
    for v in &mesh.positions {
        let r = v.distance(c);
        assert!((r - 2.376).abs() < 0.01, "{v} is {r} from the corner");
        assert!(
            v.x >= c.x - slack && v.y <= c.y + slack && v.z >= c.z - slack,
            "{v} is outside the corner's octant"
        );
    }
}

/// gen-7-13 (seed 7 model 13): a thread with a head, patterned three times. The measure
/// rebuilt the thread flank's outer helix (edge #1384, 4.07 turns) with 2 of its turns: a
/// chord across two turns has the curve's midpoint on it, and the midpoint was all it
/// compared. Samples of the flank's mesh along the missing turns read as outside the trim by
/// 1.73 ε (`stats` said 1.725 ε, 162 samples outside) where Open CASCADE's judge measured
/// 0.48 T; rebuilt whole, the measure reads 0.48 ε too.
#[test]
fn the_measure_rebuilds_every_turn_of_a_helix_edge() {
    let faces = measured_within("models/generated/gen-7-13.step.gz", 0.755, 42, 0.6);
    assert!(
        faces.iter().any(|(_, f)| f.face == 1378),
        "face #1378 measured"
    );
}

/// gen-7-13-8turns (gen-7-13's recipe with 8 turns): the tessellator cut each 8-turn helix
/// edge of the thread in two and compared each half with its chord at its quarter points and
/// midpoint, whole turns apart and all on the chord, so it drew two chords for 8 turns: the
/// flanks 6.16 T off their faces by Open CASCADE's judge, 7.99 ε by `stats`. Measured by the
/// fidelity measure (its own edge sampling, which follows every turn: `check::fidelity`).
#[test]
fn a_thread_of_eight_turns_is_drawn_along_every_turn() {
    measured_within("models/generated/gen-7-13-8turns.step.gz", 0.761, 54, 0.6);
}

/// gen-8-27 (seed 8 model 27 as OCCT built it, kept by `occt_fidelity --keep`): a thread of
/// 15.6 turns cut by another part. Five faces were skipped, "vertices not on its curve": the
/// edges' vertices lie on the thread's helix curves, but truck's nearest-point search and
/// Newton from the range's start both ended on other turns, so no parameter was found for
/// them (Open CASCADE's judge: 365 of its samples up to 1.28 T from ours, where the faces were
/// missing). Located from dense samples, every face is drawn within its tolerance.
#[test]
fn vertices_on_a_many_turn_helix_are_located_on_their_turn() {
    measured_within("models/generated/gen-8-27.step.gz", 0.833, 45, 0.6);
}

/// gen-2-47 (seed 2 model 47 reduced to one part: a revolved profile fused with a torus and
/// cut by a cone): the torus face #982's seam meridian is split by a lens-shaped hole into
/// edge #1010, a 0.19° arc (1.9e-5 m) from the seam's corner, and #1209. truck trims the
/// circle to that arc, but its ends lay within the vertex tolerance (1e-4) of each other, so
/// the arc was taken for a whole circle and its vertices located on it: the start fell at 2π,
/// the end at 0.0034, and the edge ran the long way round over #1209's half of the seam. The
/// tessellator then filled another region than the loops bound: 4 767 of 6 916 samples of the
/// face's mesh outside its trim, Open CASCADE's judge 45 T.
#[test]
fn a_tiny_seam_arc_is_not_taken_the_long_way_round() {
    let faces = measured_within("models/generated/gen-2-47.step.gz", 0.263, 9, 1.0);
    assert!(
        faces.iter().any(|(_, f)| f.face == 982),
        "face #982 measured"
    );
}

/// `path` (no face skipped) tessellated to `tol` as `stats --tolerance` does and measured face
/// by face (`check::fidelity`): at least `patches` measured, each within `max_ratio` `tol`, no sample
/// outside its trim and none of the face uncovered.
fn measured_within(
    path: &str,
    tol: f64,
    patches: usize,
    max_ratio: f64,
) -> Vec<(u32, FaceFidelity)> {
    let (scene, _) = healed_model(path);
    let meshes = tessellate_scene_tolerance(&scene, tol);
    let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
    assert!(faces.len() >= patches, "{} patches measured", faces.len());
    for (_, f) in &faces {
        assert!(
            f.ratio() <= max_ratio && f.outside == 0 && f.uncovered == 0,
            "face #{}: error/tol {} (outside {}, uncovered {})",
            f.face,
            f.ratio(),
            f.outside,
            f.uncovered
        );
    }
    faces
}

/// [`measured_within`] at `max_ratio` 1, and the face `face` among those measured.
fn measured_within_with(path: &str, tol: f64, patches: usize, face: u64) {
    let faces = measured_within(path, tol, patches, 1.0);
    assert!(
        faces.iter().any(|(_, f)| f.face == face),
        "{path}: face #{face} is measured"
    );
}

/// gen-1-78c (seed 1 model 78 as OCCT built it in one of several builds on 2026-12-04, kept by
/// `occt_fidelity --keep`): a cylinder face (#2035) of the offset box whose own edge curves lie
/// 17.8 mm (11.6 ε) off its surface. The mesh follows the edges, and OCCT's judge, against the
/// parts as built, finds 0.73 T; the measure allowed that offset to the mesh's own samples but
/// not to the face's samples judged against the mesh, and read 1.127 ε "missing" (`stats`
/// disagreed with the judge). Judged beyond the offset both ways, it reads 0.80 ε.
#[test]
fn a_face_whose_edges_lie_off_it_is_covered_beyond_that_offset() {
    let (scene, _) = healed_model("models/generated/gen-1-78c.step.gz");
    let tol = 1.534;
    let meshes = tessellate_scene_tolerance(&scene, tol);
    let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
    let off = faces
        .iter()
        .filter(|(_, f)| f.face == 2035)
        .map(|(_, f)| f.edge_offset)
        .fold(0.0, f64::max);
    assert!(off > 10.0 * tol, "face #2035's edges lie {off} off it");
    for (_, f) in &faces {
        assert!(
            f.ratio() <= 1.1 && f.outside == 0,
            "face #{}: error/tol {} (outside {}, missing {})",
            f.face,
            f.ratio(),
            f.outside,
            f.missing
        );
    }
}

/// gen-4-3-fillet (seed 4 model 3 reduced by hand to its filleted loft, two edges filleted):
/// on the fillet, a B-spline face (#2683), samples of the mesh that lie on the surface
/// (3e-7 from it) were read 1.56 ε off: the projections from the previous sample and from the
/// triangle's corner ended in one local minimum, and agreeing, the search from scratch was
/// skipped (`stats` raised an alarm the OCCT judge does not share). Measured from scratch
/// wherever the two agree on a point over ε away, the face reads 0.82 ε, as its mesh's
/// distance to the face's samples does.
#[test]
fn a_measure_does_not_stop_at_a_local_minimum_of_a_fillet() {
    let faces = measured_within("models/generated/gen-4-3-fillet.step.gz", 1.5, 4, 1.0);
    assert!(
        faces.iter().any(|(_, f)| f.face == 2683 && f.ratio() > 0.5),
        "the fillet face #2683 is measured"
    );
}

/// gen-12-57 (seed 12 model 57 reduced to its one part: a cone cut by a sphere, offset by
/// 1.695): the offset's B-spline band (#563) closes in v only to 1.1e-7 of a size of 2.8, as
/// OCCT builds it, and its loop uses the seam edge #568 both ways. Taken as open (closure
/// sought to 1e-9 of the size), the loop ran along v = 0 twice, the domain was the unit
/// square folded on itself (23 crossing constraints), and at T 0.3 the face read 5.02 ε with
/// 1 446 samples outside its trim (Open CASCADE's judge: 6.94 T). Closed to 1e-6 of its size,
/// the band is unwrapped across its seam like a periodic surface: 0.92 ε.
#[test]
fn a_band_that_closes_to_the_modelling_tolerance_is_unwrapped_across_its_seam() {
    measured_within_with("models/generated/gen-12-57.step", 0.3, 5, 563);
}

/// gen-18-45 (seed 18 model 45, as built; kept whole, 31 KB): the top plane of a revolved
/// part fused with a cylinder (#796) has a peninsula about 1.5 mm wide between the notch the
/// cylinder left and its outer circle. At T 0.848 its edges' polylines (within ε/2) crossed;
/// spade left 2 constraints out, the parity fill was off, and the peninsula was dropped:
/// `stats` read 4.56 ε missing while OCCT's judge, sampling the whole model, passed. Crossing
/// polylines now have the face tessellated again with its edges followed to ε/8: 0 crossing,
/// the peninsula drawn.
#[test]
fn a_peninsula_narrower_than_the_tolerance_is_drawn() {
    measured_within_with("models/generated/gen-18-45.step.gz", 0.848, 20, 796);
}

/// gen-16-27 (seed 16 model 27 reduced to its revolved part, chamfered and cut by a box): the
/// chamfer's sliver face #1441 (0.083 mm² on OCCT's side) is bounded by a B-spline circle's
/// edge #1447 from the circle's seam to 0.041 rad past it. Its end was located at 36.197 on a
/// knot range ending at 35.959 (truck's search ran past the last knot, where the curve's last
/// piece passes the seam again): the edge ran a whole turn round, and the face covered the
/// whole band (`stats` 138 ε at T 0.3, 8 791 samples outside the trim; OCCT's judge 12.5 T on
/// the whole model). Located inside its range, it is the short arc: 0.90 ε.
#[test]
fn an_edge_is_located_inside_its_curves_range() {
    measured_within_with("models/generated/gen-16-27.step.gz", 0.3, 9, 1441);
}

/// gen-22-26 (seed 22 model 26, as built; kept whole): a ruled loft, drafted, shelled and
/// chamfered. On its band #1415 (closed in u), the measure's boundary split the last piece of
/// the top edge before the seam edge's start and flagged those points as the seam's: even-odd
/// skipped that piece, and a mesh sample just below it, inside the face, was read 1.87 ε
/// outside (`stats` disagreed with OCCT's judge, 0.69 T). Flagged as the top edge's: 0.69 ε.
#[test]
fn a_seam_flag_stays_on_its_own_edge() {
    measured_within_with("models/generated/gen-22-26.step.gz", 0.246, 5, 1415);
}

/// gen-22-50 (seed 22 model 50, kept whole): a torus shelled inward, its inner face #198 a
/// tube of radius 0.335 round a circle of 17.943, over 3.236 rad of it (area 2π · 0.335 ·
/// 17.943 · 3.236 = 122.2). At ε 1.03 the tube is thinner than ε: its grid had no point
/// inside, and the triangles ran from one side of its seam to the other, all on one line,
/// within ε of the tube (`stats` 0.77 ε) but of no area: nothing was drawn, and Open
/// CASCADE's judge found the tube 1.42 T from any drawn surface. A triangle with an inner edge
/// that wraps round the surface (its chord shorter than the surface's distance from the chord's
/// middle) is refined: the tube is drawn.
#[test]
fn a_tube_thinner_than_the_tolerance_is_drawn_not_collapsed() {
    let (scene, _) = healed_model("models/generated/gen-22-50.step.gz");
    let meshes = tessellate_scene_tolerance(&scene, 1.03);
    let (_, mesh) = (scene.patches.iter().zip(&meshes))
        .find(|(p, _)| matches!(&p.surface, PatchSurface::Trimmed(f) if f.id == 198))
        .expect("face #198 is a patch");
    let area: f64 = (mesh.triangles.iter())
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let exact = std::f64::consts::TAU * 0.335 * 17.943 * (3.348_623_6 - 0.112_393_2);
    assert!(
        area >= 0.6 * exact,
        "face #198's mesh covers {area:.1} of its {exact:.1}"
    );
    measured_within_with("models/generated/gen-22-50.step.gz", 1.03, 5, 198);
}

/// gen-26-0-offset (seed 26 model 0 reduced to its part 1: a cone in common with a cylinder,
/// offset by 2.122; `tests/data/step/gen-26-0-offset.json`). Face #20329, the offset's
/// rolling band, has a vertex 2 mm off both its edges' curves: one edge is read ending at the
/// vertex, the next starting at its curve's end. The mesh passes through the vertex; the
/// measure's boundary took each edge's end to be the next edge's start and left the vertex
/// out, so its offset from the surface was allowed nowhere: `stats` read 1.96 ε at T 1.01
/// where Open CASCADE's judge, on the whole model, reads 0.86 T. With the vertex on the
/// boundary: 0.90 ε.
#[test]
fn a_vertex_off_its_edges_curves_bounds_the_measure() {
    let faces = measured_within("tests/data/step/gen-26-0-offset.step.gz", 1.01, 38, 1.0);
    let band = faces
        .iter()
        .find(|(_, f)| f.face == 20329)
        .expect("face #20329");
    assert!(
        band.1.edge_offset > 1.5,
        "the band's corner lies {} off its surface",
        band.1.edge_offset
    );
}

/// gen-33-39-thread (seed 33 model 39 reduced to its part 0, a thread of radius 5.65 and pitch
/// 2.44, in metres; `tests/data/step/gen-33-39-thread.json`), at T 12.9 mm (2 % of the whole
/// model's diagonal, above the thread's radius). The cylinder face at the thread's root end
/// (#6572) is bounded by a circle and one turn of helix; each half turn of the helix was within
/// the tolerance of its diameter, so its polyline was two chords, and the loop's parameters,
/// unwrapped across its seam point to point, made the half turns cancel: the loop was taken
/// to wind round the cylinder once and closed at its nominal ends, 1 m away (`stats` 77 ε,
/// OCCT's judge on the whole model a 74.9 T). No polyline piece turns half a turn now.
#[test]
fn a_helix_coarser_than_its_radius_keeps_its_turn_in_the_trim_loop() {
    measured_within_with("tests/data/step/gen-33-39-thread.step.gz", 12.9, 19, 6572);
}

/// gen-35-41-thread (seed 35 model 41 reduced to its part 0, a thread of radius 8.865 and
/// pitch 2.228 over 8.36 turns; `tests/data/step/gen-35-41-thread.json`), at T 6.38 mm (2 % of
/// the whole model's diagonal). The edges along the flank are B-splines of degree 11 in 8
/// spans; cut in two halves of 4.18 turns, each half's samples, 1.05 turns apart, lay
/// within 3.19 of its chord with their tangents along it, so the polyline crossed the thread
/// in two chords and flank face #4624 was drawn off its trim (`stats` 1.39 ε, OCCT's judge on
/// the whole model a 1.19 T). The deviation is now measured span by span.
#[test]
fn a_long_helix_edge_is_measured_span_by_span() {
    measured_within_with("tests/data/step/gen-35-41-thread.step.gz", 6.38, 16, 4624);
}

/// gen-36-31-crescent (seed 36 model 31 reduced to its part 1, a wedge fused with a cylinder
/// of radius 12.318; `tests/data/step/gen-36-31-crescent.json`), at T 11.1 mm (5 % of the
/// whole model's diagonal). Plane face #678 is a crescent: a circular arc and two straight
/// edges that meet 0.43 mm (0.038 T) inside it. At the arc's chords of T/2 and T/8 the
/// polylines crossed there; the retries stopped at T/8, which crossed as often as T/2, so T/32
/// (clear) was never tried and spade's one triangle left 1.38 T of the face uncovered
/// (`stats`; OCCT's judge on the whole model passed it, a 0.48 T).
#[test]
fn a_crescent_whose_trim_polylines_cross_is_retried_until_they_do_not() {
    measured_within_with("tests/data/step/gen-36-31-crescent.step.gz", 11.1, 10, 678);
}

/// gen-4-33-sphere (seed 4 model 33 reduced to its part 2, a shelled spring's common with a
/// sphere; `tests/data/step/gen-4-33-sphere.json`), at T 8.98 mm (2 % of the whole model's
/// diagonal). The sphere face #982 runs round the sphere near its pole; one polyline piece of
/// an edge passing 0.06 rad from the pole swept u by −3.4 and was unwrapped as +2.9, the loop
/// wound round the sphere and was closed along the other pole: the face was drawn as its
/// complement (`stats` 3.61 ε, 581 samples outside; OCCT's judge a 3.41 T). Such a piece is
/// now split on its curve until its parameters unwrap the same way from its midpoint.
#[test]
fn a_piece_that_sweeps_half_a_turn_near_a_pole_is_split_until_it_unwraps() {
    measured_within_with("tests/data/step/gen-4-33-sphere.step.gz", 8.98, 3, 982);
}

/// gen-43-42-spheres (seed 43 model 42 reduced to its part: a sphere of 293.6° fused with a
/// whole sphere and a box; `tests/data/step/gen-43-42-spheres.json`), at T 1.51 mm (3e-3 of
/// the whole model's diagonal). The whole sphere's face #485 is bounded by a `VERTEX_LOOP` at
/// its pole and two holes; one hole's edges pass 0.045 rad from each pole, where 16 points per
/// edge step over a radian of angle about the axis. The seam, placed in the widest gap between
/// the loops' points, ran through that hole, and the face was drawn across it (`stats`
/// 11.97 ε, 1 111 samples outside; OCCT's judge a 11.11 T). The gap is now the widest arc no
/// step between two points sweeps.
#[test]
fn a_sphere_seam_is_placed_clear_of_the_angles_a_hole_sweeps_beside_a_pole() {
    measured_within_with("tests/data/step/gen-43-42-spheres.step.gz", 1.51, 10, 485);
}

/// SOT23 (corpus), face #1915: a circle revolved about an axis it touches, a corner bounded by
/// three edges, one through the pole. The measure's loop comes back from the pole on the other
/// sheet; the rest of its last edge, split between the loop's end and its first point as
/// projected on the first sheet, ran across both, and `stats` read 2.55 ε missing at T 0.002
/// (5e-4 of the diagonal) where Open CASCADE's judge found 0.80 T. The first point is now
/// projected again from the loop's end.
#[test]
fn a_loop_back_from_a_pole_is_closed_on_the_sheet_it_came_back_on() {
    measured_within_with("models/corpus/SOT23.stp.gz", 0.002, 73, 1915);
}

/// gen-45-9-cone-band (seed 45 model 9, whole: a wide cone shelled inwards; see
/// `tests/data/step/README.md`): its inner cone #162 is bounded by its small circle (r 6.227
/// mm), an isoline of the cone, so the circle's points lie on one line in parameters. The
/// triangulation made slivers of three of them (their area 6e-16 of a grid step squared),
/// and with a crossing in the face's loops (inside told by each triangle's centroid) rounding
/// put them inside: in 3D each is a whole triangle across the chord of two border steps, over
/// the hole (at 1e-3 and 3e-3 of the face's radius the tessellator's own error read 4.3 and 1.97
/// ε after its 10 rounds, `stats` 1.97 ε with 24 samples outside). A sliver now lies on the
/// side of the border where its 3D centroid is nearer the surface.
#[test]
fn slivers_along_a_cone_circle_are_not_drawn_over_the_hole() {
    let path = "tests/data/step/gen-45-9-cone-band.step.gz";
    for tol in [0.033, 0.099, 0.2773] {
        let (scene, _) = healed_model(path);
        let meshes = tessellate_scene_tolerance(&scene, tol);
        let s = patchwork::tessellate::MeshStats::of(&meshes);
        assert_eq!(
            s.stopped, 0,
            "tol {tol}: a budget stop: {:?}",
            s.worst_stopped
        );
        measured_within_with(path, tol, 4, 162);
    }
}

/// gen-49-41's variable fillet (seed 49 model 41, face #2369 there, #17 alone): a rational
/// B-spline whose v knots run 92.57..93.16. The reader probed every surface for finite points at
/// (0, 0), (½, ½) and (1, 1); outside its knots this one's weights are all zero, so it read NaN
/// and the face was skipped ("the surface has non-finite parameters"; the file alone drew
/// nothing). The probe now stays inside the surface's own parameter range.
#[test]
fn a_rational_b_spline_with_knots_far_from_zero_is_drawn() {
    let path = "tests/data/step/gen-49-41-fillet.step.gz";
    for tol in [0.0146, 0.0974] {
        measured_within_with(path, tol, 1, 17);
    }
}

/// gen-46-47-pipe (seed 46 model 47 reduced to its part 2, a spring fused with a cone and
/// offset by 1.016; see `tests/data/step/README.md`): OCCT's offset left face #441, an
/// `OFFSET_SURFACE` of the pipe's rational B-spline (v 0..34), whose loop is the pipe's end
/// circle and a seam run out to v 1.24 and back. The face is that band of the tube (radius
/// 2.156 about the pipe's axis); the loop was closed at the end of v's range and the whole
/// pipe drawn, 28.9 mm past it (OCCT's judge a 178 T at 3e-3 of the diagonal). Closed at the
/// seam's far end, every vertex lies within the tube's diameter (+ T) of the seam, and the
/// measure, which closes such a loop there too, finds every face within T. (Open CASCADE
/// itself draws nothing for this face: its mesher leaves it without triangles, and its box of
/// the part holds the end circle alone, so its box is no criterion here.)
#[test]
fn a_band_bounded_by_a_circle_and_a_seam_run_out_and_back_ends_at_the_seam() {
    let path = "tests/data/step/gen-46-47-pipe.step.gz";
    let tol = 0.138;
    let (scene, _) = healed_model(path);
    let meshes = tessellate_scene_tolerance(&scene, tol);
    // The seam edge #446 from v 0 to v 1.24 (its points as the file's curve gives them).
    let seam = [
        [10.539, -0.177, 2.140],
        [10.524, 0.595, 2.277],
        [10.452, 1.365, 2.414],
        [10.324, 2.127, 2.551],
        [10.140, 2.877, 2.687],
        [9.902, 3.612, 2.824],
        [9.611, 4.328, 2.961],
        [9.268, 5.020, 3.097],
        [8.876, 5.686, 3.234],
    ]
    .map(glam::DVec3::from);
    let reach = 2.0 * 2.156 + tol;
    let mut farthest: f64 = 0.0;
    for m in &meshes {
        for p in &m.positions {
            let p = p.as_dvec3();
            let d = seam
                .windows(2)
                .map(|w| {
                    let (a, ab) = (w[0], w[1] - w[0]);
                    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                    p.distance(a + t * ab)
                })
                .fold(f64::INFINITY, f64::min);
            farthest = farthest.max(d);
            assert!(
                d <= reach,
                "patch {}: vertex {p} lies {d} from the seam (the band reaches {reach})",
                m.patch_id
            );
        }
    }
    assert!(farthest > 0.5 * reach, "the band is drawn ({farthest})");
    measured_within_with(path, tol, 3, 441);
}

/// gen-2-39 (seed 2 model 39, a loft of star sections shelled inwards): its offset face #1307
/// is bounded by a bottom curve, a seam run up to the top and a degenerate edge there. The
/// seam's far end was first taken as the seam point farthest from the loop's first point;
/// this loop starts at the top, so the bottom was taken, the loop closed across there and the
/// face drawn as a sliver (`stats` at T 0.249: 12.5 ε, 38 samples outside). A dead end is a
/// seam end beyond every other edge (`model::seam`): this seam has none, and the face is
/// closed as before.
#[test]
fn a_seam_with_an_edge_at_each_end_is_no_dead_end() {
    let path = "models/generated/gen-2-39.step";
    let (scene, _) = healed_model(path);
    let meshes = tessellate_scene_tolerance(&scene, 0.249);
    let faces = patchwork::check::fidelity::measure_meshes(&scene, &meshes);
    let (_, f) = faces
        .iter()
        .find(|(_, f)| f.face == 1307)
        .expect("face #1307 is measured");
    assert!(
        f.ratio() < 1.2 && f.outside == 0,
        "face #1307: error/tol {} ({} samples outside)",
        f.ratio(),
        f.outside
    );
}
