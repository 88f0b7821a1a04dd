//! Binary glTF 2.0 (`.glb`) export of tessellated CAD assemblies.
//!
//! Implements the writing side of the Khronos *glTF 2.0 Specification* (version 2.0.1): the
//! JSON objects of "Concepts" (asset, scenes and nodes, binary data storage, meshes, materials)
//! and the container of "GLB File Format Specification". The JSON is built with the
//! [`gltf::json`] types and serialised with their serializer; [`gltf::binary::Glb`] packs it.
//!
//! Layout of a written file:
//! - one buffer, stored as the GLB `BIN` chunk;
//! - per exported mesh one primitive (mode `TRIANGLES`) with a `POSITION` accessor (with the
//!   `min`/`max` the specification requires), a `NORMAL` accessor when the mesh has normals and
//!   a `u32` index accessor, each in its own tightly packed buffer view (targets `ARRAY_BUFFER`
//!   and `ELEMENT_ARRAY_BUFFER`); every view starts on a 4-byte boundary;
//! - one material per distinct colour: metallic-roughness with `baseColorFactor` = the colour,
//!   metallic 0, roughness [`ROUGHNESS`], double-sided (CAD faces are drawn from both sides),
//!   `alphaMode` `BLEND` when alpha < 1;
//! - one node per placed instance, with its `matrix` (omitted when it is the identity), and one
//!   scene, the default, listing all nodes.
//!
//! Guarantees: the input is validated before anything is written (indices in range, finite
//! positions and matrices, colours in `0..=1`, …), so a file is either complete and valid or not
//! written at all; writing goes to a temporary file in the target's directory that is renamed
//! over the target, and removed on failure. Normals are normalised, and a zero or non-finite
//! normal becomes `(0, 0, 1)`, because glTF requires unit normals. Meshes without triangles are
//! left out with the nodes that place them, and so are meshes no node places.
//!
//! Not done: node hierarchies (every node is a root), textures, texture coordinates, vertex
//! colours, de-duplication of identical meshes, compression (Draco, meshopt), and `.gltf` text
//! output with external buffers.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::Vec3;
use gltf::json;
use json::validation::{Checked::Valid, USize64};

/// The identity matrix, column-major, as in [`ExportNode::matrix`].
pub const IDENTITY_MATRIX: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// Base colour of meshes without [`ExportMesh::color`]: glTF's own default, opaque white.
pub const DEFAULT_COLOR: [f32; 4] = [1.0, 1.0, 1.0, 1.0];

/// Roughness of every exported material: a dull, plastic-like finish.
pub const ROUGHNESS: f32 = 0.5;

/// Stands for the output path in errors from [`to_glb_bytes`], which writes no file.
pub const IN_MEMORY: &str = "<in memory>";

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
    /// Base colour, linear RGBA, each component in `0..=1`; `None` is [`DEFAULT_COLOR`].
    pub color: Option<[f32; 4]>,
}

/// One node per placed instance of a part.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportNode {
    /// Name given to the glTF node (left out when empty).
    pub name: String,
    /// Index into [`ExportScene::meshes`].
    pub mesh: usize,
    /// Object → world transform, column-major (translation in elements 12..15). Must be finite
    /// and affine (last row `0 0 0 1`), as glTF requires.
    pub matrix: [f32; 16],
}

/// A tessellated assembly to export.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExportScene {
    /// The parts' meshes.
    pub meshes: Vec<ExportMesh>,
    /// The placed instances; only meshes some node places are written.
    pub nodes: Vec<ExportNode>,
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
/// Every variant names the output path; errors from [`to_glb_bytes`] use [`IN_MEMORY`]. Mesh
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

    /// The file would exceed what GLB can describe (4 GiB with its 32-bit length fields).
    #[error("{}: too large for a .glb file: {reason}", .path.display())]
    TooLarge { path: PathBuf, reason: String },

    /// The glTF JSON could not be serialised or packed.
    #[error("{}: cannot encode glTF: {reason}", .path.display())]
    Encode { path: PathBuf, reason: String },
}

