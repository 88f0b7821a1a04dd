//! glTF files keep what they say: each node with a mesh is a part (for `implode --by parts`,
//! `--only` and export), each primitive's material gives its patches' base colour, and patches
//! never cross a part or a colour.

mod common;

use patchwork::model::PatchSurface;

/// The distinct patch colours of a scene.
fn distinct_colours(s: &patchwork::model::Scene) -> Vec<[u32; 3]> {
    let mut colours: Vec<[u32; 3]> = s
        .patches
        .iter()
        .filter_map(|p| p.color.map(|c| c.map(f32::to_bits)))
        .collect();
    colours.sort();
    colours.dedup();
    colours
}

fn load(name: &str) -> patchwork::model::Scene {
    patchwork::prep::load(&common::root().join("models").join(name)).expect("loads")
}

/// alien.glb: 6 meshes (legs, arms, head, body) → 6 parts and 6 instances, named after their
/// nodes; every patch is in its part's instance and coloured by its material.
#[test]
fn alien_has_its_six_parts_and_colours() {
    let s = load("alien.glb");
    let mut names: Vec<&str> = s.parts.iter().map(|p| p.name.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        vec!["armLeft", "armRight", "body", "head", "legLeft", "legRight"]
    );
    assert_eq!(s.instances.len(), 6);
    for p in &s.patches {
        assert_eq!(p.instance, p.part, "patch {}", p.id);
        assert!(
            p.color.is_some(),
            "patch {} has its material's colour",
            p.id
        );
    }
    // More than one colour: the materials differ.
    let colours = distinct_colours(&s);
    assert!(colours.len() >= 3, "{colours:?}");
    let explosion = patchwork::anim::Explosion::new(&s, patchwork::anim::GroupBy::Parts, 1.0);
    assert_eq!(explosion.groups, 6, "implode --by parts moves 6 groups");
}

/// The cake: every patch lies within one primitive (one colour), and the patches together hold
/// every triangle of the file exactly once.
#[test]
fn cake_patches_stay_within_one_colour() {
    let s = load("cakeBirthday.glb");
    let triangles: usize = s
        .patches
        .iter()
        .map(|p| match &p.surface {
            PatchSurface::Mesh(m) => m.triangles.len(),
            _ => 0,
        })
        .sum();
    assert_eq!(triangles, 1332);
    assert!(s.patches.iter().all(|p| p.color.is_some()));
    // Pink icing and brown cake are different patches: at least as many colours as 3.
    let colours = distinct_colours(&s);
    assert!(colours.len() >= 3, "{colours:?}");
}
