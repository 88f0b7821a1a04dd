//! Meshes keep what their files say (issue 20 item 2): the file's normals (glTF NORMAL, OBJ
//! `vn`, PLY `nx ny nz`) reach the renderer through welding, partitioning and the MT
//! hierarchies' cuts; files without normals shade hard edges (dihedral > 40°) hard; OBJ
//! materials and PLY colours become group colours.
//!
//! The render checks compare the GPU image with an independent CPU reference: the file's
//! triangles read here with the `gltf` crate (or written here), rasterised in f64 with
//! perspective-correct normals and shaded with the renderer's lighting formula. Each check also
//! runs the comparison against the same reference with smoothed normals — what the renderer
//! drew before — and requires it to fail.

mod common;

use std::collections::HashMap;
use std::path::PathBuf;

use glam::{DMat4, DVec3, DVec4, Mat3, Mat4, Vec3};
use patchwork::model::{PatchSurface, Scene};
use patchwork::render::{RenderOptions, Shading};
use patchwork::tessellate::{PatchMesh, Tessellators};
use patchwork::view::{self, View};

fn data(name: &str) -> PathBuf {
    common::root().join("tests/data/mesh").join(name)
}

fn load(path: &std::path::Path) -> Scene {
    patchwork::prep::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// One triangle of a file as the test reads it: world positions, unit normals, sRGB colour.
#[derive(Clone, Copy, Debug)]
struct RefTri {
    p: [Vec3; 3],
    n: [Vec3; 3],
    color: [f32; 3],
}

fn srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Every triangle of a glTF file's default scene, read with the gltf crate (node matrices
/// composed, normals moved by the inverse transpose).
fn gltf_triangles(path: &std::path::Path) -> Vec<RefTri> {
    let (doc, buffers, _) = gltf::import(path).expect("imports");
    let scene = doc.default_scene().expect("a default scene");
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let r = prim.reader(|b| Some(&buffers[b.index()]));
                let p: Vec<Vec3> = r
                    .read_positions()
                    .expect("positions")
                    .map(Vec3::from)
                    .collect();
                let n: Vec<Vec3> = r.read_normals().expect("normals").map(Vec3::from).collect();
                let ix: Vec<u32> = r.read_indices().expect("indices").into_u32().collect();
                let [cr, cg, cb, _] = prim.material().pbr_metallic_roughness().base_color_factor();
                for t in ix.chunks_exact(3) {
                    out.push(RefTri {
                        p: [0, 1, 2].map(|k| world.transform_point3(p[t[k] as usize])),
                        n: [0, 1, 2].map(|k| (normal_matrix * n[t[k] as usize]).normalize()),
                        color: [cr, cg, cb].map(srgb),
                    });
                }
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    out
}

/// `tris` with area-weighted normals over bit-equal positions: what the renderer drew before
/// it kept the files' normals.
fn smoothed(tris: &[RefTri]) -> Vec<RefTri> {
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut sum: HashMap<[u32; 3], Vec3> = HashMap::new();
    for t in tris {
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
        for p in t.p {
            *sum.entry(key(p)).or_default() += n;
        }
    }
    tris.iter()
        .map(|t| RefTri {
            n: t.p.map(|p| sum[&key(p)].normalize_or_zero()),
            ..*t
        })
        .collect()
}

/// The renderer's light for `view` (`render::draw`'s globals: a key light above-left).
fn light(view: &View) -> (DVec3, DVec3) {
    let forward = (view.target - view.eye).normalize();
    let right = forward.cross(view.up).normalize();
    let up = right.cross(forward);
    (
        forward,
        (-forward * 0.8 + up * 0.55 - right * 0.35).normalize(),
    )
}

/// The reference image: per pixel the shaded colour and the triangle drawn (`u32::MAX`: none).
fn reference(tris: &[RefTri], view: &View) -> (Vec<[f64; 3]>, Vec<u32>) {
    let (w, h) = (view.width as usize, view.height as usize);
    let m: DMat4 = view.proj_matrix() * view.view_matrix();
    let (_, l) = light(view);
    let mut color = vec![[0.0; 3]; w * h];
    let mut id = vec![u32::MAX; w * h];
    let mut depth = vec![f64::INFINITY; w * h];
    for (k, t) in tris.iter().enumerate() {
        let clip = t.p.map(|p| m * p.as_dvec3().extend(1.0));
        if clip.iter().any(|c| c.w <= 1e-9) {
            continue;
        }
        let s = clip.map(|c: DVec4| {
            let ndc = c.truncate() / c.w;
            DVec3::new(
                (ndc.x * 0.5 + 0.5) * w as f64,
                (0.5 - ndc.y * 0.5) * h as f64,
                ndc.z,
            )
        });
        let area = (s[1].x - s[0].x) * (s[2].y - s[0].y) - (s[1].y - s[0].y) * (s[2].x - s[0].x);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = s[0].min(s[1]).min(s[2]);
        let hi = s[0].max(s[1]).max(s[2]);
        let (x0, y0) = ((lo.x - 0.5).ceil().max(0.0), (lo.y - 0.5).ceil().max(0.0));
        let (x1, y1) = (
            (hi.x - 0.5).floor().min(w as f64 - 1.0),
            (hi.y - 0.5).floor().min(h as f64 - 1.0),
        );
        let mut y = y0;
        while y <= y1 {
            let mut x = x0;
            while x <= x1 {
                let (px, py) = (x + 0.5, y + 0.5);
                let e = |a: DVec3, b: DVec3| {
                    ((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)) / area
                };
                let b = [e(s[1], s[2]), e(s[2], s[0]), e(s[0], s[1])];
                if b.iter().all(|&v| v >= 0.0) {
                    let z = b[0] * s[0].z + b[1] * s[1].z + b[2] * s[2].z;
                    let i = y as usize * w + x as usize;
                    if z < depth[i] {
                        // Perspective-correct weights.
                        let q = [0, 1, 2].map(|j| b[j] / clip[j].w);
                        let qs = q[0] + q[1] + q[2];
                        let at = |v: [Vec3; 3]| {
                            (0..3).fold(DVec3::ZERO, |acc, j| acc + v[j].as_dvec3() * (q[j] / qs))
                        };
                        let world = at(t.p);
                        let mut n = at(t.n).normalize_or_zero();
                        let v = (view.eye - world).normalize();
                        if n.dot(v) < 0.0 {
                            n = -n;
                        }
                        let diffuse = n.dot(l).max(0.0);
                        let spec = n.dot((l + v).normalize()).max(0.0).powf(48.0);
                        let base = t.color.map(f64::from);
                        color[i] =
                            base.map(|c| (c * (0.22 + 0.78 * diffuse) + 0.28 * spec).min(1.0));
                        depth[i] = z;
                        id[i] = k as u32;
                    }
                }
                x += 1.0;
            }
            y += 1.0;
        }
    }
    (color, id)
}

/// The scene's original triangles (no simplification) drawn lit, one sample per pixel.
fn render_original(scene: &Scene, view: &View) -> Vec<u8> {
    let mut tess = Tessellators::new();
    let meshes: Vec<PatchMesh> = scene
        .patches
        .iter()
        .map(|p| {
            let mut out = PatchMesh::default();
            tess.patch_with(p, 1e-3, true, &mut out);
            out
        })
        .collect();
    let mut renderer = common::renderer();
    let gpu = renderer.upload(&meshes);
    let opts = RenderOptions {
        shading: Shading::Lit,
        msaa: 1,
        ..RenderOptions::default()
    };
    renderer.render(&gpu, view, &opts).expect("renders").color
}

/// Of the pixels whose 3 × 3 neighbourhood shows one reference triangle (away from edges,
/// silhouettes and coincident faces), the share whose colour differs from the reference by
/// more than 4/255 in a channel, and how many were compared.
fn mismatch(rgba: &[u8], reference: &(Vec<[f64; 3]>, Vec<u32>), view: &View) -> (f64, usize) {
    let (w, h) = (view.width as usize, view.height as usize);
    let (color, id) = reference;
    let (mut compared, mut bad) = (0usize, 0usize);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let t = id[i];
            let inside = t != u32::MAX
                && (-1i64..=1).all(|dy| {
                    (-1i64..=1)
                        .all(|dx| id[(y as i64 + dy) as usize * w + (x as i64 + dx) as usize] == t)
                });
            if !inside {
                continue;
            }
            compared += 1;
            let off = (0..3)
                .map(|c| (f64::from(rgba[4 * i + c]) - color[i][c] * 255.0).abs())
                .fold(0.0, f64::max);
            if off > 4.0 {
                bad += 1;
            }
        }
    }
    (bad as f64 / compared.max(1) as f64, compared)
}

