//! Loading meshes with the hierarchy cache (`io::mt_cache` through `prep::load_with_options`):
//! a second load reads what the first built, a changed model file misses, a corrupt cache file
//! is refused with a warning and rebuilt, and a scene loaded at full resolution gets the same
//! hierarchies later (`PendingHierarchies::build`).

mod common;

use std::path::{Path, PathBuf};

use patchwork::model::mesh::MeshPatch;
use patchwork::model::{PatchSurface, Scene};
use patchwork::prep::{Hierarchies, LoadOptions, NoProgress, load_with_options};

/// A bumpy n × n grid as an OBJ file (2 n² triangles).
fn write_grid(path: &Path, n: u32, bump: f32) {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 * 0.1, j as f32 * 0.1);
            s += &format!("v {x} {y} {}\n", bump * (3.0 * x).sin() * (2.0 * y).cos());
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            s += &format!("f {} {} {}\n", at(i, j), at(i + 1, j), at(i + 1, j + 1));
            s += &format!("f {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
    std::fs::write(path, s).expect("writes the model");
}

fn dirs(name: &str) -> (PathBuf, PathBuf) {
    let root = common::scratch("hierarchy_cache").join(name);
    let _ = std::fs::remove_dir_all(&root);
    let cache = root.join("cache");
    std::fs::create_dir_all(&root).expect("scratch dir");
    (root.join("grid.obj"), cache)
}

fn meshes(scene: &Scene) -> Vec<&MeshPatch> {
    scene
        .patches
        .iter()
        .filter_map(|p| match &p.surface {
            PatchSurface::Mesh(m) => Some(&**m),
            _ => None,
        })
        .collect()
}

fn cache_files(cache: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(cache)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default()
}

#[test]
fn a_second_load_reads_the_hierarchies_the_first_built() {
    let (model, cache) = dirs("second");
    write_grid(&model, 60, 0.2); // 7 200 triangles: several patches
    // (With the coarse groups export builds, so they are cached too.)
    let mut build = LoadOptions::new(Hierarchies::Build, Some(cache.clone()));
    build.groups = true;
    let first = load_with_options(&model, &build, &NoProgress).expect("loads");
    assert!(first.warnings.is_empty(), "{:?}", first.warnings);
    assert!(first.pending.is_none());
    let built = meshes(&first.scene);
    assert!(built.len() > 2 && built.iter().all(|m| !m.hierarchy.is_original()));
    assert_eq!(cache_files(&cache).len(), 1);
    // Read back: the same hierarchies, even when asked not to build.
    let mut lazy = LoadOptions::new(Hierarchies::CachedOrOriginal, Some(cache.clone()));
    lazy.groups = true;
    let second = load_with_options(&model, &lazy, &NoProgress).expect("loads");
    assert!(second.pending.is_none(), "the cache was not used");
    assert!(second.warnings.is_empty(), "{:?}", second.warnings);
    assert!(meshes(&second.scene) == built, "cached ≠ built");
    // The coarse groups' hierarchies are cached too (`prep::groups`).
    assert!(!first.scene.mesh_groups.is_empty(), "no groups");
    assert!(
        second.scene.mesh_groups == first.scene.mesh_groups,
        "cached groups ≠ built"
    );
}

#[test]
fn a_changed_model_misses_the_cache() {
    let (model, cache) = dirs("changed");
    write_grid(&model, 40, 0.2);
    let build = LoadOptions::new(Hierarchies::Build, Some(cache.clone()));
    load_with_options(&model, &build, &NoProgress).expect("loads");
    // Same size and topology, other heights.
    write_grid(&model, 40, 0.3);
    let lazy = LoadOptions::new(Hierarchies::CachedOrOriginal, Some(cache.clone()));
    let loaded = load_with_options(&model, &lazy, &NoProgress).expect("loads");
    assert!(loaded.pending.is_some(), "a stale cache was used");
    assert!(
        meshes(&loaded.scene)
            .iter()
            .all(|m| m.hierarchy.is_original())
    );
    // Without a cache, nothing is read or written.
    let none = LoadOptions::new(Hierarchies::CachedOrOriginal, None);
    assert!(
        load_with_options(&model, &none, &NoProgress)
            .expect("loads")
            .pending
            .is_some()
    );
    assert_eq!(cache_files(&cache).len(), 1);
}

