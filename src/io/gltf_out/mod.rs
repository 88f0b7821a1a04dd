//! Binary glTF 2.0 (`.glb`) export of tessellated CAD assemblies.
//!
//! Implements the writing side of the Khronos *glTF 2.0 Specification* (version 2.0.1): the
//! JSON objects of "Concepts" (asset, scenes and nodes, binary data storage, meshes, materials)
//! and the container of "GLB File Format Specification". The JSON is built with the
//! [`gltf::json`] types and serialised with their serializer; [`gltf::binary::Glb`] packs it.
//!
//! Layout of a written file:
//! - one buffer, stored as the GLB `BIN` chunk;
//! - per exported mesh one primitive (mode `TRIANGLES`) per colour run ([`ExportMesh::runs`]),
//!   all sharing its vertices, with a `POSITION` accessor (with the
//!   `min`/`max` the specification requires), a `NORMAL` accessor when the mesh has normals and
//!   a `u32` index accessor per primitive, each in its own tightly packed buffer view (targets `ARRAY_BUFFER`
//!   and `ELEMENT_ARRAY_BUFFER`); every view starts on a 4-byte boundary;
//! - one material per distinct colour: metallic-roughness with `baseColorFactor` = the colour,
//!   metallic 0, roughness `ROUGHNESS`, double-sided (CAD faces are drawn from both sides),
//!   `alphaMode` `BLEND` when alpha < 1;
//! - one node per placed instance, with its `matrix` (omitted when it is the identity), under
//!   the groups of the assembly tree ([`ExportGroup`]: sub-assemblies, and a root that turns
//!   the model's axes and unit into the file's), and one scene, the default, listing the roots.
//!
//! Guarantees: the input is validated before anything is written (indices in range, finite
//! positions and matrices, colours in `0..=1`, …), so a file is either complete and valid or not
//! written at all; writing goes to a temporary file in the target's directory that is renamed
//! over the target, and removed on failure. Normals are normalised, and a zero or non-finite
//! normal becomes `(0, 0, 1)`, because glTF requires unit normals. Meshes without triangles are
//! left out with the nodes that place them, and so are meshes no node places.
//!
//! `.gltf` text output with the buffer in a `.bin` file beside it: [`write_gltf`].
//!
//! Not done: textures, texture coordinates, vertex
//! colours, de-duplication of identical meshes, compression (Draco, meshopt).

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use gltf::json;

/// The identity matrix, column-major, as in [`ExportNode::matrix`].
pub(crate) const IDENTITY_MATRIX: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// Base colour of meshes without [`ExportMesh::color`]: glTF's own default, opaque white.
pub(crate) const DEFAULT_COLOR: [f32; 4] = [1.0, 1.0, 1.0, 1.0];

/// Roughness of every exported material: a dull, plastic-like finish.
pub(crate) const ROUGHNESS: f32 = 0.5;

/// Stands for the output path in errors from `to_glb_bytes` (tests), which writes no file.
#[cfg(test)]
pub(crate) const IN_MEMORY: &str = "<in memory>";

/// One mesh per part, in the part's own coordinates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExportMesh {
    /// Name given to the glTF mesh (left out when empty).
    pub name: String,
    /// Vertex positions; every one must be finite.
    pub positions: Vec<[f32; 3]>,
    /// One normal per position, or none at all (then the file has no `NORMAL` attribute and
    /// viewers compute flat normals). Need not be unit length.
    pub normals: Vec<[f32; 3]>,
    /// Triangle list, three indices into `positions` per triangle, counter-clockwise seen from
    /// the front (all materials are double-sided, so the winding only affects lighting).
    pub indices: Vec<u32>,
    /// Base colour, linear RGBA, each component in `0..=1`; `None` is `DEFAULT_COLOR`.
    pub color: Option<[f32; 4]>,
    /// More colours in one mesh (a mesh whose faces or patches differ in colour): each
    /// `(start, colour)` gives the triangles from `indices[start]` to the next run's start
    /// (or the end) that colour, `color` being that of the triangles before the first run.
    /// Starts are multiples of 3, increasing, inside `indices`. One glTF primitive per run,
    /// all sharing the mesh's vertices.
    pub runs: Vec<(usize, Option<[f32; 4]>)>,
}

impl ExportMesh {
    /// The mesh's primitives: every run of `indices` with its colour (the first is `color`'s,
    /// empty when the mesh has no triangles before its first run).
    pub(crate) fn primitives(
        &self,
    ) -> impl Iterator<Item = (std::ops::Range<usize>, Option<[f32; 4]>)> + '_ {
        let starts = std::iter::once((0, self.color)).chain(self.runs.iter().copied());
        let ends = (self.runs.iter().map(|r| r.0)).chain(std::iter::once(self.indices.len()));
        starts
            .zip(ends)
            .map(|((start, color), end)| (start..end, color))
            .filter(|(range, _)| !range.is_empty())
    }
}