fn golden_view(scene: &Scene) -> View {
    let fov = view::DEFAULT_FOV_Y_DEG.to_radians();
    View::framing(&scene.bounds, scene.up.vector(), fov, (400, 300))
}

/// Checks a scene's render against the file's triangles `tris` (and, as the control, against
/// them smoothed).
fn renders_as_the_file_shades(name: &str, scene: &Scene, tris: &[RefTri]) {
    let v = golden_view(scene);
    let rgba = render_original(scene, &v);
    let (faithful, n) = mismatch(&rgba, &reference(tris, &v), &v);
    let (smooth, _) = mismatch(&rgba, &reference(&smoothed(tris), &v), &v);
    eprintln!(
        "{name}: {n} pixels compared, {faithful:.4} off the file's shading, {smooth:.4} off smoothed"
    );
    assert!(n > 4_000, "{name}: only {n} pixels compared");
    assert!(
        faithful < 0.01,
        "{name}: {:.1} % of pixels are not shaded with the file's normals",
        100.0 * faithful
    );
    assert!(
        smooth > 0.2,
        "{name}: the control — the smoothed shading — should differ ({:.1} %)",
        100.0 * smooth
    );
}

fn mesh_patches(scene: &Scene) -> Vec<&patchwork::model::mesh::MeshPatch> {
    scene
        .patches
        .iter()
        .map(|p| match &p.surface {
            PatchSurface::Mesh(m) => &**m,
            other => panic!("not a mesh patch: {other:?}"),
        })
        .collect()
}

