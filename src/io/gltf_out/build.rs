//! The glTF JSON objects and the binary chunk of a validated export ([`super::Plan`]).

use std::collections::{BTreeMap, HashMap};

use glam::Vec3;
use gltf::json;
use json::validation::{Checked::Valid, USize64};

use super::{DEFAULT_COLOR, ExportScene, IDENTITY_MATRIX, Plan, ROUGHNESS};

/// Builds the glTF JSON and the binary chunk for a validated [`Plan`].
pub(super) fn build(scene: &ExportScene, plan: &Plan) -> (json::Root, Vec<u8>) {
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

        // One primitive per colour run, each with its own index view, all sharing the
        // vertices.
        let mut primitives = Vec::new();
        for (range, color) in mesh.primitives() {
            let view = push_u32(&mut root, &mut bin, buffer, &mesh.indices[range.clone()]);
            let indices = root.push(json::Accessor {
                buffer_view: Some(view),
                byte_offset: None,
                count: USize64::from(range.len()),
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
            let color = color.unwrap_or(DEFAULT_COLOR);
            // `+ 0.0` turns -0.0 into 0.0, so that both share a material.
            let key = color.map(|c| (c + 0.0).to_bits());
            let material = *materials
                .entry(key)
                .or_insert_with(|| root.push(material(color)));
            primitives.push(json::mesh::Primitive {
                attributes: attributes.clone(),
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }

        root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: non_empty(&mesh.name),
            primitives,
            weights: None,
        });
    }
    debug_assert_eq!(bin.len() as u64, plan.bin_len);

    // Groups first (their indices are known before their children are pushed), then the
    // nodes; children lists are filled in afterwards.
    let mut roots = Vec::new();
    let mut children: Vec<Vec<json::Index<json::Node>>> = vec![Vec::new(); scene.groups.len()];
    let mut group_index = Vec::with_capacity(scene.groups.len());
    for g in &scene.groups {
        let index = root.push(json::Node {
            name: non_empty(&g.name),
            matrix: (g.matrix != IDENTITY_MATRIX).then_some(g.matrix),
            ..Default::default()
        });
        match g.parent {
            Some(p) => children[p].push(index),
            None => roots.push(index),
        }
        group_index.push(index);
    }
    for &i in &plan.nodes {
        let node = &scene.nodes[i];
        let mesh = plan.mesh_out[node.mesh].map(json::Index::new);
        let index = root.push(json::Node {
            mesh,
            name: non_empty(&node.name),
            matrix: (node.matrix != IDENTITY_MATRIX).then_some(node.matrix),
            ..Default::default()
        });
        match node.parent {
            Some(p) => children[p].push(index),
            None => roots.push(index),
        }
    }
    for (g, kids) in group_index.iter().zip(children) {
        if !kids.is_empty() {
            root.nodes[g.value()].children = Some(kids);
        }
    }
    let nodes = roots;
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
pub(super) fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
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
