//! Meshes of the seeded mesh generator (`tools/mesh_generator.py`) that the meshoptimizer
//! judge (`tools/mesh_vs_meshopt.py --generate N`, in CI) failed, reduced and kept in
//! `models/generated/` with their recipes: each stays here as a regression test of what the
//! judge found (issue 30: inputs nobody chose).

use std::path::Path;

use patchwork::model::PatchSurface;
use patchwork::prep::{Hierarchies, LoadOptions, NoProgress, load_with_options};

/// The triangles every mesh patch of `file` (in `models/generated/`) cuts at `relative` times
/// the bounding-box diagonal, and the original's triangles.
fn cut_triangles(file: &str, relative: f64) -> (usize, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models/generated")
        .join(file);
    cut_triangles_of(&path, relative)
}

/// [`cut_triangles`] of the model at `path`.
fn cut_triangles_of(path: &Path, relative: f64) -> (usize, usize) {
    let options = LoadOptions::new(Hierarchies::Build, None);
    let scene = load_with_options(path, &options, &NoProgress)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .scene;
    let file = path.display();
    let eps = relative * scene.bbox_diagonal();
    let (mut drawn, mut original) = (0, 0);
    let mut cut = Vec::new();
    for p in &scene.patches {
        let PatchSurface::Mesh(m) = &p.surface else {
            panic!("{file}: a mesh scene");
        };
        m.hierarchy.cut(eps, &mut cut);
        drawn += cut.len();
        original += m.triangles.len();
    }
    (drawn, original)
}

/// mgen-1-5 reduced: two planes joined by a step (a cliff through the triangles), an irregular
/// Delaunay triangulation of 750 random points (1 606 triangles). The planes need only their
/// outlines and the cliff: meshoptimizer keeps 772 triangles at an error of 1e-6. A piece of
/// the original surface is given to one fan triangle, so on a plane a piece straddling two fan
/// triangles was bounded by its overhang until split along their side, and with at most 3
/// splits per piece (`mt::build::PIECE_DEPTH`) the planes stopped simplifying at zero error:
/// mgen-1-5 reduced to its step (1 500 points) kept 1 843 of its 3 150 triangles at 1e-9 of
/// its diagonal, and the whole mgen-1-5's cut at 0.5 % was 24× meshoptimizer's error at the
/// same count (2.7× with 8 splits; 0.36× with the border height bounds too).
#[test]
fn flat_regions_simplify_at_zero_error() {
    let (drawn, original) = cut_triangles("mgen-1-5-steps.obj", 1e-9);
    eprintln!("mgen-1-5-steps: {drawn} of {original} triangles at 1e-9 of the diagonal");
    assert_eq!(original, 1_606);
    assert!(
        drawn <= 450,
        "{drawn} of {original} triangles at 1e-9 of the diagonal: the planes do not simplify"
    );
}

