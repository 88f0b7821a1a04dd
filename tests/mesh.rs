//! Mesh import (glTF, OBJ) and the split into patches: every triangle in one patch, node
//! transforms applied, bad files reported with the file and the reason, never a panic.

mod common;

use std::path::PathBuf;

use glam::Vec3;
use patchwork::io::{LoadError, load};
use patchwork::model::PatchSurface;
use patchwork::model::mesh::MeshPatch;

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data/mesh").join(name)
}

fn mesh_patches(scene: &patchwork::model::Scene) -> Vec<&MeshPatch> {
    scene
        .patches
        .iter()
        .map(|p| match &p.surface {
            PatchSurface::Mesh(m) => m.as_ref(),
            other => panic!("not a mesh patch: {other:?}"),
        })
        .collect()
}

#[test]
fn the_bunny_splits_into_patches_of_about_the_target_size() {
    let scene = common::load("bunny.glb");
    let patches = mesh_patches(&scene);
    let total: usize = patches.iter().map(|p| p.triangles.len()).sum();
    assert_eq!(total, 144_046);
    let mut seen = vec![false; total];
    // Regions under a quarter of the target are merged into a neighbour; only a piece of
    // the mesh that touches no other (a loose component) stays small.
    let small: Vec<usize> = patches
        .iter()
        .map(|p| p.triangles.len())
        .filter(|&n| n < 375)
        .collect();
    assert!(small.len() <= 2, "small patches: {small:?}");
    for p in &patches {
        let n = p.triangles.len();
        assert!(n <= 3000, "patch of {n} triangles");
        assert_eq!(p.normals.len(), p.positions.len());
        for &t in &p.source_triangles {
            assert!(!seen[t as usize], "triangle {t} in two patches");
            seen[t as usize] = true;
        }
    }
    assert!(seen.iter().all(|&s| s));
    let with_border = patches.iter().filter(|p| !p.borders.is_empty()).count();
    assert!(
        with_border + small.len() >= patches.len(),
        "patches without a border"
    );
    // Shared borders: every border vertex of a patch is a border vertex of another patch
    // (or lies on a hole of the mesh): count border vertices that no other patch has.
    let key = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let mut owners: std::collections::HashMap<[u32; 3], usize> = Default::default();
    for p in &patches {
        let mut mine = std::collections::HashSet::new();
        for ring in &p.borders {
            for &i in ring {
                mine.insert(key(p.positions[i as usize]));
            }
        }
        for k in mine {
            *owners.entry(k).or_default() += 1;
        }
    }
    let lonely = owners.values().filter(|&&c| c == 1).count();
    assert!(
        lonely * 20 < owners.len(),
        "{lonely} of {} border vertices unshared",
        owners.len()
    );
}

#[test]
fn gltf_node_transforms_are_applied() {
    let scene = load(&data("two_instances.gltf")).expect("loads");
    let patches = mesh_patches(&scene);
    let mut points: Vec<[f32; 3]> = patches
        .iter()
        .flat_map(|p| p.positions.iter().map(|v| v.to_array()))
        .collect();
    points.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    // Instance 1 at the origin; instance 2: its own translation (0,0,1) under a parent that
    // scales by 2 and moves by 10 in x: (10,0,2), (12,0,2), (10,2,2).
    let mut expected = vec![
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [10.0, 0.0, 2.0],
        [10.0, 2.0, 2.0],
        [12.0, 0.0, 2.0],
    ];
    expected.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    assert_eq!(points, expected);
}

#[test]
fn obj_polygons_are_triangulated() {
    let scene = load(&data("quad.obj")).expect("loads");
    let patches = mesh_patches(&scene);
    assert_eq!(patches.iter().map(|p| p.triangles.len()).sum::<usize>(), 2);
    assert_eq!(patches[0].borders.len(), 1);
    assert_eq!(patches[0].borders[0].len(), 4);
}

#[test]
fn bad_mesh_files_are_typed_errors_naming_the_file() {
    let cases: &[(&str, &str)] = &[
        ("index_out_of_range.gltf", "index 5 is out of range"),
        ("nan_position.gltf", "non-finite"),
        ("not_whole_triangles.gltf", "whole triangles"),
        ("no_triangles.gltf", "no triangles"),
        ("garbage.glb", "not a valid glTF"),
        ("bad_index.obj", "out of bounds"),
        ("nan.obj", "non-finite"),
        ("empty.obj", "no faces"),
        ("missing.glb", "cannot read"),
    ];
    for (file, why) in cases {
        let path = data(file);
        let err = match load(&path) {
            Ok(_) => panic!("{file}: loaded"),
            Err(e) => e,
        };
        let msg = err.to_string();
        assert!(msg.contains(file), "{file}: {msg}");
        assert!(msg.contains(why), "{file}: {msg}");
        assert!(
            !matches!(err, LoadError::UnsupportedFormat { .. }),
            "{file}"
        );
    }
}

#[test]
fn mesh_patches_render_with_their_borders() {
    // Full resolution: neighbours share their border vertices exactly, so the picture is
    // crack-free with and without fat borders; the fat-border pass still runs on every
    // patch border.
    let scene = common::load("bunny.glb");
    let mut renderer = common::renderer();
    let opts = patchwork::check::CheckOptions {
        views: 6,
        variants: vec![
            patchwork::render::FatBorders::Off,
            patchwork::render::FatBorders::Six,
        ],
        ..patchwork::check::CheckOptions::default()
    };
    let r = patchwork::check::run_check(&mut renderer, &scene, &opts, |_| {}).expect("renders");
    for v in &r.views {
        assert!(v.stats.border_vertices > 10_000, "{:?}", v.stats);
        for (fb, c) in &v.counts {
            assert_eq!(c.cracks(), 0, "view {} fat borders {fb}: {c:?}", v.index);
            assert!(c.inside > 1000, "the bunny is in view");
        }
    }
}