/// One node per placed instance of a part.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportNode {
    /// Name given to the glTF node (left out when empty).
    pub name: String,
    /// Index into [`ExportScene::meshes`].
    pub mesh: usize,
    /// Object → parent transform, column-major (translation in elements 12..15). Must be
    /// finite and affine (last row `0 0 0 1`), as glTF requires.
    pub matrix: [f32; 16],
    /// Index into [`ExportScene::groups`] of the group holding the node; `None`: a root node.
    pub parent: Option<usize>,
}

/// A node without a mesh that groups others: a sub-assembly of the tree, or the root that
/// turns the model's axes and units into the file's.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportGroup {
    /// Name given to the glTF node (left out when empty).
    pub name: String,
    /// Group → parent transform, as [`ExportNode::matrix`].
    pub matrix: [f32; 16],
    /// Index of the parent group, which must come before this one; `None`: a root node.
    pub parent: Option<usize>,
}

/// A tessellated assembly to export.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExportScene {
    /// The parts' meshes.
    pub meshes: Vec<ExportMesh>,
    /// The placed instances; only meshes some node places are written.
    pub nodes: Vec<ExportNode>,
    /// The tree above the nodes (every group is written, in this order, before the nodes).
    pub groups: Vec<ExportGroup>,
    /// Written as `asset.generator` (left out when empty), e.g. `"patchwork 0.1.0"`.
    pub generator: String,
}

/// What was written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GltfStats {
    /// Meshes written (those with triangles that some node places).
    pub meshes: usize,
    /// Nodes written (those placing a written mesh).
    pub nodes: usize,
    /// Triangles stored in the file: each written mesh counted once, however many nodes place
    /// it.
    pub triangles: usize,
    /// Size of the `.glb` file in bytes.
    pub bytes: usize,
}

/// Why a scene could not be exported.
///
/// Every variant names the output path; errors from `to_glb_bytes` (tests) use `IN_MEMORY`. Mesh
/// and node numbers are 0-based indices into [`ExportScene::meshes`] and
/// [`ExportScene::nodes`].
#[derive(Debug, thiserror::Error)]
pub enum GltfWriteError {
    /// The file could not be written (missing directory, no permission, disk full…).
    #[error("{}: cannot write: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },

    /// Nothing to export: no node places a mesh that has at least one triangle.
    #[error(
        "{}: nothing to export: no node places a mesh with at least one triangle",
        .path.display()
    )]
    Empty { path: PathBuf },

    /// A node refers to a mesh that does not exist.
    #[error(
        "{}: node {node} ({name:?}) refers to mesh {mesh}, but there are {meshes} meshes",
        .path.display()
    )]
    MissingMesh {
        path: PathBuf,
        node: usize,
        name: String,
        mesh: usize,
        meshes: usize,
    },

    /// A node's matrix has a NaN or infinite element, or is not affine.
    #[error("{}: node {node} ({name:?}): the matrix {reason}", .path.display())]
    InvalidMatrix {
        path: PathBuf,
        node: usize,
        name: String,
        reason: &'static str,
    },

    /// A node or group names a parent group that does not exist or (for a group) does not
    /// come before it.
    #[error("{}: {what} ({name:?}) has parent group {parent}, {reason}", .path.display())]
    BadParent {
        path: PathBuf,
        what: String,
        name: String,
        parent: usize,
        reason: &'static str,
    },

    /// The number of indices of a mesh is not a multiple of 3.
    #[error(
        "{}: mesh {mesh} ({name:?}) has {len} indices, which is not a multiple of 3",
        .path.display()
    )]
    PartialTriangle {
        path: PathBuf,
        mesh: usize,
        name: String,
        len: usize,
    },

    /// An index does not name a vertex of its mesh (`at` is its place in `indices`).
    #[error(
        "{}: mesh {mesh} ({name:?}): index {index} at position {at} is out of range for \
         {vertices} vertices",
        .path.display()
    )]
    IndexOutOfRange {
        path: PathBuf,
        mesh: usize,
        name: String,
        at: usize,
        index: u32,
        vertices: usize,
    },

    /// A vertex position has a NaN or infinite coordinate.
    #[error(
        "{}: mesh {mesh} ({name:?}): the position of vertex {vertex} is not finite: {value:?}",
        .path.display()
    )]
    NonFinitePosition {
        path: PathBuf,
        mesh: usize,
        name: String,
        vertex: usize,
        value: [f32; 3],
    },

    /// A mesh has normals, but not one per position.
    #[error(
        "{}: mesh {mesh} ({name:?}) has {normals} normals for {positions} positions \
         (expected as many, or none)",
        .path.display()
    )]
    NormalCount {
        path: PathBuf,
        mesh: usize,
        name: String,
        normals: usize,
        positions: usize,
    },

    /// A colour component is NaN, infinite or outside `0..=1`.
    #[error(
        "{}: mesh {mesh} ({name:?}) has colour {color:?}; every component must be within 0..=1",
        .path.display()
    )]
    InvalidColor {
        path: PathBuf,
        mesh: usize,
        name: String,
        color: [f32; 4],
    },

    /// A colour run of a mesh ([`ExportMesh::runs`]) does not start where a triangle does,
    /// after the run before it and inside the indices.
    #[error(
        "{}: mesh {mesh} ({name:?}): colour run {run} starts at index {start}, which is not a \
         triangle's first after the run before it and before the end ({indices} indices)",
        .path.display()
    )]
    BadRun {
        path: PathBuf,
        mesh: usize,
        name: String,
        run: usize,
        start: usize,
        indices: usize,
    },

    /// The file would exceed what GLB can describe (4 GiB with its 32-bit length fields).
    #[error("{}: too large for a .glb file: {reason}", .path.display())]
    TooLarge { path: PathBuf, reason: String },

    /// The glTF JSON could not be serialised or packed.
    #[error("{}: cannot encode glTF: {reason}", .path.display())]
    Encode { path: PathBuf, reason: String },
}

