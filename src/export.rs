//! A scene's tessellation, assembled for export: one mesh per shell, one node per placement.
//!
//! [`assemble`] turns a [`Scene`] into the [`ExportScene`] that [`crate::io::gltf_out`] writes:
//! - one node per placed solid / shell ([`Scene::instances`]) that has patches, named after its
//!   occurrence, with the instance's (world) transform, under groups that follow the
//!   occurrence paths (`a/b/c`: groups `a`, `b`, node `c`), all under one root group that turns
//!   the model's axes and unit into the file's ([`ExportOptions::up`], [`ExportOptions::scale`]);
//! - one mesh per shell (per part outside STEP: the key is `(part, shell)`), tessellated once in
//!   the shell's own coordinates and shared by every placement of it; its faces (patches) in
//!   order of their colours' first appearance, one glTF primitive per colour
//!   ([`ExportMesh::runs`]), so a face's or a mesh patch's colour is kept;
//! - every face tessellated to one ε in its own units: the absolute tolerance divided by the
//!   placement's scale, or, for a pixel error, the finest ε that any placement of the same face
//!   asks for in `default_view`.
//!
//! Guarantees: deterministic (instances, patches and meshes in scene order); the tolerance is
//! checked first, so a bad one never starts tessellating. A face whose tessellation fails
//! ([`PatchMesh::failure`]) is left out of its mesh and reported, once per mesh, by
//! [`assemble_reporting`] (`patchwork export` warns). Not done: no mesh is de-duplicated
//! beyond the `(part, shell)` key.

use std::borrow::Cow;
use std::collections::HashMap;

use glam::DMat4;
use thiserror::Error;

use crate::io::gltf_out::{ExportGroup, ExportMesh, ExportNode, ExportScene};
use crate::model::{Patch, PatchSurface, Scene, UpAxis};
use crate::tessellate::{PatchMesh, Tessellators};
use crate::view::{self, View};

/// Image size of [`default_view`], the view a pixel error is measured in.
pub(crate) const EXPORT_VIEW_SIZE: (u32, u32) = (1024, 768);

/// How finely the faces are tessellated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// Screen-space error in pixels, in `default_view`.
    PixelError(f64),
    /// Absolute error in model units (millimetres for STEP).
    Absolute(f64),
}

/// What [`assemble`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    pub tolerance: Tolerance,
    /// Written as the file's `asset.generator`.
    pub generator: String,
    /// The file's up axis: the root group turns the model's up axis into it (`None`: the
    /// model's axes are kept).
    pub up: Option<UpAxis>,
    /// File units per model unit (0.001 for millimetres written as metres), applied by the
    /// root group.
    pub scale: f64,
    /// Name of the root group (e.g. the file's name).
    pub root_name: String,
}

impl Default for ExportOptions {
    /// [`view::DEFAULT_PIXEL_ERROR`], generator `patchwork <version>`, the model's axes and
    /// units kept.
    fn default() -> Self {
        ExportOptions {
            tolerance: Tolerance::PixelError(view::DEFAULT_PIXEL_ERROR),
            generator: format!("patchwork {}", env!("CARGO_PKG_VERSION")),
            up: None,
            scale: 1.0,
            root_name: String::new(),
        }
    }
}

/// Length of one unit in metres, for the unit names [`Scene::unit`] and `export --unit` use
/// (`m`, `cm`, `mm`, `in`, `ft`).
pub fn metres_per_unit(unit: &str) -> Option<f64> {
    Some(match unit {
        "m" => 1.0,
        "cm" => 0.01,
        "mm" => 0.001,
        "in" => 0.0254,
        "ft" => 0.3048,
        _ => return None,
    })
}

/// The rotation taking a model whose up axis is `from` to one whose up axis is `to`, keeping
/// its front facing the viewer (z-up front −y ↔ y-up front +z): ∓90° about x.
pub(crate) fn up_rotation(from: UpAxis, to: UpAxis) -> DMat4 {
    match (from, to) {
        (UpAxis::Z, UpAxis::Y) => DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2),
        (UpAxis::Y, UpAxis::Z) => DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2),
        _ => DMat4::IDENTITY,
    }
}