impl GltfWriteError {
    /// The output path the error is about ([`IN_MEMORY`] for [`to_glb_bytes`]).
    pub fn path(&self) -> &Path {
        match self {
            GltfWriteError::Io { path, .. }
            | GltfWriteError::Empty { path }
            | GltfWriteError::MissingMesh { path, .. }
            | GltfWriteError::InvalidMatrix { path, .. }
            | GltfWriteError::PartialTriangle { path, .. }
            | GltfWriteError::IndexOutOfRange { path, .. }
            | GltfWriteError::NonFinitePosition { path, .. }
            | GltfWriteError::NormalCount { path, .. }
            | GltfWriteError::InvalidColor { path, .. }
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

/// Encodes `scene` as the bytes of a binary glTF file, with the validation of [`write_glb`].
pub fn to_glb_bytes(scene: &ExportScene) -> Result<Vec<u8>, GltfWriteError> {
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

    let mut placed = vec![false; scene.meshes.len()];
    for (i, node) in scene.nodes.iter().enumerate() {
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
        if !node.matrix.iter().all(|x| x.is_finite()) {
            return Err(invalid("has a NaN or infinite element"));
        }
        let last_row = [
            node.matrix[3],
            node.matrix[7],
            node.matrix[11],
            node.matrix[15],
        ];
        if last_row != [0.0, 0.0, 0.0, 1.0] {
            return Err(invalid("is not affine (its last row is not 0 0 0 1)"));
        }
        placed[node.mesh] = true;
    }

    let mut meshes = Vec::new();
    let mut mesh_out = vec![None; scene.meshes.len()];
    let mut bin_len = 0u64;
    let mut triangles = 0usize;
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
        if let Some(reason) = too_large(bin_len, meshes.len()) {
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

/// Whether the binary data, or the number of glTF objects, is beyond what a GLB can hold.
///
/// Keeping the data under 4 GiB also keeps every object count (at most 3 accessors and 3 views
/// per mesh, each mesh holding at least 28 bytes) below `u32::MAX`, so the `Index` pushes of
/// [`build`] cannot panic.
fn too_large(bin_len: u64, meshes: usize) -> Option<String> {
    let limit = u64::from(u32::MAX) - GLB_HEADER_BYTES - 2 * CHUNK_HEADER_BYTES;
    (bin_len > limit || meshes as u64 * 3 >= u64::from(u32::MAX))
        .then(|| format!("{bin_len} bytes of binary data in {meshes} meshes"))
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
    match mesh.color {
        Some(color) if !color.iter().all(|c| (0.0..=1.0).contains(c)) => {
            Err(GltfWriteError::InvalidColor {
                path: path(),
                mesh: i,
                name: name(),
                color,
            })
        }
        _ => Ok(()),
    }
}

/// Builds the glTF JSON and the binary chunk for a validated [`Plan`].
fn build(scene: &ExportScene, plan: &Plan) -> (json::Root, Vec<u8>) {
    let mut root = json::Root {
        asset: json::Asset {
            generator: non_empty(&scene.generator),
            ..Default::default()
        },
        ..Default::default()
    };
    // Reserves the capacity once; `plan` computed the exact size.
    let mut bin = Vec::with_capacity(usize::try_from(plan.bin_len).unwrap_or(0));
    let buffer = root.push(json::Buffer {
        byte_length: USize64(plan.bin_len),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let mut materials: HashMap<[u32; 4], json::Index<json::Material>> = HashMap::new();

    for &i in &plan.meshes {
        let mesh = &scene.meshes[i];

        let view = push_f32x3(&mut root, &mut bin, buffer, mesh.positions.iter().copied());
        let (min, max) = bounds(&mesh.positions);
        let positions = root.push(accessor_vec3(view, mesh.positions.len(), Some((min, max))));
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), positions);

        if !mesh.normals.is_empty() {
            let unit = mesh.normals.iter().map(|&n| unit_normal(n));
            let view = push_f32x3(&mut root, &mut bin, buffer, unit);
            let normals = root.push(accessor_vec3(view, mesh.normals.len(), None));
            attributes.insert(Valid(json::mesh::Semantic::Normals), normals);
        }

        let view = push_u32(&mut root, &mut bin, buffer, &mesh.indices);
        let indices = root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(mesh.indices.len()),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::U32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(json::accessor::Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        });

        let color = mesh.color.unwrap_or(DEFAULT_COLOR);
        // `+ 0.0` turns -0.0 into 0.0, so that both share a material.
        let key = color.map(|c| (c + 0.0).to_bits());
        let material = *materials
            .entry(key)
            .or_insert_with(|| root.push(material(color)));

        root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: non_empty(&mesh.name),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
    }
    debug_assert_eq!(bin.len() as u64, plan.bin_len);

    let mut nodes = Vec::with_capacity(plan.nodes.len());
    for &i in &plan.nodes {
        let node = &scene.nodes[i];
        let mesh = plan.mesh_out[node.mesh].map(json::Index::new);
        nodes.push(root.push(json::Node {
            mesh,
            name: non_empty(&node.name),
            matrix: (node.matrix != IDENTITY_MATRIX).then_some(node.matrix),
            ..Default::default()
        }));
    }
    let scene_index = root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: None,
        nodes,
    });
    root.scene = Some(scene_index);
    (root, bin)
}

fn non_empty(s: &str) -> Option<String> {
    (!s.is_empty()).then(|| s.to_owned())
}

/// Unit normal, or `+z` for a zero, tiny or non-finite one (glTF requires unit normals).
fn unit_normal(n: [f32; 3]) -> Vec3 {
    Vec3::from(n).try_normalize().unwrap_or(Vec3::Z)
}

/// Component-wise bounds of a non-empty point list (`plan` ensures the mesh has a vertex).
fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    points.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        },
    )
}

