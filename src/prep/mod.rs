//! Load-time preparation, the stage between reading a file ([`crate::io`]) and everything that
//! uses a scene: a mesh is welded, split into patches and given its MT hierarchies
//! ([`crate::mt`]); a STEP model's faces are probed and placed ([`step`]). The scene that
//! comes out is immutable: per-view state lives in the frame loop and the renderer.
//!
//! Long steps report to a [`Progress`] the caller passes (the binary draws a bar); the
//! library itself prints nothing.

pub mod groups;
pub mod partition;
pub mod step;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DMat4;

pub use partition::partition;

use crate::io::mt_cache::{self, CacheKey};
use crate::io::{LoadError, Model};
use crate::model::mesh::{MeshGroup, MeshPatch, TriMesh};
use crate::model::{Patch, PatchSurface, Scene, Sphere, UpAxis, bounding_box};
use crate::mt::MtHierarchy;
use crate::mt::group::{GroupLinks, Unit};
use groups::GroupPart;

/// Triangles per patch when a mesh is split into patches (the 1–2 k).
pub const DEFAULT_PATCH_TRIANGLES: usize = 1500;

use crate::util::Bar;
pub use crate::util::{NoProgress, Progress};

/// When the MT hierarchies of a mesh's patches are built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hierarchies {
    /// Now, while loading (read from the cache when it holds them, written to it otherwise).
    #[default]
    Build,
    /// Read from the cache when it holds them; otherwise every patch gets the hierarchy
    /// without collapses ([`crate::mt::MtHierarchy::original`]: its cut is the full-resolution
    /// mesh, error 0, within every ε), made at once, and [`Loaded::pending`] says how to
    /// build the real ones later ([`PendingHierarchies::build`]).
    CachedOrOriginal,
}

/// How [`load_with_options`] prepares a model.
#[non_exhaustive]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    pub hierarchies: Hierarchies,
    /// Directory of the hierarchy cache ([`crate::io::mt_cache`]); `None`: no cache.
    pub cache: Option<PathBuf>,
    /// Build a mesh's coarse patch groups too ([`groups`]: `export` draws them; the frame
    /// loop does not yet, so the other commands leave out their ~3× build cost).
    pub groups: bool,
}

impl LoadOptions {
    pub fn new(hierarchies: Hierarchies, cache: Option<PathBuf>) -> LoadOptions {
        LoadOptions {
            hierarchies,
            cache,
            groups: false,
        }
    }
}

/// A prepared scene and what is left to do for it.
#[derive(Debug)]
pub struct Loaded {
    pub scene: Scene,
    /// The mesh patches still carry hierarchies without collapses: build them with this.
    pub pending: Option<PendingHierarchies>,
    /// About the cache (refused, unreadable or unwritable files): nothing is lost, the
    /// hierarchies were built instead.
    pub warnings: Vec<String>,
}

/// How to build the MT hierarchies a scene loaded with [`Hierarchies::CachedOrOriginal`] left
/// out, and where to store them.
#[derive(Clone, Debug, PartialEq)]
pub struct PendingHierarchies {
    arc_size: f64,
    cache: Option<(PathBuf, CacheKey)>,
}

/// A scene with every mesh patch's hierarchy built, and warnings about the cache.
#[derive(Debug)]
pub struct Built {
    pub scene: Scene,
    pub warnings: Vec<String>,
}

impl PendingHierarchies {
    /// A copy of `scene` in which every mesh patch has its real hierarchy (built on rayon,
    /// reported to `progress`), written to the cache when there is one. `scene` itself is
    /// not touched: a viewer keeps drawing it meanwhile and swaps in the result.
    pub fn build(&self, scene: &Scene, progress: &dyn Progress) -> Built {
        use rayon::prelude::*;
        let mut scene = scene.clone();
        let mesh_patches = scene
            .patches
            .iter()
            .filter(|p| matches!(p.surface, PatchSurface::Mesh(_)))
            .count();
        {
            let bar = Bar::begin(progress, "patch hierarchies", mesh_patches, 20);
            scene.patches.par_iter_mut().for_each(|p| {
                if let PatchSurface::Mesh(m) = &p.surface {
                    let mut m = MeshPatch::clone(m);
                    m.build_hierarchy(self.arc_size);
                    p.surface = PatchSurface::Mesh(Arc::new(m));
                    bar.advance();
                }
            });
            let patches: Vec<&MeshPatch> = mesh_patches_of(&scene);
            let mut groups: Vec<(MeshPatch, Vec<Unit>, u32)> = (scene.mesh_groups.iter())
                .map(|g| (MeshPatch::clone(&g.patch), g.links.members.clone(), g.level))
                .collect();
            groups
                .par_iter_mut()
                .for_each(|(p, _, _)| p.build_hierarchy(self.arc_size));
            let groups = finish_groups(&patches, groups);
            scene.mesh_groups = groups;
        }
        let mut warnings = Vec::new();
        if let Some((dir, key)) = &self.cache {
            let hs: Vec<&MtHierarchy> = mesh_hierarchies(&scene).collect();
            if let Err(e) = mt_cache::write(dir, *key, &hs) {
                warnings.push(e.to_string());
            }
        }
        Built { scene, warnings }
    }
}