/// Why a scene could not be assembled.
#[derive(Debug, Error)]
pub enum ExportError {
    /// The tolerance is not a positive finite number.
    #[error("the export tolerance must be a positive number, not {0:?}")]
    Tolerance(Tolerance),
    /// The unit scale is not a positive finite number.
    #[error("the export scale must be a positive number, not {0}")]
    Scale(f64),
}

/// The view a [`Tolerance::PixelError`] is measured in: the scene framed from the default
/// direction, [`view::DEFAULT_FOV_Y_DEG`], [`EXPORT_VIEW_SIZE`].
pub(crate) fn default_view(scene: &Scene) -> View {
    View::framing(
        &scene.bounds,
        scene.up.vector(),
        view::DEFAULT_FOV_Y_DEG.to_radians(),
        EXPORT_VIEW_SIZE,
    )
}

/// Whether two patches draw the same surface (the same face placed twice).
pub(crate) fn same_surface(a: &Patch, b: &Patch) -> bool {
    match (&a.surface, &b.surface) {
        (PatchSurface::Trimmed(x), PatchSurface::Trimmed(y)) => std::sync::Arc::ptr_eq(x, y),
        _ => a.id == b.id,
    }
}

/// The ε `p` is tessellated to, in its own (unplaced) units.
fn face_eps(scene: &Scene, view: &View, p: &Patch, tolerance: Tolerance) -> f64 {
    match tolerance {
        Tolerance::Absolute(tol) => tol / p.scale(),
        // The finest ε any placement of the face asks for.
        Tolerance::PixelError(px) => scene
            .patches
            .iter()
            .filter(|q| q.part == p.part && same_surface(q, p))
            .map(|q| view.eps_obj(&q.bounds, px) / q.scale())
            .fold(f64::INFINITY, f64::min),
    }
}

/// The patches to tessellate with their ε: every patch, except that a mesh's coarse groups
/// ([`Scene::mesh_groups`]) stand for their members where the ε wanted for the group (the
/// tolerance, or the pixel error over the group's bounds) reaches its switch error.
fn drawn<'a>(scene: &'a Scene, view: &View, tolerance: Tolerance) -> Vec<(Cow<'a, Patch>, f64)> {
    use crate::mt::group::Unit;
    let group_eps = |g: usize| match tolerance {
        // Group patches are unplaced (scale 1), as mesh patches are.
        Tolerance::Absolute(tol) => tol,
        Tolerance::PixelError(px) => view.eps_obj(&scene.mesh_groups[g].bounds, px),
    };
    let mut eps = |u: Unit| match u {
        Unit::Patch(p) => face_eps(scene, view, &scene.patches[p as usize], tolerance),
        Unit::Group(g) => group_eps(g as usize),
    };
    if scene.mesh_groups.is_empty() {
        return (scene.patches.iter())
            .map(|p| (Cow::Borrowed(p), face_eps(scene, view, p, tolerance)))
            .collect();
    }
    (scene.mesh_units(&mut eps).into_iter())
        .map(|u| match u {
            Unit::Patch(p) => {
                let p = &scene.patches[p as usize];
                (Cow::Borrowed(p), face_eps(scene, view, p, tolerance))
            }
            Unit::Group(g) => (
                Cow::Owned(scene.mesh_group_patch(g as usize)),
                group_eps(g as usize),
            ),
        })
        .collect()
}

/// A face (or mesh patch) left out of an export: its tessellation failed.
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    /// The patch's id in the scene (of the face's first placement, when several share it).
    pub patch: u32,
    /// The name of the part whose mesh it is missing from.
    pub part: String,
    /// Why ([`PatchMesh::failure`]).
    pub reason: String,
}

/// Tessellates `scene` into meshes (one per shell) and nodes (one per placement); see the
/// module documentation. Faces whose tessellation fails are left out: use
/// [`assemble_reporting`] to learn which.
pub fn assemble(scene: &Scene, opts: &ExportOptions) -> Result<ExportScene, ExportError> {
    assemble_reporting(scene, opts).map(|(doc, _)| doc)
}