impl GltfWriteError {
    /// The output path the error is about (`IN_MEMORY` for `to_glb_bytes`, in tests).
    pub fn path(&self) -> &Path {
        match self {
            GltfWriteError::Io { path, .. }
            | GltfWriteError::Empty { path }
            | GltfWriteError::MissingMesh { path, .. }
            | GltfWriteError::InvalidMatrix { path, .. }
            | GltfWriteError::BadParent { path, .. }
            | GltfWriteError::PartialTriangle { path, .. }
            | GltfWriteError::IndexOutOfRange { path, .. }
            | GltfWriteError::NonFinitePosition { path, .. }
            | GltfWriteError::NormalCount { path, .. }
            | GltfWriteError::InvalidColor { path, .. }
            | GltfWriteError::BadRun { path, .. }
            | GltfWriteError::TooLarge { path, .. }
            | GltfWriteError::Encode { path, .. } => path,
        }
    }
}

/// Writes `scene` as a binary glTF file at `path`, atomically: the bytes go to a temporary file
/// in the same directory (`.<name>.<pid>.<n>.tmp`) that is then renamed to `path`. On any error
/// nothing is left behind, neither `path` (an existing file there is kept unchanged) nor the
/// temporary file.
pub fn write_glb(path: &Path, scene: &ExportScene) -> Result<GltfStats, GltfWriteError> {
    let (bytes, stats) = encode(path, scene)?;
    crate::io::atomic::write(path, &bytes).map_err(|source| GltfWriteError::Io {
        path: path.to_owned(),
        source,
    })?;
    Ok(stats)
}