/// The hierarchies a mesh scene caches: its patches', then its groups'.
fn mesh_hierarchies(scene: &Scene) -> impl Iterator<Item = &MtHierarchy> {
    let patches = scene.patches.iter().filter_map(|p| match &p.surface {
        PatchSurface::Mesh(m) => Some(&m.hierarchy),
        _ => None,
    });
    patches.chain(scene.mesh_groups.iter().map(|g| &g.patch.hierarchy))
}

/// The mesh patches of a scene, by patch id (a mesh scene's patches are all meshes).
fn mesh_patches_of(scene: &Scene) -> Vec<&MeshPatch> {
    (scene.patches.iter())
        .filter_map(|p| match &p.surface {
            PatchSurface::Mesh(m) => Some(&**m),
            _ => None,
        })
        .collect()
}

/// The scene's groups from built group patches (members before groups): each one's bounds
/// and switch error ([`crate::mt::group::switch_error`] against its members' hierarchies).
fn finish_groups(
    patches: &[&MeshPatch],
    groups: Vec<(MeshPatch, Vec<Unit>, u32)>,
) -> Vec<MeshGroup> {
    let mut out: Vec<MeshGroup> = Vec::with_capacity(groups.len());
    for (patch, members, level) in groups {
        let switch_error = {
            let theirs: Vec<&MtHierarchy> = (members.iter())
                .map(|&m| match m {
                    Unit::Patch(p) => &patches[p as usize].hierarchy,
                    Unit::Group(g) => &out[g as usize].patch.hierarchy,
                })
                .collect();
            crate::mt::group::switch_error(&patch.hierarchy, &theirs)
        };
        out.push(MeshGroup {
            bounds: Sphere::around(patch.positions.iter().map(|v| v.as_dvec3())),
            patch: Arc::new(patch),
            links: GroupLinks {
                members,
                switch_error,
            },
            level,
        });
    }
    out
}

/// Reads and prepares a model (see [`crate::io::read`] for the formats), building every
/// hierarchy, without a cache.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    load_with(path, &NoProgress)
}

/// As [`load`], reporting long steps to `progress`.
pub(crate) fn load_with(path: &Path, progress: &dyn Progress) -> Result<Scene, LoadError> {
    let mut scene = prepare(crate::io::read_with(path, progress)?, progress)?;
    scene.unit = scene.unit.or(crate::io::stated_unit(path));
    Ok(scene)
}

/// Prepares a model read by [`crate::io::read`], building every hierarchy (no cache).
pub fn prepare(model: Model, progress: &dyn Progress) -> Result<Scene, LoadError> {
    Ok(match model {
        Model::Bezier(patches) => Scene::from_bezier(patches, UpAxis::Z),
        Model::Mesh(mesh) => mesh_scene(
            mesh,
            DEFAULT_PATCH_TRIANGLES,
            crate::mt::DEFAULT_ARC_SIZE,
            UpAxis::Y,
            false,
            progress,
        ),
        Model::Step(model) => step::assemble(*model, progress)?,
    })
}