/// Position key of a point, for finding a file's corners.
fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Every patch triangle's corner normals are the file's for that corner (within the 1° in
/// which welding counts normals as one); a coarse cut of every patch's hierarchy uses only
/// normals the file gives at each vertex's position (a subset of the vertices, none averaged).
#[test]
fn the_cake_keeps_its_normals_through_patches_and_cuts() {
    let path = common::root().join("models/cakeBirthday.glb");
    let file = gltf_triangles(&path);
    let scene = load(&path);
    // Corners by their triangle (positions in winding order, from the smallest key).
    let tri_key = |p: [Vec3; 3]| {
        let k = p.map(key);
        let r = (0..3).min_by_key(|&i| k[i]).expect("three");
        [k[r], k[(r + 1) % 3], k[(r + 2) % 3]]
    };
    let mut by_triangle: HashMap<[[u32; 3]; 3], Vec<RefTri>> = HashMap::new();
    let mut at_position: HashMap<[u32; 3], Vec<Vec3>> = HashMap::new();
    for t in &file {
        by_triangle.entry(tri_key(t.p)).or_default().push(*t);
        for k in 0..3 {
            at_position.entry(key(t.p[k])).or_default().push(t.n[k]);
        }
    }
    let close = |a: Vec3, b: Vec3| a.dot(b) > 1.5f32.to_radians().cos();
    let mut matched = 0;
    for m in mesh_patches(&scene) {
        for t in &m.triangles {
            let p = t.map(|v| m.positions[v as usize]);
            let candidates = by_triangle
                .get(&tri_key(p))
                .expect("a triangle of the file");
            let fits = candidates.iter().any(|c| {
                (0..3).all(|k| {
                    let j = (0..3)
                        .find(|&j| key(c.p[j]) == key(p[k]))
                        .expect("same corners");
                    close(m.normals[t[k] as usize], c.n[j])
                })
            });
            assert!(
                fits,
                "triangle at {p:?} is not shaded with the file's normals"
            );
            matched += 1;
        }
    }
    assert_eq!(matched, file.len());
    // Coarse cuts: at 2 % of the model's size, far fewer triangles, the file's normals only.
    let eps = 0.02 * scene.bounds.radius;
    let mut tess = Tessellators::new();
    let (mut coarse, mut fine) = (0, 0);
    for p in &scene.patches {
        let mut out = PatchMesh::default();
        tess.patch(p, eps, &mut out);
        coarse += out.triangles.len();
        for &v in out.triangles.iter().flatten() {
            let (pos, n) = (out.positions[v as usize], out.normals[v as usize]);
            let given = &at_position[&key(pos)];
            assert!(
                given.iter().any(|&g| close(g, n)),
                "a cut vertex at {pos} has normal {n}, not one of the file's {given:?}"
            );
        }
        fine += mesh_patches(&scene)[p.id as usize].triangles.len();
    }
    assert!(coarse < fine, "the cuts are coarser: {coarse} of {fine}");
}

/// The cake's hard edges (flat facets, its own normals) render as the file shades them, not
/// smoothed into dark blotches.
#[test]
fn the_cake_renders_with_its_own_normals() {
    let path = common::root().join("models/cakeBirthday.glb");
    renders_as_the_file_shades("cake", &load(&path), &gltf_triangles(&path));
}

/// An OBJ cube without normals and with two materials: every 90° edge is a crease (24
/// vertices, each with its face's normal), its faces in the .mtl's two Kd colours, and it
/// renders flat-shaded.
#[test]
fn an_obj_cube_without_normals_has_hard_edges_and_its_material_colours() {
    let scene = load(&data("two_colours.obj"));
    let patches = mesh_patches(&scene);
    let vertices: usize = patches.iter().map(|m| m.positions.len()).sum();
    assert_eq!(vertices, 24, "8 corners × 3 faces");
    let mut tris = Vec::new();
    for (m, p) in patches.iter().zip(&scene.patches) {
        let color = p.color.expect("a material colour");
        for t in &m.triangles {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            let face = (b - a).cross(c - a).normalize();
            for &v in t {
                assert!(
                    m.normals[v as usize].dot(face) > 0.9999,
                    "a smoothed corner"
                );
            }
            tris.push(RefTri {
                p: [a, b, c],
                n: [face; 3],
                color,
            });
        }
    }
    let mut colours: Vec<[u32; 3]> = (scene.patches.iter())
        .map(|p| p.color.expect("coloured").map(f32::to_bits))
        .collect();
    colours.sort();
    colours.dedup();
    let expected = [[0.8f32, 0.1, 0.1], [0.1, 0.2, 0.9]].map(|c| c.map(f32::to_bits));
    assert_eq!(colours.len(), 2);
    assert!(expected.iter().all(|c| colours.contains(c)), "{colours:?}");
    renders_as_the_file_shades("obj cube", &scene, &tris);
}

/// OBJ `vn`: the file's normals are kept, even smooth across a 90° fold that would be a
/// crease without them.
#[test]
fn obj_normals_are_the_files() {
    let scene = load(&data("normals.obj"));
    let patches = mesh_patches(&scene);
    let m = patches[0];
    assert_eq!(
        m.positions.len(),
        6,
        "no vertex split: the file's normals agree"
    );
    let fold = Vec3::new(-1.0, 0.0, 1.0).normalize();
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let expected = if p.x == 1.0 && p.z == 0.0 {
            fold
        } else if p.x == 1.0 {
            -Vec3::X
        } else {
            Vec3::Z
        };
        assert!(
            n.dot(expected) > 0.9999,
            "{n} at {p}, the file says {expected}"
        );
    }
}