/// Writes `scene` as a text glTF file at `path` (`NAME.gltf`) with its binary data in
/// `NAME.bin` beside it (referred to by a relative URI), with the validation of [`write_glb`];
/// each file is written atomically, the `.bin` first. [`GltfStats::bytes`] counts both.
pub fn write_gltf(path: &Path, scene: &ExportScene) -> Result<GltfStats, GltfWriteError> {
    let io = |source| GltfWriteError::Io {
        path: path.to_owned(),
        source,
    };
    let plan = plan(path, scene)?;
    let (mut root, bin) = build(scene, &plan);
    let bin_path = path.with_extension("bin");
    let bin_name = bin_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the path does not name a file",
            ))
        })?;
    if let Some(buffer) = root.buffers.first_mut() {
        buffer.uri = Some(uri_escape(&bin_name));
    }
    let json = json::serialize::to_vec_pretty(&root).map_err(|e| GltfWriteError::Encode {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    crate::io::atomic::write(&bin_path, &bin).map_err(|source| GltfWriteError::Io {
        path: bin_path.clone(),
        source,
    })?;
    crate::io::atomic::write(path, &json).map_err(io)?;
    Ok(GltfStats {
        meshes: plan.meshes.len(),
        nodes: plan.nodes.len(),
        triangles: plan.triangles,
        bytes: json.len() + bin.len(),
    })
}

/// A file name as a relative URI reference: bytes other than unreserved ones
/// (RFC 3986 §2.3) percent-encoded.
fn uri_escape(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// Encodes `scene` as the bytes of a binary glTF file, with the validation of [`write_glb`].
#[cfg(test)]
pub(crate) fn to_glb_bytes(scene: &ExportScene) -> Result<Vec<u8>, GltfWriteError> {
    encode(Path::new(IN_MEMORY), scene).map(|(bytes, _)| bytes)
}

/// Size of the GLB header and of each chunk header.
const GLB_HEADER_BYTES: u64 = 12;
const CHUNK_HEADER_BYTES: u64 = 8;

/// Bytes of one `vec3` of `f32` and of one `u32` index.
const VEC3_BYTES: u64 = 12;
const INDEX_BYTES: u64 = 4;

/// What survives validation: which meshes and nodes are written, in output order.
struct Plan {
    /// Input mesh indices, ascending.
    meshes: Vec<usize>,
    /// Input mesh index → output mesh index, for the written meshes.
    mesh_out: Vec<Option<u32>>,
    /// Input node indices, ascending.
    nodes: Vec<usize>,
    /// Exact size of the binary chunk's data.
    bin_len: u64,
    triangles: usize,
}

/// Validates and encodes; `path` is only used in errors.
fn encode(path: &Path, scene: &ExportScene) -> Result<(Vec<u8>, GltfStats), GltfWriteError> {
    let plan = plan(path, scene)?;
    let (root, bin) = build(scene, &plan);

    let json = json::serialize::to_vec(&root).map_err(|e| GltfWriteError::Encode {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    let total = GLB_HEADER_BYTES
        + CHUNK_HEADER_BYTES
        + pad4(json.len() as u64)
        + CHUNK_HEADER_BYTES
        + pad4(bin.len() as u64);
    let length = u32::try_from(total).map_err(|_| GltfWriteError::TooLarge {
        path: path.to_owned(),
        reason: format!("{total} bytes"),
    })?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length,
        },
        // `Glb` pads the JSON chunk with spaces and the BIN chunk with zeros to 4 bytes.
        json: Cow::Owned(json),
        bin: Some(Cow::Owned(bin)),
    };
    let bytes = glb.to_vec().map_err(|e| GltfWriteError::Encode {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    debug_assert_eq!(bytes.len() as u64, total);

    let stats = GltfStats {
        meshes: plan.meshes.len(),
        nodes: plan.nodes.len(),
        triangles: plan.triangles,
        bytes: bytes.len(),
    };
    Ok((bytes, stats))
}

fn pad4(n: u64) -> u64 {
    n.div_ceil(4) * 4
}

/// Checks the whole input and decides what is written.
fn plan(path: &Path, scene: &ExportScene) -> Result<Plan, GltfWriteError> {
    for (i, mesh) in scene.meshes.iter().enumerate() {
        check_mesh(path, i, mesh)?;
    }

    for (i, group) in scene.groups.iter().enumerate() {
        check_matrix(&group.matrix).map_err(|reason| GltfWriteError::InvalidMatrix {
            path: path.to_owned(),
            node: i,
            name: format!("group {}", group.name),
            reason,
        })?;
        if let Some(parent) = group.parent
            && parent >= i
        {
            return Err(GltfWriteError::BadParent {
                path: path.to_owned(),
                what: format!("group {i}"),
                name: group.name.clone(),
                parent,
                reason: "which does not come before it",
            });
        }
    }
    let mut placed = vec![false; scene.meshes.len()];
    for (i, node) in scene.nodes.iter().enumerate() {
        if let Some(parent) = node.parent
            && parent >= scene.groups.len()
        {
            return Err(GltfWriteError::BadParent {
                path: path.to_owned(),
                what: format!("node {i}"),
                name: node.name.clone(),
                parent,
                reason: "which does not exist",
            });
        }
        let invalid = |reason| GltfWriteError::InvalidMatrix {
            path: path.to_owned(),
            node: i,
            name: node.name.clone(),
            reason,
        };
        if node.mesh >= scene.meshes.len() {
            return Err(GltfWriteError::MissingMesh {
                path: path.to_owned(),
                node: i,
                name: node.name.clone(),
                mesh: node.mesh,
                meshes: scene.meshes.len(),
            });
        }
        check_matrix(&node.matrix).map_err(invalid)?;
        placed[node.mesh] = true;
    }

    let mut meshes = Vec::new();
    let mut mesh_out = vec![None; scene.meshes.len()];
    let mut bin_len = 0u64;
    let mut triangles = 0usize;
    let mut objects = 0u64;
    for (i, mesh) in scene.meshes.iter().enumerate() {
        if !placed[i] || mesh.indices.is_empty() {
            continue;
        }
        // Fits: the output counts stay far below the input counts checked in `too_large`.
        mesh_out[i] = Some(meshes.len() as u32);
        meshes.push(i);
        bin_len += VEC3_BYTES * (mesh.positions.len() + mesh.normals.len()) as u64
            + INDEX_BYTES * mesh.indices.len() as u64;
        triangles += mesh.indices.len() / 3;
        objects += 3 + mesh.runs.len() as u64;
        if let Some(reason) = too_large(bin_len, objects) {
            return Err(GltfWriteError::TooLarge {
                path: path.to_owned(),
                reason,
            });
        }
    }
    let nodes: Vec<usize> = (0..scene.nodes.len())
        .filter(|&i| mesh_out[scene.nodes[i].mesh].is_some())
        .collect();
    if nodes.is_empty() {
        return Err(GltfWriteError::Empty {
            path: path.to_owned(),
        });
    }
    if u32::try_from(nodes.len()).is_err() {
        return Err(GltfWriteError::TooLarge {
            path: path.to_owned(),
            reason: format!("{} nodes", nodes.len()),
        });
    }
    Ok(Plan {
        meshes,
        mesh_out,
        nodes,
        bin_len,
        triangles,
    })
}

/// Why `m` cannot be a glTF node matrix (finite and affine), if it cannot.
fn check_matrix(m: &[f32; 16]) -> Result<(), &'static str> {
    if !m.iter().all(|x| x.is_finite()) {
        return Err("has a NaN or infinite element");
    }
    if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        return Err("is not affine (its last row is not 0 0 0 1)");
    }
    Ok(())
}

/// Whether the binary data, or the number of glTF objects, is beyond what a GLB can hold.
///
/// Keeping the data under 4 GiB also keeps every object count (at most 3 accessors and 3 views
/// per mesh and one more of each per colour run, each mesh holding at least 28 bytes and each
/// run 12) below `u32::MAX`, so the `Index` pushes of [`build`] cannot panic. `objects`: the
/// accessors so far.
fn too_large(bin_len: u64, objects: u64) -> Option<String> {
    let limit = u64::from(u32::MAX) - GLB_HEADER_BYTES - 2 * CHUNK_HEADER_BYTES;
    (bin_len > limit || objects >= u64::from(u32::MAX))
        .then(|| format!("{bin_len} bytes of binary data in {objects} accessors"))
}

fn check_mesh(path: &Path, i: usize, mesh: &ExportMesh) -> Result<(), GltfWriteError> {
    let path = || path.to_owned();
    let name = || mesh.name.clone();
    if !mesh.indices.len().is_multiple_of(3) {
        return Err(GltfWriteError::PartialTriangle {
            path: path(),
            mesh: i,
            name: name(),
            len: mesh.indices.len(),
        });
    }
    if !mesh.normals.is_empty() && mesh.normals.len() != mesh.positions.len() {
        return Err(GltfWriteError::NormalCount {
            path: path(),
            mesh: i,
            name: name(),
            normals: mesh.normals.len(),
            positions: mesh.positions.len(),
        });
    }
    if let Some((vertex, &value)) =
        (mesh.positions.iter().enumerate()).find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(GltfWriteError::NonFinitePosition {
            path: path(),
            mesh: i,
            name: name(),
            vertex,
            value,
        });
    }
    if let Some((at, &index)) = (mesh.indices.iter().enumerate())
        .find(|&(_, &index)| index as usize >= mesh.positions.len())
    {
        return Err(GltfWriteError::IndexOutOfRange {
            path: path(),
            mesh: i,
            name: name(),
            at,
            index,
            vertices: mesh.positions.len(),
        });
    }
    let mut after = 0;
    for (run, &(start, _)) in mesh.runs.iter().enumerate() {
        if start % 3 != 0 || start < after || start >= mesh.indices.len() {
            return Err(GltfWriteError::BadRun {
                path: path(),
                mesh: i,
                name: name(),
                run,
                start,
                indices: mesh.indices.len(),
            });
        }
        after = start + 3;
    }
    let colors = std::iter::once(mesh.color).chain(mesh.runs.iter().map(|r| r.1));
    match colors
        .flatten()
        .find(|c| !c.iter().all(|c| (0.0..=1.0).contains(c)))
    {
        Some(color) => Err(GltfWriteError::InvalidColor {
            path: path(),
            mesh: i,
            name: name(),
            color,
        }),
        None => Ok(()),
    }
}

mod build;
use build::build;
#[cfg(test)]
mod tests;