/// Reads and prepares a model as `options` say: a mesh's hierarchies from the cache, built
/// now, or left for later ([`Hierarchies`]).
pub fn load_with_options(
    path: &Path,
    options: &LoadOptions,
    progress: &dyn Progress,
) -> Result<Loaded, LoadError> {
    let model = crate::io::read(path)?;
    let Model::Mesh(mesh) = model else {
        let mut scene = prepare(model, progress)?;
        scene.unit = scene.unit.or(crate::io::stated_unit(path));
        return Ok(Loaded {
            scene,
            pending: None,
            warnings: Vec::new(),
        });
    };
    let mut warnings = Vec::new();
    let (patch_triangles, arc_size) = (DEFAULT_PATCH_TRIANGLES, crate::mt::DEFAULT_ARC_SIZE);
    let cache = options.cache.as_ref().and_then(|dir| {
        match std::fs::read(path) {
            Ok(bytes) => {
                let key = CacheKey::new(
                    &bytes,
                    &[
                        patch_triangles as u64,
                        arc_size.to_bits(),
                        u64::from(options.groups),
                    ],
                );
                Some((dir.clone(), key))
            }
            Err(e) => {
                // The model was just read; should it vanish now, go on without a cache.
                warnings.push(format!("{}: not cached: {e}", path.display()));
                None
            }
        }
    });
    let (parts, group_parts, labels, bbox, weld_warnings) =
        mesh_parts(mesh, patch_triangles, options.groups);
    let counts: Vec<usize> = (parts.iter().chain(group_parts.iter().map(|g| &g.patch)))
        .map(|p| p.positions.len())
        .collect();
    let cached = cache
        .as_ref()
        .and_then(|(dir, key)| match mt_cache::read(dir, *key, &counts) {
            Ok(Some(hs))
                if (hs.iter())
                    .zip(parts.iter().chain(group_parts.iter().map(|g| &g.patch)))
                    .all(|(h, p)| same_originals(h, p)) =>
            {
                Some(hs)
            }
            Ok(Some(_)) => {
                warnings.push(format!(
                    "{}: hierarchy cache refused: it does not match the patches; rebuilt",
                    dir.join(key.file_name()).display()
                ));
                None
            }
            Ok(None) => None,
            Err(e) => {
                warnings.push(format!("{e}; rebuilt"));
                None
            }
        });
    let pending = PendingHierarchies { arc_size, cache };
    let (parts, groups, pending) = match (cached, options.hierarchies) {
        (Some(hs), _) => {
            let mut hs = hs.into_iter();
            let parts: Vec<MeshPatch> = (parts.into_iter().zip(hs.by_ref()))
                .map(|(p, hierarchy)| MeshPatch { hierarchy, ..p })
                .collect();
            let groups = (group_parts.into_iter().zip(hs))
                .map(|(g, hierarchy)| GroupPart {
                    patch: MeshPatch {
                        hierarchy,
                        ..g.patch
                    },
                    ..g
                })
                .collect();
            (parts, groups, None)
        }
        (None, Hierarchies::Build) => {
            let (parts, groups) = build_hierarchies(parts, group_parts, arc_size, progress);
            if let Some((dir, key)) = &pending.cache {
                let hs: Vec<&MtHierarchy> = (parts.iter())
                    .map(|p| &p.hierarchy)
                    .chain(groups.iter().map(|g| &g.patch.hierarchy))
                    .collect();
                if let Err(e) = mt_cache::write(dir, *key, &hs) {
                    warnings.push(e.to_string());
                }
            }
            (parts, groups, None)
        }
        (None, Hierarchies::CachedOrOriginal) => {
            let original = |p: MeshPatch| MeshPatch {
                hierarchy: MtHierarchy::original(&p.triangles, p.positions.len()),
                ..p
            };
            let parts = parts.into_iter().map(original).collect();
            let groups = (group_parts.into_iter())
                .map(|g| GroupPart {
                    patch: original(g.patch),
                    ..g
                })
                .collect();
            (parts, groups, Some(pending))
        }
    };
    let mut scene = scene_of(parts, groups, &labels, UpAxis::Y, bbox, weld_warnings);
    scene.unit = crate::io::stated_unit(path);
    Ok(Loaded {
        scene,
        pending,
        warnings,
    })
}

/// Whether `h` is a hierarchy of patch `p`: its original triangles (created by node 0) are
/// the patch's.
fn same_originals(h: &MtHierarchy, p: &MeshPatch) -> bool {
    let mut a: Vec<[u32; 3]> = h
        .triangles
        .iter()
        .zip(&h.created_by)
        .filter(|&(_, &c)| c == 0)
        .map(|(t, _)| *t)
        .collect();
    let mut b = p.triangles.clone();
    a.sort_unstable();
    b.sort_unstable();
    a == b
}

/// Builds a scene from a triangle mesh: welded, split into patches of about
/// `patch_triangles` triangles ([`partition`](fn@partition)), each with its MT hierarchy reduced
/// to `arc_size` triangles per arc (built on rayon, reported to `progress`), and with
/// `groups` its coarse patch groups ([`groups`]) with theirs.
pub fn mesh_scene(
    m: TriMesh,
    patch_triangles: usize,
    arc_size: f64,
    up: UpAxis,
    groups: bool,
    progress: &dyn Progress,
) -> Scene {
    let (parts, groups, labels, bbox, warnings) = mesh_parts(m, patch_triangles, groups);
    let (parts, groups) = build_hierarchies(parts, groups, arc_size, progress);
    scene_of(parts, groups, &labels, up, bbox, warnings)
}

