//! Coarse patch groups of mesh scenes (issue 30; `mt::group`, `prep::groups`): an export at
//! a tolerance draws every patch exactly once — alone or inside one drawn group — and stays
//! within the tolerance of the original surface; coarse tolerances draw groups and fewer
//! triangles than the patches alone would.

use glam::{DVec3, Vec3};
use patchwork::export::{ExportOptions, Tolerance, assemble};
use patchwork::model::mesh::TriMesh;
use patchwork::model::{PatchSurface, Scene, UpAxis};
use patchwork::mt::group::Unit;

/// A bumpy sphere: an icosahedron subdivided `levels` times, radius 1 + 0.08 sin(5x) cos(4y).
fn bumpy_sphere(levels: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|v| Vec3::from(v).normalize())
    .to_vec();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let mut m = |x: u32, y: u32| {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    p.push(((p[x as usize] + p[y as usize]) * 0.5).normalize());
                    p.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    let positions = p
        .iter()
        .map(|v| *v * (1.0 + 0.08 * (5.0 * v.x).sin() * (4.0 * v.y).cos()))
        .collect();
    TriMesh {
        positions,
        triangles: f,
        ..TriMesh::default()
    }
}

fn scene() -> (Scene, TriMesh) {
    let mesh = bumpy_sphere(4);
    let scene = patchwork::prep::mesh_scene(
        mesh.clone(),
        100,
        patchwork::mt::DEFAULT_ARC_SIZE,
        UpAxis::Y,
        true,
        &patchwork::prep::NoProgress,
    );
    (scene, mesh)
}

/// The hierarchy of a unit.
fn hierarchy(scene: &Scene, u: Unit) -> &patchwork::mt::MtHierarchy {
    match u {
        Unit::Patch(p) => match &scene.patches[p as usize].surface {
            PatchSurface::Mesh(m) => &m.hierarchy,
            _ => panic!("a mesh scene"),
        },
        Unit::Group(g) => &scene.mesh_groups[g as usize].patch.hierarchy,
    }
}

/// The patches of a unit.
fn patches_of(scene: &Scene, u: Unit, out: &mut Vec<u32>) {
    match u {
        Unit::Patch(p) => out.push(p),
        Unit::Group(g) => {
            for &m in &scene.mesh_groups[g as usize].links.members {
                patches_of(scene, m, out);
            }
        }
    }
}