/// mgen-1-3 reduced to its fault: a plane in two materials whose faces the OBJ file lists
/// interleaved (`usemtl` switching face by face, as the generator writes faces in grid order).
/// Each run of one material was a group of its own, and patches never cross a group: the
/// generated plane was cut into 5 667 patches for its 21 000 triangles (4–22× meshoptimizer's
/// error at the same triangle counts). One colour is one group, however the file orders it.
#[test]
fn interleaved_materials_are_one_group_each() {
    let dir = std::env::temp_dir().join(format!("patchwork-mtl-runs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (n, mut obj) = (20usize, String::from("mtllib two.mtl\n"));
    for i in 0..=n {
        for j in 0..=n {
            obj += &format!("v {i} {j} 0\n");
        }
    }
    let at = |i: usize, j: usize| i * (n + 1) + j + 1;
    for j in 0..n {
        for i in 0..n {
            // Left half one colour, right half the other; in file order they alternate
            // along every row.
            obj += &format!("usemtl m{}\n", usize::from(i >= n / 2));
            obj += &format!("f {} {} {}\n", at(i, j), at(i + 1, j), at(i + 1, j + 1));
            obj += &format!("f {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
    std::fs::write(
        dir.join("two.mtl"),
        "newmtl m0\nKd 1 0 0\nnewmtl m1\nKd 0 0 1\n",
    )
    .expect("write mtl");
    let path = dir.join("runs.obj");
    std::fs::write(&path, obj).expect("write obj");
    let options = LoadOptions::new(Hierarchies::Build, None);
    let scene = load_with_options(&path, &options, &NoProgress)
        .expect("loads")
        .scene;
    let _ = std::fs::remove_dir_all(&dir);
    let colours: std::collections::BTreeSet<String> = scene
        .patches
        .iter()
        .map(|p| format!("{:?}", p.color))
        .collect();
    assert_eq!(colours.len(), 2, "{colours:?}");
    assert_eq!(
        scene.patches.len(),
        2,
        "{} patches for two 200-triangle halves in two colours",
        scene.patches.len()
    );
}

/// mgen-1-5 reduced to its step at an error above the step's height (0.07, 5 % of the
/// diagonal): the cliff's wall is bounded by creases (> 40°), where the welder splits the
/// vertices by their normals. With creases as borders of the patches' hierarchies, every
/// strip of wall between two creases was an island that never went below its last triangles
/// (44 of 1 606 triangles drawn at 10 % of the diagonal); built across creases, the wall goes
/// once the error allows (4: the plane's outline).
#[test]
fn a_step_between_creases_vanishes_when_the_error_allows() {
    let (drawn, original) = cut_triangles("mgen-1-5-steps.obj", 0.1);
    eprintln!("mgen-1-5-steps: {drawn} of {original} triangles at 10 % of the diagonal");
    assert!(
        drawn <= 12,
        "{drawn} of {original} triangles at 10 % of the diagonal"
    );
}

/// mgen-2-4 reduced to its fault: a flat-shaded OBJ (every face's corners name one `vn`, its
/// face normal, as exporters write "flat shading"), here a wavy 24 × 24 grid. The welder
/// splits every position into one vertex per face around it, so with creases as borders every
/// triangle was an island and nothing simplified but where neighbours were coplanar (1 108 of
/// its 1 152 triangles drawn at 2 % of the diagonal; the generated mgen-2-4 drew 4.8–10.7×
/// meshoptimizer's error at equal triangles, 0.66–0.76× since). Built across creases: 78.
#[test]
fn a_flat_shaded_mesh_simplifies() {
    let dir = std::env::temp_dir().join(format!("patchwork-flat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let n = 24usize;
    let z = |i: usize, j: usize| 0.08 * (i as f64 * 0.5).sin() * (j as f64 * 0.4).cos();
    let p = |i: usize, j: usize| [i as f64 / n as f64, j as f64 / n as f64, z(i, j)];
    let mut obj = String::new();
    for i in 0..=n {
        for j in 0..=n {
            let [x, y, z] = p(i, j);
            obj += &format!("v {x} {y} {z}\n");
        }
    }
    let at = |i: usize, j: usize| i * (n + 1) + j + 1;
    let mut faces = 0;
    for j in 0..n {
        for i in 0..n {
            for t in [
                [(i, j), (i + 1, j), (i + 1, j + 1)],
                [(i, j), (i + 1, j + 1), (i, j + 1)],
            ] {
                let [a, b, c] = t.map(|(i, j)| glam::DVec3::from(p(i, j)));
                let normal = (b - a).cross(c - a).normalize();
                faces += 1;
                obj += &format!("vn {} {} {}\n", normal.x, normal.y, normal.z);
                let [a, b, c] = t.map(|(i, j)| at(i, j));
                obj += &format!("f {a}//{faces} {b}//{faces} {c}//{faces}\n");
            }
        }
    }
    let path = dir.join("flat.obj");
    std::fs::write(&path, obj).expect("write obj");
    let (drawn, original) = cut_triangles_of(&path, 0.02);
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("flat-shaded grid: {drawn} of {original} triangles at 2 % of the diagonal");
    assert_eq!(original, 2 * n * n);
    assert!(
        drawn <= 120,
        "{drawn} of {original} triangles at 2 % of the diagonal"
    );
}

/// What building across creases first cost `models/alien.glb` (a low-poly model of boxes):
/// a box's top is two faces meeting at a slight crease (6°) that ends on the patch's outline
/// at both ends. With creases as borders, the crease's vertices slid along it onto the
/// outline; built across creases they were interior vertices, which could not move onto the
/// border then, and stayed (289 of 292 triangles drawn at 1 % of the diagonal, 1.69×
/// meshoptimizer's error at equal triangles). Once a vertex could move onto the border along
/// a crease: 281 (0.25×); the same since any interior vertex may.
#[test]
fn a_crease_collapses_onto_the_patch_outline() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/alien.glb");
    let (drawn, original) = cut_triangles_of(&path, 0.01);
    eprintln!("alien: {drawn} of {original} triangles at 1 % of the diagonal");
    assert!(
        drawn <= 284,
        "{drawn} of {original} triangles at 1 % of the diagonal"
    );
}

/// mgen-2-3 reduced (`--reduce-to`): a 30 × 30 grid stretched into slivers (aspect 80, a strip
/// 70 times longer than wide) with one step along it (1 800 triangles). meshoptimizer stays
/// near 8e-4 of the diagonal down to 12 triangles; we kept 28 at 1e-3 and 26 at 5e-3 (5.5×
/// its error at 0.5 %). The fan triangles beside the step are long and thin: bounded by their
/// height over the originals under them, the wall's height (the whole step) was taken where its
/// distance is a fraction of it, and split at most 6 times the parts stayed longer than the
/// grid's cells, their Lipschitz term above the step. With the distance to a steep original and
/// 10 splits: 11.
#[test]
fn a_long_step_of_slivers_simplifies() {
    let (drawn, original) = cut_triangles("mgen-2-3-step.obj", 1e-3);
    eprintln!("mgen-2-3-step: {drawn} of {original} triangles at 1e-3 of the diagonal");
    assert_eq!(original, 1_800);
    assert!(
        drawn <= 16,
        "{drawn} of {original} triangles at 1e-3 of the diagonal"
    );
}

/// mgen-4-4 reduced (`--reduce-to`): two creased 30 × 30 grids, one part each (3 600
/// triangles). At 0.5 % of the diagonal meshoptimizer draws 4 triangles (each grid flat, 3.1e-3
/// of the diagonal); we drew 6, one grid keeping its crease, because that grid's 4 → 3 triangle
/// collapse was bounded at 4.6× its distance: the border bound's argument took the centroid of
/// the fan triangle as its one point inside one original, and on a grid the centroid of a
/// triangle of grid vertices lies on an original edge. Any interior point will do: 4.
#[test]
fn two_creased_grids_flatten_together() {
    let (drawn, original) = cut_triangles("mgen-4-4-crease.glb", 0.005);
    eprintln!("mgen-4-4-crease: {drawn} of {original} triangles at 0.5 % of the diagonal");
    assert_eq!(original, 3_600);
    assert!(
        drawn <= 4,
        "{drawn} of {original} triangles at 0.5 % of the diagonal"
    );
}

/// mgen-3-0 reduced (a flat tube, 1 080 triangles): meshoptimizer's error at our triangle
/// count was lower at 1 and 2 % of the diagonal (1.09× and 1.011×). Once a collapse's error is
/// high, the candidates around it inherit it and tie at that cost; they were taken by vertex
/// ids, so the collapses that change the surface most went as early as those that change it
/// least. Ties go to the smallest own distance (`mt::build`'s candidate order): 48 triangles at
/// 1 % here (60 by vertex ids, seen failing), and the judge's export is 0.57× meshoptimizer's
/// error at 1 %, 0.66× at 2 %.
#[test]
fn a_flat_tube_takes_tied_collapses_by_their_own_distance() {
    let (drawn, original) = cut_triangles("mgen-3-0-tube.obj", 0.01);
    eprintln!("mgen-3-0-tube: {drawn} of {original} triangles at 1 % of the diagonal");
    assert!(
        drawn <= 52,
        "{drawn} of {original} triangles at 1 % of the diagonal"
    );
}