#[test]
fn a_corrupt_cache_file_is_refused_with_a_warning_and_rebuilt() {
    let (model, cache) = dirs("corrupt");
    write_grid(&model, 40, 0.2);
    let build = LoadOptions::new(Hierarchies::Build, Some(cache.clone()));
    let good = load_with_options(&model, &build, &NoProgress).expect("loads");
    let file = cache_files(&cache).pop().expect("a cache file");
    let bytes = std::fs::read(&file).expect("reads");
    let mut flipped = bytes.clone();
    let at = bytes.len() - 100;
    flipped[at] ^= 0x10;
    for bad in [bytes[..bytes.len() / 2].to_vec(), flipped, Vec::new()] {
        std::fs::write(&file, &bad).expect("corrupts");
        let loaded = load_with_options(&model, &build, &NoProgress).expect("loads");
        assert!(
            loaded.warnings.iter().any(|w| w.contains("refused")),
            "{:?}",
            loaded.warnings
        );
        assert!(meshes(&loaded.scene) == meshes(&good.scene), "not rebuilt");
        // ... and the rebuilt hierarchies were written back.
        assert!(
            std::fs::read(&file).expect("reads") == bytes,
            "not written back"
        );
    }
}

#[test]
fn full_resolution_first_then_the_same_hierarchies_as_a_build() {
    let (model, cache) = dirs("pending");
    write_grid(&model, 50, 0.2);
    let mut lazy = LoadOptions::new(Hierarchies::CachedOrOriginal, Some(cache.clone()));
    lazy.groups = true;
    let loaded = load_with_options(&model, &lazy, &NoProgress).expect("loads");
    // Every cut of the first scene is the original mesh, error 0.
    let mut cut = Vec::new();
    for m in meshes(&loaded.scene) {
        assert!(m.hierarchy.is_original());
        for eps in [0.0, 1e-3, 1.0, 1e30] {
            assert_eq!(m.hierarchy.cut(eps, &mut cut), 0.0);
            let (mut a, mut b) = (cut.clone(), m.triangles.clone());
            a.sort_unstable();
            b.sort_unstable();
            assert!(a == b, "ε {eps}: the cut is not the original mesh");
        }
    }
    let pending = loaded.pending.expect("hierarchies left to build");
    let built = pending.build(&loaded.scene, &NoProgress);
    assert!(built.warnings.is_empty(), "{:?}", built.warnings);
    // The first scene is untouched; the second equals a scene built while loading.
    assert!(
        meshes(&loaded.scene)
            .iter()
            .all(|m| m.hierarchy.is_original())
    );
    let mut at_load = LoadOptions::new(Hierarchies::Build, None);
    at_load.groups = true;
    let direct = load_with_options(&model, &at_load, &NoProgress)
        .expect("loads")
        .scene;
    assert!(
        meshes(&built.scene) == meshes(&direct),
        "built later ≠ built at load"
    );
    // Groups without their hierarchies are never drawn; built later, they are as at load.
    assert!(!loaded.scene.mesh_groups.is_empty(), "no groups");
    assert!((loaded.scene.mesh_groups.iter()).all(|g| g.links.switch_error == f64::INFINITY));
    assert!(
        built.scene.mesh_groups == direct.mesh_groups,
        "groups built later ≠ built at load"
    );
    assert_eq!(built.scene.patches.len(), loaded.scene.patches.len());
    // And it went to the cache.
    let again = load_with_options(&model, &lazy, &NoProgress).expect("loads");
    assert!(again.pending.is_none());
    assert!(meshes(&again.scene) == meshes(&direct), "cached ≠ built");
}

#[test]
fn an_unwritable_cache_is_a_warning_only() {
    let (model, cache) = dirs("unwritable");
    write_grid(&model, 20, 0.2);
    // A file where the directory should be.
    std::fs::write(&cache, b"not a directory").expect("writes");
    let build = LoadOptions::new(Hierarchies::Build, Some(cache.clone()));
    let loaded = load_with_options(&model, &build, &NoProgress).expect("loads despite it");
    assert!(!loaded.warnings.is_empty());
    assert!(
        meshes(&loaded.scene)
            .iter()
            .all(|m| !m.hierarchy.is_original())
    );
}