/// Largest distance from points on `from` (corners, centroids and edge midpoints) to the
/// triangles `to`.
fn one_sided(from: (&[DVec3], &[[u32; 3]]), to: (&[DVec3], &[[u32; 3]])) -> f64 {
    let mut worst = 0.0f64;
    for t in from.1 {
        let [a, b, c] = t.map(|i| from.0[i as usize]);
        for q in [
            a,
            b,
            c,
            (a + b + c) / 3.0,
            (a + b) / 2.0,
            (b + c) / 2.0,
            (c + a) / 2.0,
        ] {
            let d =
                to.1.iter()
                    .map(|s| {
                        let [x, y, z] = s.map(|i| to.0[i as usize]);
                        patchwork::geom::point_triangle_distance(q, x, y, z)
                    })
                    .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn an_export_draws_every_patch_once_within_its_tolerance() {
    let (scene, mesh) = scene();
    assert!(scene.patches.len() >= 30, "{} patches", scene.patches.len());
    assert!(scene.mesh_groups.iter().any(|g| g.level == 2), "two levels");
    let diagonal = scene.bbox_diagonal();
    let original: Vec<DVec3> = mesh.positions.iter().map(|v| v.as_dvec3()).collect();
    let mut some_group = false;
    // At one tolerance for all, this sphere's top group (one hierarchy for the whole mesh)
    // is always the cheapest: mixes of levels are `mt::group`'s tests.
    for rel in [2e-3, 5e-3, 1e-2, 2e-2, 5e-2] {
        let tol = rel * diagonal;
        let units = scene.mesh_units(&mut |_| tol);
        // Exactly once: never a group and its member, never neither.
        let mut covered = Vec::new();
        for &u in &units {
            patches_of(&scene, u, &mut covered);
        }
        covered.sort_unstable();
        let all: Vec<u32> = (0..scene.patches.len() as u32).collect();
        assert_eq!(covered, all, "at {rel}: {units:?}");
        let groups = units.iter().filter(|u| matches!(u, Unit::Group(_))).count();
        some_group |= groups > 0;
        // The export draws exactly the cuts of those units, and no more.
        let options = ExportOptions {
            tolerance: Tolerance::Absolute(tol),
            ..ExportOptions::default()
        };
        let out = assemble(&scene, &options).expect("the export assembles");
        let drawn: usize = out.meshes.iter().map(|m| m.indices.len() / 3).sum();
        let mut cut = Vec::new();
        let expected: usize = units
            .iter()
            .map(|&u| {
                hierarchy(&scene, u).cut(tol, &mut cut);
                cut.len()
            })
            .sum();
        assert_eq!(drawn, expected, "at {rel}");
        let patches_alone: usize = (0..scene.patches.len() as u32)
            .map(|p| {
                hierarchy(&scene, Unit::Patch(p)).cut(tol, &mut cut);
                cut.len()
            })
            .sum();
        // A group is drawn only where it costs no more than its members.
        assert!(
            drawn <= patches_alone,
            "at {rel}: {drawn} > {patches_alone}"
        );
        // Within the tolerance of the original, both ways (the exported vertices are the
        // original's, in the model's frame).
        let m = &out.meshes[0];
        let pos: Vec<DVec3> = m
            .positions
            .iter()
            .map(|p| DVec3::from(p.map(f64::from)))
            .collect();
        let tris: Vec<[u32; 3]> = m.indices.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let there = one_sided((&pos, &tris), (&original, &mesh.triangles));
        let back = one_sided((&original, &mesh.triangles), (&pos, &tris));
        // f32 positions: a little slack.
        assert!(
            there.max(back) <= tol * (1.0 + 1e-4) + 1e-6,
            "at {rel}: {there:.3e} / {back:.3e} > {tol:.3e}"
        );
    }
    assert!(some_group, "no tolerance drew a group");
}

/// The command a user runs, `patchwork export --tolerance`, draws the groups too: the same
/// triangles as the library's export of a scene loaded with its groups, fewer than a scene of
/// patches alone (the other commands load without groups: `LoadOptions::groups`).
#[test]
fn the_export_command_draws_the_groups() {
    use patchwork::prep::{Hierarchies, LoadOptions, NoProgress, load_with_options};
    // 20 480 triangles: 14 patches of the default 1 500, so groups of them.
    let mesh = bumpy_sphere(5);
    let dir = std::env::temp_dir().join(format!("patchwork-groups-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let obj = dir.join("sphere.obj");
    let mut text = String::new();
    for v in &mesh.positions {
        text.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
    }
    std::fs::write(&obj, text).expect("writes the model");
    let count = |groups: bool| {
        let mut options = LoadOptions::new(Hierarchies::Build, None);
        options.groups = groups;
        let scene = load_with_options(&obj, &options, &NoProgress)
            .expect("loads")
            .scene;
        let tol = 2e-2 * scene.bbox_diagonal();
        let options = ExportOptions {
            tolerance: Tolerance::Absolute(tol),
            ..ExportOptions::default()
        };
        let out = assemble(&scene, &options).expect("the export assembles");
        (
            out.meshes
                .iter()
                .map(|m| m.indices.len() / 3)
                .sum::<usize>(),
            tol,
        )
    };
    let ((grouped, tol), (alone, _)) = (count(true), count(false));
    assert!(
        grouped < alone,
        "the groups save nothing here: {grouped} vs {alone}"
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args([
            "export",
            "--no-cache",
            "--unit",
            "model",
            "--up",
            "model",
            "--tolerance",
        ])
        .arg(tol.to_string())
        .arg(&obj)
        .arg("-o")
        .arg(dir.join("sphere.glb"))
        .output()
        .expect("runs patchwork");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let drawn: usize = stdout
        .split(", ")
        .find_map(|f| f.strip_suffix(" triangles")?.trim().parse().ok())
        .unwrap_or_else(|| panic!("no triangle count in {stdout:?}"));
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(
        drawn, grouped,
        "the command drew {drawn} triangles; with groups {grouped}, patches alone {alone}"
    );
}

/// `models/spot.obj` loaded with its hierarchies built and its patches grouped.
fn spot_with_groups() -> Scene {
    use patchwork::prep::{Hierarchies, LoadOptions, NoProgress, load_with_options};
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/models/spot.obj"));
    let mut options = LoadOptions::new(Hierarchies::Build, None);
    options.groups = true;
    load_with_options(path, &options, &NoProgress)
        .expect("loads")
        .scene
}

/// The collapse order follows the node errors (`mt::build`: candidates re-keyed by a lower
/// bound of their certified error when popped). Ordered by the quadric alone, a collapse cheap
/// by quadric but high in error came early and passed its error to every collapse around it:
/// with the re-keying switched off, Spot as one hierarchy (its group) cut 1 967 triangles at
/// 0.5 % of the diagonal; ordered by error, 1 546 (meshoptimizer's distance at that count is
/// the same, 4.88e-3 against our 4.84e-3). Re-measured 2026-12-05 with border height bounds
/// and pieces split up to 8 times: 1 199 with the re-keying off (above the bound), 1 062 on.
#[test]
fn spot_as_one_hierarchy_cuts_few_triangles_at_half_a_percent() {
    let scene = spot_with_groups();
    let mut cut = Vec::new();
    let group = &scene.mesh_groups[0].patch;
    group.hierarchy.cut(5e-3 * scene.bbox_diagonal(), &mut cut);
    eprintln!("Spot's group: {} triangles at 0.5 %", cut.len());
    assert!(
        cut.len() <= 1_120,
        "Spot's group cuts {} triangles at 0.5 %",
        cut.len()
    );
}

/// The switch rule (`mt::group::select`): a group is drawn exactly where its cut has no more
/// triangles than what its members would draw at the same certified error — fewer triangles
/// for the same tolerance, and never a group that costs more than what it replaces. Spot's
/// group of its 4 patches: at 0.5 % of the diagonal its cut was 1 546 triangles against the
/// patches' 1 719, but the old rule also wanted it within one patch target (1 500) and drew
/// the patches; from about 10 % on its cut was larger than theirs (146 against 135) and the
/// old rule's 12.5 % slack drew it anyway. Both seen failing before the rule changed. Since
/// pieces split up to 8 times (`mt::build::PIECE_DEPTH`) the group costs no more than the
/// patches at every error here (1 062 against 1 279 at 0.5 %, equal at 50 %); the patches
/// winning is `mt::group`'s `a_group_is_drawn_only_where_it_costs_no_more_than_its_members`.
#[test]
fn spot_draws_its_group_exactly_where_the_group_is_cheaper() {
    let scene = spot_with_groups();
    assert_eq!((scene.patches.len(), scene.mesh_groups.len()), (4, 1));
    let diagonal = scene.bbox_diagonal();
    let mut cut = Vec::new();
    let mut cut_len = |u: Unit, tol: f64| {
        hierarchy(&scene, u).cut(tol, &mut cut);
        cut.len()
    };
    let (mut grouped, mut alone) = (0, 0);
    for rel in [1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.15, 0.2, 0.5] {
        let tol = rel * diagonal;
        let own = cut_len(Unit::Group(0), tol);
        let members: usize = (0..4).map(|p| cut_len(Unit::Patch(p), tol)).sum();
        let units = scene.mesh_units(&mut |_| tol);
        let drawn: usize = units.iter().map(|&u| cut_len(u, tol)).sum();
        eprintln!("at {rel}: group {own}, patches {members}: drew {units:?}");
        assert_eq!(drawn, own.min(members), "at {rel}: {units:?}");
        if own <= members {
            assert_eq!(units, vec![Unit::Group(0)], "at {rel}");
            grouped += 1;
        } else {
            alone += 1;
        }
    }
    // The group pays from 0.1 % to 2 % at least.
    assert!(grouped >= 5, "{grouped} grouped, {alone} alone");
    let tol = 5e-3 * diagonal;
    assert_eq!(scene.mesh_units(&mut |_| tol), vec![Unit::Group(0)]);
}