fn material(color: [f32; 4]) -> json::Material {
    let [r, g, b, a] = color;
    json::Material {
        alpha_mode: Valid(if a < 1.0 {
            json::material::AlphaMode::Blend
        } else {
            json::material::AlphaMode::Opaque
        }),
        double_sided: true,
        name: Some(format!("rgba {r} {g} {b} {a}")),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(color),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(ROUGHNESS),
            ..Default::default()
        },
        ..Default::default()
    }
}

fn accessor_vec3(
    view: json::Index<json::buffer::View>,
    count: usize,
    bounds: Option<([f32; 3], [f32; 3])>,
) -> json::Accessor {
    let value = |v: [f32; 3]| json::Value::from(v.to_vec());
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(
            json::accessor::ComponentType::F32,
        )),
        extensions: None,
        extras: Default::default(),
        type_: Valid(json::accessor::Type::Vec3),
        min: bounds.map(|(lo, _)| value(lo)),
        max: bounds.map(|(_, hi)| value(hi)),
        name: None,
        normalized: false,
        sparse: None,
    }
}

/// Appends little-endian `vec3<f32>` data as a vertex attribute buffer view.
fn push_f32x3(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    data: impl Iterator<Item = impl Into<[f32; 3]>>,
) -> json::Index<json::buffer::View> {
    let start = bin.len();
    for v in data {
        for c in v.into() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    push_view(
        root,
        buffer,
        start,
        bin.len(),
        json::buffer::Target::ArrayBuffer,
    )
}

/// Appends little-endian `u32` indices as an index buffer view.
fn push_u32(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    data: &[u32],
) -> json::Index<json::buffer::View> {
    let start = bin.len();
    for i in data {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    push_view(
        root,
        buffer,
        start,
        bin.len(),
        json::buffer::Target::ElementArrayBuffer,
    )
}

fn push_view(
    root: &mut json::Root,
    buffer: json::Index<json::Buffer>,
    start: usize,
    end: usize,
    target: json::buffer::Target,
) -> json::Index<json::buffer::View> {
    // All data is made of 4-byte values, so every view starts 4-byte aligned.
    debug_assert_eq!(start % 4, 0);
    root.push(json::buffer::View {
        buffer,
        byte_length: USize64::from(end - start),
        byte_offset: Some(USize64::from(start)),
        byte_stride: None,
        name: None,
        target: Some(Valid(target)),
        extensions: None,
        extras: Default::default(),
    })
}

#[cfg(test)]
mod tests;