/// What the patches of a mesh belong to: the part names and each patch's group.
struct PatchLabels {
    part_names: Vec<String>,
    groups: Vec<crate::model::mesh::TriGroup>,
}

/// What [`mesh_parts`] returns: patches, their groups, labels, bounding box, warnings.
type MeshParts = (
    Vec<MeshPatch>,
    Vec<GroupPart>,
    PatchLabels,
    (glam::DVec3, glam::DVec3),
    Vec<String>,
);

/// The welded mesh's patches and, with `with_groups`, their groups (hierarchies not built),
/// its bounding box and warnings.
fn mesh_parts(mut m: TriMesh, patch_triangles: usize, with_groups: bool) -> MeshParts {
    let dropped = m.weld();
    let mut warnings = std::mem::take(&mut m.warnings);
    if dropped > 0 {
        warnings.push(format!(
            "{dropped} degenerate triangles dropped after welding"
        ));
    }
    let bbox = bounding_box(m.positions.iter().map(|p| p.as_dvec3())).unwrap_or_default();
    let patches = partition(&m, patch_triangles);
    // A patch lies in one group (partition never crosses them): its first triangle's.
    let of_triangle = m.triangle_groups();
    let groups = patches
        .iter()
        .map(|p| {
            let t = p.source_triangles.first().copied().unwrap_or(0) as usize;
            m.group(of_triangle.get(t).copied().unwrap_or(0))
        })
        .collect::<Vec<crate::model::mesh::TriGroup>>();
    let keys: Vec<groups::GroupKey> = (groups.iter())
        .map(|g| (g.part, g.color.map(|c| c.map(f32::to_bits))))
        .collect();
    let group_parts = match with_groups {
        true => groups::group_parts(
            &m,
            &patches,
            &keys,
            groups::UNITS_PER_GROUP,
            groups::GROUP_LEVELS,
        ),
        false => Vec::new(),
    };
    let labels = PatchLabels {
        part_names: std::mem::take(&mut m.part_names),
        groups,
    };
    (patches, group_parts, labels, bbox, warnings)
}

/// Every patch's and group's hierarchy built and reduced to `arc_size`, on rayon (the
/// groups, largest first, in the same pool as the patches).
fn build_hierarchies(
    mut parts: Vec<MeshPatch>,
    mut groups: Vec<GroupPart>,
    arc_size: f64,
    progress: &dyn Progress,
) -> (Vec<MeshPatch>, Vec<GroupPart>) {
    use rayon::prelude::*;
    let bar = Bar::begin(
        progress,
        "patch hierarchies",
        parts.len() + groups.len(),
        20,
    );
    let mut all: Vec<&mut MeshPatch> = groups.iter_mut().map(|g| &mut g.patch).collect();
    all.sort_by_key(|p| std::cmp::Reverse(p.triangles.len()));
    all.extend(parts.iter_mut());
    all.par_iter_mut().with_max_len(1).for_each(|p| {
        p.build_hierarchy(arc_size);
        bar.advance();
    });
    (parts, groups)
}

fn scene_of(
    parts: Vec<MeshPatch>,
    groups: Vec<GroupPart>,
    labels: &PatchLabels,
    up: UpAxis,
    bbox: (glam::DVec3, glam::DVec3),
    warnings: Vec<String>,
) -> Scene {
    let named = !labels.part_names.is_empty();
    let patches: Vec<Patch> = parts
        .into_iter()
        .enumerate()
        .map(|(i, p)| {
            let g = labels.groups.get(i).copied().unwrap_or_default();
            // Without part names every patch is part 0.
            let part = if named { g.part } else { 0 };
            Patch {
                id: i as u32,
                bounds: Sphere::around(p.positions.iter().map(|v| v.as_dvec3())),
                surface: PatchSurface::Mesh(Arc::new(p)),
                transform: DMat4::IDENTITY,
                part,
                color: g.color,
                // One instance per part (the triangles are in world coordinates).
                instance: part,
            }
        })
        .collect();
    let mut scene = Scene::single_part(patches, up, bbox, warnings);
    let groups = groups
        .into_iter()
        .map(|g| (g.patch, g.members, g.level))
        .collect();
    scene.mesh_groups = finish_groups(&mesh_patches_of(&scene), groups);
    if named {
        scene.parts = (labels.part_names.iter())
            .map(|name| crate::model::Part { name: name.clone() })
            .collect();
        scene.instances = (labels.part_names.iter().enumerate())
            .map(|(k, name)| crate::model::Instance {
                name: name.clone(),
                part: k as u32,
                transform: DMat4::IDENTITY,
                shell: None,
            })
            .collect();
    }
    scene
}