/// A missing material file or one outside the OBJ's folder: a warning, the default colour.
#[test]
fn obj_material_files_missing_or_outside_are_warnings() {
    for (file, why) in [
        ("missing_mtl.obj", "nowhere.mtl"),
        ("outside_mtl.obj", "outside"),
    ] {
        let scene = load(&data(file));
        assert!(scene.patches.iter().all(|p| p.color.is_none()), "{file}");
        assert!(
            scene.warnings.iter().any(|w| w.contains(why)),
            "{file}: {:?}",
            scene.warnings
        );
    }
}

/// PLY vertex colours become group colours (two squares, red and green) and its `nx ny nz`
/// the vertex normals (tilted on purpose, not the faces' +z).
#[test]
fn ply_vertex_colours_and_normals_are_kept() {
    let scene = load(&data("vertex_colours.ply"));
    let mut by_colour: HashMap<[u32; 3], usize> = HashMap::new();
    for (m, p) in mesh_patches(&scene).into_iter().zip(&scene.patches) {
        let c = p.color.expect("a vertex colour");
        *by_colour.entry(c.map(f32::to_bits)).or_default() += m.triangles.len();
        let expected = if c == [1.0, 0.0, 0.0] {
            Vec3::new(0.6, 0.0, 0.8)
        } else {
            assert_eq!(c, [0.0, 1.0, 0.0]);
            Vec3::new(0.0, 0.6, 0.8)
        };
        for n in &m.normals {
            assert!(
                (*n - expected).length() < 1e-6,
                "{n}, the file says {expected}"
            );
        }
    }
    assert_eq!(by_colour.len(), 2);
    assert!(by_colour.values().all(|&n| n == 2), "{by_colour:?}");
}