/// [`assemble`], with the faces left out because their tessellation failed (each once, in
/// scene order, though a mesh several placements share is missing it in each).
pub fn assemble_reporting(
    scene: &Scene,
    opts: &ExportOptions,
) -> Result<(ExportScene, Vec<LeftOut>), ExportError> {
    let (Tolerance::PixelError(t) | Tolerance::Absolute(t)) = opts.tolerance;
    if !(t.is_finite() && t > 0.0) {
        return Err(ExportError::Tolerance(opts.tolerance));
    }
    if !(opts.scale.is_finite() && opts.scale > 0.0) {
        return Err(ExportError::Scale(opts.scale));
    }
    let view = default_view(scene);
    // The root group: the model's axes and unit turned into the file's.
    let rotation = opts
        .up
        .map_or(DMat4::IDENTITY, |to| up_rotation(scene.up, to));
    let root = DMat4::from_scale(glam::DVec3::splat(opts.scale)) * rotation;
    let mut tree = Tree {
        groups: vec![ExportGroup {
            name: opts.root_name.clone(),
            matrix: root.as_mat4().to_cols_array(),
            parent: None,
        }],
        by_path: HashMap::new(),
    };
    let mut by_instance: Vec<Vec<(Cow<'_, Patch>, f64)>> = vec![Vec::new(); scene.instances.len()];
    for (p, eps) in drawn(scene, &view, opts.tolerance) {
        if let Some(list) = by_instance.get_mut(p.instance as usize) {
            list.push((p, eps));
        }
    }
    let mut meshes = Vec::new();
    let mut left_out = Vec::new();
    let mut mesh_of = HashMap::new();
    let mut nodes = Vec::new();
    let mut t = Tessellators::new();
    for (index, (inst, patches)) in scene.instances.iter().zip(&by_instance).enumerate() {
        if patches.is_empty() {
            continue;
        }
        let part_name = scene
            .parts
            .get(inst.part as usize)
            .map(|p| p.name.clone())
            .unwrap_or_default();
        let key = (inst.part, inst.shell);
        let mesh = match mesh_of.get(&key) {
            Some(&m) => m,
            None => {
                let mut mesh = ExportMesh {
                    name: part_name.clone(),
                    ..ExportMesh::default()
                };
                // Faces grouped by colour (stable: first appearance), one run each.
                let mut first: Vec<Option<[u32; 3]>> = Vec::new();
                let mut order: Vec<(usize, &(Cow<'_, Patch>, f64))> = (patches.iter())
                    .map(|pe| {
                        let key = pe.0.color.map(|c| c.map(f32::to_bits));
                        let rank = first.iter().position(|&k| k == key).unwrap_or_else(|| {
                            first.push(key);
                            first.len() - 1
                        });
                        (rank, pe)
                    })
                    .collect();
                order.sort_by_key(|&(rank, _)| rank);
                for (_, (p, eps)) in order {
                    let eps = *eps;
                    let local = Patch {
                        transform: DMat4::IDENTITY,
                        ..Patch::clone(p)
                    };
                    let mut m = PatchMesh::default();
                    t.patch(&local, eps, &mut m);
                    if let Some(why) = &m.failure {
                        left_out.push(LeftOut {
                            patch: p.id,
                            part: part_name.clone(),
                            reason: why.clone(),
                        });
                    }
                    // A face or patch of another colour than the triangles before it
                    // starts a run (a primitive of its own).
                    let color = p.color.map(linear_color);
                    let current = mesh.runs.last().map_or(mesh.color, |r| r.1);
                    if mesh.indices.is_empty() {
                        mesh.color = color;
                    } else if color != current && !m.triangles.is_empty() {
                        mesh.runs.push((mesh.indices.len(), color));
                    }
                    append_used(&mut mesh, &m);
                }
                mesh_of.insert(key, meshes.len());
                meshes.push(mesh);
                meshes.len() - 1
            }
        };
        // The occurrence path `a/b/c`: groups `a` and `a/b`, the node named `c`.
        let (parent, leaf) = match inst.name.rsplit_once('/') {
            Some((path, leaf)) => (tree.group(path), leaf),
            None => (0, inst.name.as_str()),
        };
        let name = match (leaf.is_empty(), inst.shell) {
            (false, _) => leaf.to_owned(),
            (true, Some(shell)) => format!("{part_name} shell #{shell} {index}"),
            (true, None) => format!("{part_name} {index}"),
        };
        nodes.push(ExportNode {
            name,
            mesh,
            matrix: inst.transform.as_mat4().to_cols_array(),
            parent: Some(parent),
        });
    }
    let doc = ExportScene {
        meshes,
        nodes,
        groups: tree.groups,
        generator: opts.generator.clone(),
    };
    Ok((doc, left_out))
}

/// The groups of the assembly tree, made as occurrence paths name them. Instance transforms
/// are world transforms, so every group below the root has the identity matrix: the tree
/// keeps the structure and names, each node its whole placement.
struct Tree {
    groups: Vec<ExportGroup>,
    by_path: HashMap<String, usize>,
}

impl Tree {
    /// The group of occurrence path `path` (`a/b`), made with its ancestors if new.
    fn group(&mut self, path: &str) -> usize {
        if let Some(&g) = self.by_path.get(path) {
            return g;
        }
        let (parent, name) = match path.rsplit_once('/') {
            Some((up, name)) => (self.group(up), name),
            None => (0, path),
        };
        self.groups.push(ExportGroup {
            name: name.to_owned(),
            matrix: crate::io::gltf_out::IDENTITY_MATRIX,
            parent: Some(parent),
        });
        self.by_path.insert(path.to_owned(), self.groups.len() - 1);
        self.groups.len() - 1
    }
}

/// A patch's colour (sRGB, the space it is drawn in: `io::mesh` turns a glTF file's linear
/// base colour into it, OBJ and STEP colours are sRGB) as glTF's base colour factor, which
/// is linear (glTF 2.0, "Metallic-Roughness Material"), opaque.
fn linear_color(c: [f32; 3]) -> [f32; 4] {
    let [r, g, b] = c.map(|c| {
        let c = if c.is_finite() {
            c.clamp(0.0, 1.0)
        } else {
            1.0
        };
        if c <= 0.040_45 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    });
    [r, g, b, 1.0]
}

/// Appends the triangles of `m` with only the vertices they use: a trimmed face's mesh also
/// holds vertices of the untrimmed surface that no triangle kept, which would stretch the
/// bounds other tools compute from the vertices.
fn append_used(mesh: &mut ExportMesh, m: &PatchMesh) {
    let mut remap = vec![u32::MAX; m.positions.len()];
    for &i in m.triangles.iter().flatten() {
        let slot = &mut remap[i as usize];
        if *slot == u32::MAX {
            *slot = mesh.positions.len() as u32;
            mesh.positions.push(m.positions[i as usize].to_array());
            mesh.normals.push(m.normals[i as usize].to_array());
        }
        mesh.indices.push(*slot);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(name: &str) -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("models")
            .join(name);
        crate::prep::load(&path).expect("model loads")
    }

    fn triangles(doc: &ExportScene) -> usize {
        doc.meshes.iter().map(|m| m.indices.len() / 3).sum()
    }

    #[test]
    fn teapot_is_one_mesh_placed_once() {
        let scene = load("teapot.bpt");
        let doc = assemble(&scene, &ExportOptions::default()).expect("assembles");
        assert_eq!(doc.meshes.len(), scene.parts.len());
        assert_eq!(doc.meshes.len(), 1);
        assert_eq!(doc.nodes.len(), scene.instances.len());
        assert_eq!(doc.nodes[0].mesh, 0);
        assert_eq!(doc.nodes[0].matrix, crate::io::gltf_out::IDENTITY_MATRIX);
        let m = &doc.meshes[0];
        assert_eq!(m.normals.len(), m.positions.len());
        assert_eq!(m.indices.len() % 3, 0);
        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
        assert!(doc.generator.starts_with("patchwork "));
        // Every patch contributed triangles (32 patches, at least 2 each).
        assert!(triangles(&doc) >= 64, "{}", triangles(&doc));
    }

    /// A mesh of three colours (`mgen-6-3-colours.obj`: one patch or more per colour, the
    /// colours interleaved in the file) keeps them: one run per colour, each colour once, and
    /// every triangle in the run of its patch's colour.
    #[test]
    fn colours_of_a_mesh_are_kept_one_run_each() {
        let scene = load("generated/mgen-6-3-colours.obj");
        let doc = assemble(&scene, &ExportOptions::default()).expect("assembles");
        assert_eq!(doc.meshes.len(), 1);
        let m = &doc.meshes[0];
        let colours: Vec<_> = m.primitives().map(|(_, c)| c.expect("coloured")).collect();
        let mut distinct: Vec<[u32; 4]> = (scene.patches.iter())
            .map(|p| linear_color(p.color.expect("coloured")).map(f32::to_bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 3);
        let mut got: Vec<[u32; 4]> = colours.iter().map(|c| c.map(f32::to_bits)).collect();
        got.sort_unstable();
        assert_eq!(got, distinct, "each colour one run");
        // Every triangle lies in the run of its colour: its vertices are vertices of patches
        // of that colour (a cut's vertices are its patch's own, half-edge collapses move no
        // vertex).
        let mut of_colour: HashMap<[u32; 4], std::collections::HashSet<[u32; 3]>> = HashMap::new();
        for p in &scene.patches {
            let PatchSurface::Mesh(mesh) = &p.surface else {
                panic!("a mesh patch");
            };
            let key = linear_color(p.color.expect("coloured")).map(f32::to_bits);
            let set = of_colour.entry(key).or_default();
            set.extend(
                mesh.positions
                    .iter()
                    .map(|v| v.to_array().map(f32::to_bits)),
            );
        }
        for (range, colour) in m.primitives() {
            let key = colour.expect("coloured").map(f32::to_bits);
            for &i in &m.indices[range] {
                let v = m.positions[i as usize].map(f32::to_bits);
                assert!(of_colour[&key].contains(&v), "vertex {i} of another colour");
            }
        }
    }

    /// The base colour factor is linear: a patch's sRGB colour is converted (and glTF's
    /// reader converts it back: `io::mesh`).
    #[test]
    fn colours_are_written_linear() {
        assert_eq!(linear_color([0.0, 1.0, 0.5]), [0.0, 1.0, 0.21404114, 1.0]);
        assert_eq!(linear_color([f32::NAN, 2.0, -1.0]), [1.0, 1.0, 0.0, 1.0]);
        let scene = load("alien.glb");
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/alien.glb");
        let (doc, _, _) = gltf::import(path).expect("reads");
        let original: Vec<[u32; 3]> = (doc.materials())
            .map(|m| m.pbr_metallic_roughness().base_color_factor())
            .map(|[r, g, b, _]| [r, g, b].map(|c| (c * 255.0).round() as u32))
            .collect();
        let out = assemble(&scene, &ExportOptions::default()).expect("assembles");
        for m in &out.meshes {
            for (_, c) in m.primitives() {
                let c = c.expect("coloured").map(|c| (c * 255.0).round() as u32);
                let c = [c[0], c[1], c[2]];
                assert!(
                    original.contains(&c),
                    "{c:?} is none of the file's {original:?}"
                );
            }
        }
    }

    /// A trimmed face's mesh also holds vertices of its untrimmed surface that no triangle
    /// kept; the export leaves them out (other tools take bounds from the vertices).
    #[test]
    fn every_exported_vertex_is_used() {
        let scene = load("corpus/wing_fuselage.step");
        let doc = assemble(&scene, &ExportOptions::default()).expect("assembles");
        for m in &doc.meshes {
            let mut used = vec![false; m.positions.len()];
            for &i in &m.indices {
                used[i as usize] = true;
            }
            let unused = used.iter().filter(|u| !**u).count();
            assert_eq!(
                unused,
                0,
                "{}: {unused} of {} vertices unused",
                m.name,
                used.len()
            );
            assert_eq!(m.normals.len(), m.positions.len());
        }
    }

    #[test]
    fn finer_tolerance_gives_more_triangles() {
        let scene = load("teapot.bpt");
        let with = |tolerance| {
            let opts = ExportOptions {
                tolerance,
                ..ExportOptions::default()
            };
            triangles(&assemble(&scene, &opts).expect("assembles"))
        };
        let coarse = with(Tolerance::Absolute(0.05));
        let fine = with(Tolerance::Absolute(0.005));
        assert!(fine > coarse, "{fine} ≤ {coarse}");
        assert!(with(Tolerance::PixelError(4.0)) < with(Tolerance::PixelError(0.5)));
    }

    #[test]
    fn assembly_shares_a_mesh_between_placements_of_a_shell() {
        // 9 parts, 5 with geometry (rod, plate, bracket, bolt, nut), 18 placements.
        let scene = load("as1-oc-214.stp");
        let opts = ExportOptions {
            tolerance: Tolerance::Absolute(0.5),
            ..ExportOptions::default()
        };
        let doc = assemble(&scene, &opts).expect("assembles");
        assert_eq!(doc.meshes.len(), 5);
        assert_eq!(doc.nodes.len(), scene.instances.len());
        assert_eq!(doc.nodes.len(), 18);
        for (node, inst) in doc.nodes.iter().zip(&scene.instances) {
            assert_eq!(node.matrix, inst.transform.as_mat4().to_cols_array());
            let part = &scene.parts[inst.part as usize].name;
            assert!(
                node.name.starts_with(part.as_str()),
                "{} / {part}",
                node.name
            );
            assert_eq!(doc.meshes[node.mesh].name, *part);
        }
        // The same shell placed twice is the same mesh.
        for (a, ia) in doc.nodes.iter().zip(&scene.instances) {
            for (b, ib) in doc.nodes.iter().zip(&scene.instances) {
                assert_eq!(
                    a.mesh == b.mesh,
                    (ia.part, ia.shell) == (ib.part, ib.shell),
                    "{} / {}",
                    a.name,
                    b.name
                );
            }
        }
    }

    #[test]
    fn a_face_that_fails_is_reported_left_out() {
        // One face of the assembly given no loops: its tessellation fails (`NoLoops`).
        let mut scene = load("as1-oc-214.stp");
        let opts = ExportOptions {
            tolerance: Tolerance::Absolute(0.5),
            ..ExportOptions::default()
        };
        let (whole, none) = assemble_reporting(&scene, &opts).expect("assembles");
        assert!(none.is_empty(), "{none:?}");
        let k = (scene.patches.iter())
            .position(|p| matches!(p.surface, PatchSurface::Trimmed(_)))
            .expect("a trimmed face");
        let PatchSurface::Trimmed(face) = &scene.patches[k].surface else {
            unreachable!()
        };
        let mut broken = crate::model::trimmed::TrimmedFace::clone(face);
        broken.loops.clear();
        let broken = std::sync::Arc::new(broken);
        let id = scene.patches[k].id;
        // Every placement of that face (patches sharing its surface).
        let same = face.clone();
        for p in &mut scene.patches {
            if let PatchSurface::Trimmed(f) = &p.surface
                && std::sync::Arc::ptr_eq(f, &same)
            {
                p.surface = PatchSurface::Trimmed(broken.clone());
            }
        }
        let (doc, left) = assemble_reporting(&scene, &opts).expect("assembles");
        assert_eq!(left.len(), 1, "{left:?}");
        assert_eq!(left[0].patch, id);
        assert!(
            left[0].reason.contains("no boundary loop"),
            "{}",
            left[0].reason
        );
        let part = &scene.parts[scene.patches[k].part as usize].name;
        assert_eq!(&left[0].part, part);
        // The rest is written as before.
        assert!(triangles(&doc) < triangles(&whole));
        assert_eq!(doc.nodes.len(), whole.nodes.len());
    }

    #[test]
    fn bad_tolerance_is_an_error() {
        let scene = load("teapot.bpt");
        for tolerance in [
            Tolerance::Absolute(0.0),
            Tolerance::Absolute(-1.0),
            Tolerance::PixelError(f64::NAN),
            Tolerance::PixelError(f64::INFINITY),
        ] {
            let opts = ExportOptions {
                tolerance,
                ..ExportOptions::default()
            };
            assert!(matches!(
                assemble(&scene, &opts),
                Err(ExportError::Tolerance(_))
            ));
        }
    }

    #[test]
    fn same_surface_is_the_same_face_or_patch() {
        let scene = load("as1-oc-214.stp");
        let p = &scene.patches;
        assert!(same_surface(&p[0], &p[0]));
        assert!(!same_surface(&p[0], &p[1]));
        // A face placed twice: two patches, one surface.
        let twice = p
            .iter()
            .enumerate()
            .flat_map(|(i, a)| p[i + 1..].iter().map(move |b| (a, b)))
            .find(|(a, b)| a.instance != b.instance && same_surface(a, b));
        let (a, b) = twice.expect("a shell placed twice");
        assert_ne!(a.id, b.id);
        assert_eq!(a.part, b.part);
    }
}
