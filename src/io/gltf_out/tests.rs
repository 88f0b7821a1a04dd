//! Tests of [`super`] (gltf_out).

use super::*;

use glam::{Mat4, Quat, Vec3};

use super::build::bounds;

/// Distinguishes the test directories of one process.
static DIRS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A fresh, empty directory for one test.
fn test_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "patchwork-gltf-{}-{tag}-{}",
        std::process::id(),
        DIRS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test dir");
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

const RED: [f32; 4] = [0.8, 0.1, 0.05, 1.0];

fn quad() -> ExportMesh {
    ExportMesh {
        name: "quad".into(),
        positions: vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.5, 0.0],
            [0.0, 1.5, -0.25],
        ],
        normals: vec![[0.0, 0.0, 1.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        color: Some(RED),
        runs: Vec::new(),
    }
}

fn triangle() -> ExportMesh {
    ExportMesh {
        name: "triangle".into(),
        positions: vec![[-1.0, 0.1, 3.0], [1.0, -0.7, 3.0], [0.0, 1.0, 3.5]],
        // Not unit, zero, and NaN: normalised, and the last two replaced by +z.
        normals: vec![[3.0, 0.0, 4.0], [0.0, 0.0, 0.0], [f32::NAN, 1.0, 0.0]],
        indices: vec![0, 1, 2],
        color: None,
        runs: Vec::new(),
    }
}

fn node(name: &str, mesh: usize, matrix: Mat4) -> ExportNode {
    ExportNode {
        name: name.into(),
        mesh,
        matrix: matrix.to_cols_array(),
        parent: None,
    }
}

fn assembly() -> ExportScene {
    ExportScene {
        meshes: vec![quad(), triangle()],
        nodes: vec![
            node("base", 0, Mat4::IDENTITY),
            node(
                "lid",
                0,
                Mat4::from_rotation_translation(
                    Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
                    glam::vec3(10.0, 0.0, 0.5),
                ),
            ),
            node(
                "flag",
                1,
                Mat4::from_rotation_translation(
                    Quat::from_rotation_x(0.3),
                    glam::vec3(-1.0, 2.0, 3.0),
                ),
            ),
        ],
        groups: Vec::new(),
        generator: "patchwork test".into(),
    }
}

fn as_f32s(v: Option<json::Value>) -> Vec<f32> {
    v.expect("min/max present")
        .as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number") as f32)
        .collect()
}