/// PLY face colours: faces 1 and 3 orange, face 2 blue (float channels) → two groups.
#[test]
fn ply_face_colours_are_groups() {
    let scene = load(&data("face_colours.ply"));
    let mut by_colour: HashMap<[u32; 3], usize> = HashMap::new();
    for (m, p) in mesh_patches(&scene).into_iter().zip(&scene.patches) {
        let c = p.color.expect("a face colour");
        *by_colour.entry(c.map(f32::to_bits)).or_default() += m.triangles.len();
    }
    let orange = [1.0f32, 0.5, 0.0].map(f32::to_bits);
    let blue = [0.0f32, 0.0, 1.0].map(f32::to_bits);
    assert_eq!(by_colour.get(&orange), Some(&4));
    assert_eq!(by_colour.get(&blue), Some(&2));
}

/// A PLY coloured per vertex with more distinct colours than groups are made for (a scan):
/// one colour, their mean, and a warning.
#[test]
fn ply_with_many_colours_is_drawn_in_their_mean() {
    let n = patchwork::io::mesh::MAX_COLOR_GROUPS + 6;
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {n}\nproperty list uchar int vertex_indices\nend_header\n",
        3 * n
    );
    for k in 0..n {
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
            text += &format!("{} {y} 0 {} 0 100\n", x + 2.0 * k as f64, 2 * k);
        }
    }
    for k in 0..n {
        text += &format!("3 {} {} {}\n", 3 * k, 3 * k + 1, 3 * k + 2);
    }
    let path = common::scratch("faithful").join("many_colours.ply");
    std::fs::write(&path, text).expect("writes");
    let scene = load(&path);
    let mean_red = (0..n).map(|k| (2 * k) as f32 / 255.0).sum::<f32>() / n as f32;
    for p in &scene.patches {
        let c = p.color.expect("the mean colour");
        assert!((c[0] - mean_red).abs() < 1e-5 && c[1] == 0.0, "{c:?}");
    }
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("distinct colours")),
        "{:?}",
        scene.warnings
    );
}