#[test]
fn assembly_round_trips_through_gltf_import() {
    let dir = test_dir("roundtrip");
    let path = dir.join("assembly.glb");
    let scene = assembly();
    let stats = write_glb(&path, &scene).expect("write");
    assert_eq!(
        stats,
        GltfStats {
            meshes: 2,
            nodes: 3,
            triangles: 3,
            bytes: std::fs::metadata(&path).expect("metadata").len() as usize,
        }
    );
    assert_eq!(entries(&dir), ["assembly.glb"], "no temporary file is left");

    // `import` validates the document and loads the BIN chunk.
    let (doc, buffers, _) = gltf::import(&path).expect("import");
    let json = doc.as_json();
    assert_eq!(json.asset.version, "2.0");
    assert_eq!(json.asset.generator.as_deref(), Some("patchwork test"));
    assert_eq!(doc.meshes().len(), 2);
    assert_eq!(doc.nodes().len(), 3);
    assert_eq!(doc.buffers().len(), 1);
    let default_scene = doc.default_scene().expect("default scene");
    let in_scene: Vec<usize> = default_scene.nodes().map(|n| n.index()).collect();
    assert_eq!(in_scene, [0, 1, 2]);

    for (mesh, input) in doc.meshes().zip(&scene.meshes) {
        assert_eq!(mesh.name(), Some(input.name.as_str()));
        assert_eq!(mesh.primitives().len(), 1);
        let prim = mesh.primitives().next().expect("primitive");
        assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
        assert_eq!(positions, input.positions);
        let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
        assert_eq!(indices, input.indices);
        let normals: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
        for (n, expected) in normals.iter().zip(input.normals.iter().map(|&n| {
            let v = Vec3::from(n);
            if v.is_finite() && v.length() > 0.0 {
                v.normalize()
            } else {
                Vec3::Z
            }
        })) {
            assert!(Vec3::from(*n).abs_diff_eq(expected, 1e-6), "{n:?}");
            assert!((Vec3::from(*n).length() - 1.0).abs() < 1e-6);
        }

        let pos = prim
            .get(&gltf::Semantic::Positions)
            .expect("POSITION accessor");
        let (lo, hi) = bounds(&input.positions);
        assert_eq!(as_f32s(pos.min()), lo);
        assert_eq!(as_f32s(pos.max()), hi);

        let material = prim.material();
        assert!(material.index().is_some());
        assert!(material.double_sided());
        let pbr = material.pbr_metallic_roughness();
        assert_eq!(
            pbr.base_color_factor(),
            input.color.unwrap_or(DEFAULT_COLOR)
        );
        assert_eq!(pbr.metallic_factor(), 0.0);
        assert_eq!(pbr.roughness_factor(), ROUGHNESS);
        assert_eq!(material.alpha_mode(), gltf::material::AlphaMode::Opaque);
    }
    assert_eq!(
        bounds(&quad().positions),
        ([0.0, 0.0, -0.25], [2.0, 1.5, 0.0])
    );
    assert_eq!(doc.materials().len(), 2);

    for (n, input) in doc.nodes().zip(&scene.nodes) {
        assert_eq!(n.name(), Some(input.name.as_str()));
        assert_eq!(n.mesh().map(|m| m.index()), Some(input.mesh));
        assert_eq!(n.transform().matrix().concat(), input.matrix);
    }
    assert_eq!(json.nodes[0].matrix, None, "identity is omitted");
    assert_eq!(json.nodes[1].matrix, Some(scene.nodes[1].matrix));
    assert_eq!(json.nodes[2].matrix, Some(scene.nodes[2].matrix));

    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn glb_layout_follows_the_container_rules() {
    let bytes = to_glb_bytes(&assembly()).expect("encode");
    let word =
        |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize;
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(word(4), 2);
    assert_eq!(word(8), bytes.len());

    let json_len = word(12);
    assert_eq!(&bytes[16..20], b"JSON");
    assert_eq!(json_len % 4, 0);
    let json_chunk = &bytes[20..20 + json_len];
    let end = json_chunk
        .iter()
        .rposition(|&b| b == b'}')
        .expect("JSON ends with }");
    assert!(json_chunk[end + 1..].iter().all(|&b| b == b' '));

    let bin_at = 20 + json_len;
    let bin_len = word(bin_at);
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(bin_len % 4, 0);
    assert_eq!(bin_at + 8 + bin_len, bytes.len());

    let gltf = gltf::Gltf::from_slice(&bytes).expect("valid glb");
    let buffer = gltf.buffers().next().expect("buffer");
    assert_eq!(buffer.length(), bin_len);
    assert!(matches!(buffer.source(), gltf::buffer::Source::Bin));
    for mesh in gltf.meshes() {
        for prim in mesh.primitives() {
            for (_, accessor) in prim.attributes() {
                let view = accessor.view().expect("view");
                assert_eq!(view.target(), Some(gltf::buffer::Target::ArrayBuffer));
                assert_eq!(view.offset() % 4, 0);
            }
            let view = prim.indices().expect("indices").view().expect("view");
            assert_eq!(
                view.target(),
                Some(gltf::buffer::Target::ElementArrayBuffer)
            );
            assert_eq!(view.offset() % 4, 0);
        }
    }
}

#[test]
fn file_bytes_equal_in_memory_bytes() {
    let dir = test_dir("same");
    let path = dir.join("a.glb");
    write_glb(&path, &assembly()).expect("write");
    assert_eq!(
        std::fs::read(&path).expect("read"),
        to_glb_bytes(&assembly()).expect("encode")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn meshes_without_triangles_are_skipped_with_their_nodes() {
    let mut scene = assembly();
    let empty = ExportMesh {
        name: "empty".into(),
        positions: vec![[f32::MAX, 0.0, 0.0]],
        ..Default::default()
    };
    scene.meshes.insert(0, empty);
    for n in &mut scene.nodes {
        n.mesh += 1;
    }
    scene.nodes.insert(1, node("ghost", 0, Mat4::IDENTITY));
    // Placed by no node: left out as well.
    scene.meshes.push(triangle());

    let bytes = to_glb_bytes(&scene).expect("encode");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("valid");
    assert_eq!(gltf.meshes().len(), 2);
    let names: Vec<_> = gltf.nodes().map(|n| n.name().map(str::to_owned)).collect();
    assert_eq!(
        names,
        [
            Some("base".to_owned()),
            Some("lid".to_owned()),
            Some("flag".to_owned())
        ]
    );
    let meshes: Vec<_> = gltf
        .nodes()
        .map(|n| n.mesh().and_then(|m| m.name().map(str::to_owned)))
        .collect();
    assert_eq!(
        meshes,
        [
            Some("quad".to_owned()),
            Some("quad".to_owned()),
            Some("triangle".to_owned())
        ]
    );

    let dir = test_dir("skip");
    let stats = write_glb(&dir.join("s.glb"), &scene).expect("write");
    assert_eq!((stats.meshes, stats.nodes, stats.triangles), (2, 3, 3));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn equal_colours_share_a_material_and_alpha_blends() {
    let mut scene = assembly();
    scene.meshes[1].color = Some(RED);
    let gltf = gltf::Gltf::from_slice(&to_glb_bytes(&scene).expect("encode")).expect("valid");
    assert_eq!(gltf.materials().len(), 1);

    scene.meshes[1].color = Some([0.2, 0.4, 0.6, 0.5]);
    let gltf = gltf::Gltf::from_slice(&to_glb_bytes(&scene).expect("encode")).expect("valid");
    assert_eq!(gltf.materials().len(), 2);
    let glass = gltf.materials().nth(1).expect("material");
    assert_eq!(glass.alpha_mode(), gltf::material::AlphaMode::Blend);
    assert_eq!(
        glass.pbr_metallic_roughness().base_color_factor(),
        [0.2, 0.4, 0.6, 0.5]
    );
}

#[test]
fn colour_runs_are_primitives_sharing_the_vertices() {
    let mut scene = assembly();
    let blue = [0.1, 0.2, 0.9, 1.0];
    // The quad's second triangle blue; the first keeps the mesh's red.
    scene.meshes[0].runs = vec![(3, Some(blue))];
    let bytes = to_glb_bytes(&scene).expect("encode");
    let (doc, buffers, _) = gltf::import_slice(&bytes).expect("imports");
    let mesh = doc.meshes().next().expect("mesh");
    let prims: Vec<_> = mesh.primitives().collect();
    assert_eq!(prims.len(), 2);
    let mut seen = Vec::new();
    for p in &prims {
        let reader = p.reader(|b| Some(&buffers[b.index()]));
        let indices: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
        let color = p.material().pbr_metallic_roughness().base_color_factor();
        let position = p
            .get(&gltf::Semantic::Positions)
            .expect("positions")
            .index();
        seen.push((indices, color, position));
    }
    assert_eq!(seen[0].0, [0, 1, 2]);
    assert_eq!(seen[0].1, RED);
    assert_eq!(seen[1].0, [0, 2, 3]);
    assert_eq!(seen[1].1, blue);
    assert_eq!(seen[0].2, seen[1].2, "one POSITION accessor for both");
    // Red, blue, and the default white of the assembly's other mesh.
    assert_eq!(doc.materials().len(), 3);

    // A run from index 0 leaves no primitive of the mesh's own colour.
    scene.meshes[0].runs = vec![(0, Some(blue))];
    let gltf = gltf::Gltf::from_slice(&to_glb_bytes(&scene).expect("encode")).expect("valid");
    assert_eq!(gltf.meshes().next().expect("mesh").primitives().count(), 1);
}

#[test]
fn meshes_without_normals_have_no_normal_attribute() {
    let mut scene = assembly();
    scene.meshes[1].normals.clear();
    let gltf = gltf::Gltf::from_slice(&to_glb_bytes(&scene).expect("encode")).expect("valid");
    let prim = gltf.meshes().nth(1).expect("mesh").primitives().next();
    let prim = prim.expect("primitive");
    assert!(prim.get(&gltf::Semantic::Normals).is_none());
    assert!(prim.get(&gltf::Semantic::Positions).is_some());
}

/// Writes `scene` into a fresh directory, expects an error, and checks that the directory
/// is still empty (no output, no temporary file).
fn write_fails(tag: &str, scene: &ExportScene) -> GltfWriteError {
    let dir = test_dir(tag);
    let path = dir.join("out.glb");
    let err = write_glb(&path, scene).expect_err("invalid scene");
    assert_eq!(err.path(), path);
    assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
    let _ = std::fs::remove_dir_all(&dir);
    assert!(to_glb_bytes(scene).is_err());
    err
}

#[test]
fn node_with_missing_mesh_is_an_error() {
    let mut scene = assembly();
    scene.nodes[2].mesh = 7;
    let err = write_fails("missing", &scene);
    assert!(
        matches!(
            err,
            GltfWriteError::MissingMesh {
                node: 2,
                mesh: 7,
                meshes: 2,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string()
            .contains("node 2 (\"flag\") refers to mesh 7")
    );
}

#[test]
fn index_out_of_range_is_an_error() {
    let mut scene = assembly();
    scene.meshes[0].indices[4] = 4;
    let err = write_fails("index", &scene);
    assert!(
        matches!(
            err,
            GltfWriteError::IndexOutOfRange {
                mesh: 0,
                at: 4,
                index: 4,
                vertices: 4,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn nan_position_is_an_error() {
    let mut scene = assembly();
    scene.meshes[1].positions[2][1] = f32::NAN;
    let err = write_fails("nan", &scene);
    assert!(
        matches!(
            err,
            GltfWriteError::NonFinitePosition {
                mesh: 1,
                vertex: 2,
                ..
            }
        ),
        "{err}"
    );
    scene.meshes[1].positions[2][1] = f32::INFINITY;
    assert!(matches!(
        write_fails("inf", &scene),
        GltfWriteError::NonFinitePosition { .. }
    ));
}

#[test]
fn empty_scene_is_an_error() {
    let err = write_fails("empty", &ExportScene::default());
    assert!(matches!(err, GltfWriteError::Empty { .. }), "{err}");

    let mut only_empty_meshes = assembly();
    for m in &mut only_empty_meshes.meshes {
        m.indices.clear();
    }
    let err = write_fails("no-triangles", &only_empty_meshes);
    assert!(matches!(err, GltfWriteError::Empty { .. }), "{err}");

    let mut no_nodes = assembly();
    no_nodes.nodes.clear();
    let err = write_fails("no-nodes", &no_nodes);
    assert!(matches!(err, GltfWriteError::Empty { .. }), "{err}");
}

#[test]
fn other_invalid_input_is_an_error() {
    let mut scene = assembly();
    scene.meshes[0].indices.pop();
    assert!(matches!(
        write_fails("partial", &scene),
        GltfWriteError::PartialTriangle { len: 5, .. }
    ));

    let mut scene = assembly();
    scene.meshes[0].normals.pop();
    assert!(matches!(
        write_fails("normals", &scene),
        GltfWriteError::NormalCount {
            normals: 3,
            positions: 4,
            ..
        }
    ));

    let mut scene = assembly();
    scene.meshes[0].color = Some([1.5, 0.0, 0.0, 1.0]);
    assert!(matches!(
        write_fails("color", &scene),
        GltfWriteError::InvalidColor { .. }
    ));

    for (tag, runs) in [
        ("run-inside", vec![(1, None)]),
        ("run-end", vec![(6, None)]),
        ("run-order", vec![(3, None), (3, None)]),
    ] {
        let mut scene = assembly();
        scene.meshes[0].runs = runs;
        assert!(matches!(
            write_fails(tag, &scene),
            GltfWriteError::BadRun { mesh: 0, .. }
        ));
    }
    let mut scene = assembly();
    scene.meshes[0].runs = vec![(3, Some([0.0, f32::NAN, 0.0, 1.0]))];
    assert!(matches!(
        write_fails("run-color", &scene),
        GltfWriteError::InvalidColor { .. }
    ));

    let mut scene = assembly();
    scene.nodes[1].matrix[13] = f32::NAN;
    assert!(matches!(
        write_fails("matrix-nan", &scene),
        GltfWriteError::InvalidMatrix { node: 1, .. }
    ));

    let mut scene = assembly();
    scene.nodes[1].matrix[3] = 0.5;
    assert!(matches!(
        write_fails("projective", &scene),
        GltfWriteError::InvalidMatrix { node: 1, .. }
    ));
}

#[test]
fn in_memory_errors_name_no_file() {
    let err = to_glb_bytes(&ExportScene::default()).expect_err("empty");
    assert_eq!(err.path(), Path::new(IN_MEMORY));
    assert!(err.to_string().starts_with(IN_MEMORY));
}

#[test]
fn missing_directory_is_an_io_error_and_leaves_nothing() {
    let dir = test_dir("nodir");
    let path = dir.join("missing-subdir").join("x.glb");
    let err = write_glb(&path, &assembly()).expect_err("cannot write");
    assert!(matches!(err, GltfWriteError::Io { .. }), "{err}");
    assert_eq!(err.path(), path);
    assert!(!path.exists());
    assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn failed_rename_removes_the_temporary_file() {
    // The target is a directory: the temporary file is written, the rename fails.
    let dir = test_dir("rename");
    let path = dir.join("taken.glb");
    std::fs::create_dir(&path).expect("mkdir");
    let err = write_glb(&path, &assembly()).expect_err("cannot replace a directory");
    assert!(matches!(err, GltfWriteError::Io { .. }), "{err}");
    assert_eq!(entries(&dir), ["taken.glb"]);
    assert!(path.is_dir());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn failed_write_keeps_an_existing_file() {
    let dir = test_dir("keep");
    let path = dir.join("old.glb");
    std::fs::write(&path, b"old").expect("write old");
    let mut scene = assembly();
    scene.nodes[0].mesh = 9;
    assert!(write_glb(&path, &scene).is_err());
    assert_eq!(std::fs::read(&path).expect("read"), b"old");
    assert_eq!(entries(&dir), ["old.glb"]);

    // A valid export replaces it.
    write_glb(&path, &assembly()).expect("write");
    assert!(gltf::Gltf::open(&path).is_ok());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn path_without_a_file_name_is_an_io_error() {
    let err = write_glb(Path::new("/"), &assembly()).expect_err("no file name");
    assert!(matches!(err, GltfWriteError::Io { .. }), "{err}");
}

/// A tree: the root group scales and turns, a sub-assembly group holds two nodes; the import
/// sees the hierarchy and the composed world transforms.
#[test]
fn groups_become_the_node_hierarchy() {
    let mut scene = assembly();
    let turn =
        Mat4::from_scale(Vec3::splat(0.001)) * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    scene.groups = vec![
        ExportGroup {
            name: "root".into(),
            matrix: turn.to_cols_array(),
            parent: None,
        },
        ExportGroup {
            name: "sub".into(),
            matrix: IDENTITY_MATRIX,
            parent: Some(0),
        },
    ];
    scene.nodes[0].parent = Some(0);
    scene.nodes[1].parent = Some(1);
    scene.nodes[2].parent = Some(1);
    let bytes = to_glb_bytes(&scene).expect("encodes");
    let doc = gltf::Gltf::from_slice(&bytes).expect("parses");
    let roots: Vec<_> = doc.default_scene().expect("scene").nodes().collect();
    assert_eq!(roots.len(), 1, "one root");
    assert_eq!(roots[0].name(), Some("root"));
    let kids: Vec<Option<&str>> = roots[0].children().map(|n| n.name()).collect();
    assert_eq!(kids, vec![Some("sub"), Some("base")]);
    let sub = roots[0].children().next().expect("sub");
    let grandkids: Vec<Option<&str>> = sub.children().map(|n| n.name()).collect();
    assert_eq!(grandkids, vec![Some("lid"), Some("flag")]);
    // The lid's world transform: root · sub · lid.
    let lid = sub.children().next().expect("lid");
    let world = Mat4::from_cols_array_2d(&roots[0].transform().matrix())
        * Mat4::from_cols_array_2d(&sub.transform().matrix())
        * Mat4::from_cols_array_2d(&lid.transform().matrix());
    let expected = turn * Mat4::from_cols_array(&scene.nodes[1].matrix);
    assert!(world.abs_diff_eq(expected, 1e-6), "{world} vs {expected}");
}

/// Parents must exist and come first (no cycles).
#[test]
fn bad_parents_are_errors() {
    let mut scene = assembly();
    scene.nodes[0].parent = Some(0);
    let e = to_glb_bytes(&scene).expect_err("no group 0");
    assert!(matches!(e, GltfWriteError::BadParent { .. }), "{e}");
    scene.nodes[0].parent = None;
    scene.groups = vec![ExportGroup {
        name: "loop".into(),
        matrix: IDENTITY_MATRIX,
        parent: Some(0),
    }];
    let e = to_glb_bytes(&scene).expect_err("own parent");
    assert!(e.to_string().contains("does not come before it"), "{e}");
}

/// `.gltf` + `.bin`: the import (which reads the external buffer) sees what the GLB holds.
#[test]
fn text_gltf_with_a_bin_file_imports() {
    let dir = test_dir("text-gltf");
    let path = dir.join("my part.gltf");
    let stats = write_gltf(&path, &assembly()).expect("writes");
    assert!(dir.join("my part.bin").is_file());
    let text = std::fs::read_to_string(&path).expect("json");
    assert!(text.contains("\"uri\": \"my%20part.bin\""), "{text}");
    let (doc, buffers, _) = gltf::import(&path).expect("imports");
    assert_eq!(doc.meshes().count(), stats.meshes);
    assert_eq!(doc.nodes().count(), stats.nodes);
    let glb = gltf::Gltf::from_slice(&to_glb_bytes(&assembly()).expect("glb")).expect("glb");
    assert_eq!(
        buffers[0].len() as u64,
        glb.buffers().next().expect("buffer").length() as u64
    );
    assert_eq!(entries(&dir), vec!["my part.bin", "my part.gltf"]);
}
