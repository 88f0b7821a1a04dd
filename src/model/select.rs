//! Choosing parts of an assembly by name: what `--only` and `--hide` keep.
//!
//! A pattern names instances ([`Scene::instances`]) by their part's name, by their
//! occurrence path (`l-bracket-assembly_1/nut-bolt-assembly_2/bolt_1`) or by any leading part
//! of that path (`l-bracket-assembly_1` names everything below it), or by `#N`, the
//! instance's index in `stats --parts`. `*` matches any run of characters and `?` one
//! character; matching is case-sensitive, as CAD names are.

use super::{Instance, Scene, Sphere};

/// Whether `pattern` (with `*` and `?`) matches the whole of `text`.
pub(crate) fn glob(pattern: &str, text: &str) -> bool {
    let (p, t): (Vec<char>, Vec<char>) = (pattern.chars().collect(), text.chars().collect());
    // Iterative matching with one backtrack point for the last `*`.
    let (mut i, mut j) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while j < t.len() {
        if i < p.len() && (p[i] == '?' || p[i] == t[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some((i, j));
            i += 1;
        } else if let Some((si, sj)) = star {
            i = si + 1;
            j = sj + 1;
            star = Some((si, sj + 1));
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// Whether `pattern` names instance `index` of `scene`.
pub fn names(scene: &Scene, index: usize, inst: &Instance, pattern: &str) -> bool {
    if let Some(n) = pattern.strip_prefix('#') {
        return n.parse::<usize>().is_ok_and(|n| n == index);
    }
    let part = scene
        .parts
        .get(inst.part as usize)
        .map_or("", |p| p.name.as_str());
    if !part.is_empty() && glob(pattern, part) {
        return true;
    }
    // The path and each of its leading parts.
    let mut end = 0;
    for (k, segment) in inst.name.split('/').enumerate() {
        end += segment.len() + usize::from(k > 0);
        if !inst.name.is_empty() && glob(pattern, &inst.name[..end]) {
            return true;
        }
    }
    false
}

impl Scene {
    /// The scene with only the patches of the instances `keep` is true for, renumbered, its
    /// bounds those of what is left (`None` when nothing is left). Instances and parts are kept
    /// as they are, so their indices still hold.
    pub fn with_instances(&self, keep: &[bool]) -> Option<Scene> {
        let mut patches: Vec<_> = self
            .patches
            .iter()
            .filter(|p| keep.get(p.instance as usize).copied().unwrap_or(false))
            .cloned()
            .collect();
        if patches.is_empty() {
            return None;
        }
        for (i, p) in patches.iter_mut().enumerate() {
            p.id = i as u32;
        }
        let spheres: Vec<Sphere> = patches.iter().map(|p| p.bounds).collect();
        let bbox = super::box_of(patches.iter().flat_map(|p| {
            let r = glam::DVec3::splat(p.bounds.radius);
            [p.bounds.center - r, p.bounds.center + r]
        }))
        .unwrap_or_default();
        Some(Scene {
            bounds: Sphere::union(&spheres),
            // The kept patches' boxes within the whole model's.
            bbox: (bbox.0.max(self.bbox.0), bbox.1.min(self.bbox.1)),
            patches,
            ..self.clone_without_patches()
        })
    }

    fn clone_without_patches(&self) -> Scene {
        Scene {
            patches: Vec::new(),
            up: self.up,
            bounds: self.bounds,
            bbox: self.bbox,
            parts: self.parts.clone(),
            instances: self.instances.clone(),
            skipped: self.skipped.clone(),
            warnings: self.warnings.clone(),
            unit: self.unit,
            // Groups name patches by their old numbers: dropped (the patches draw alone).
            mesh_groups: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Part, UpAxis};
    use glam::DMat4;

    #[test]
    fn glob_matches_stars_and_marks() {
        assert!(glob("nut", "nut"));
        assert!(!glob("nut", "nut_1"));
        assert!(glob("nut*", "nut_1"));
        assert!(glob("*bolt*", "nut-bolt-assembly_2"));
        assert!(glob("b?lt", "bolt"));
        assert!(glob("*", ""));
        assert!(!glob("?", ""));
        assert!(glob("a*b*c", "aXbYbZc"));
        assert!(!glob("a*b*c", "aXbYbZ"));
    }

    fn scene() -> Scene {
        let mut s = Scene::from_bezier(Vec::new(), UpAxis::Z);
        s.parts = vec![Part { name: "nut".into() }, Part { name: "rod".into() }];
        let inst = |name: &str, part| Instance {
            name: name.into(),
            part,
            transform: DMat4::IDENTITY,
            shell: None,
        };
        s.instances = vec![
            inst("rod-assembly_1/nut_1", 0),
            inst("rod-assembly_1/rod_1", 1),
            inst("bracket_1/nut_3", 0),
        ];
        s
    }

    #[test]
    fn patterns_name_parts_paths_and_indices() {
        let s = scene();
        let hits = |pattern: &str| -> Vec<usize> {
            (s.instances.iter().enumerate())
                .filter(|(i, inst)| names(&s, *i, inst, pattern))
                .map(|(i, _)| i)
                .collect()
        };
        assert_eq!(hits("nut"), vec![0, 2], "by part name");
        assert_eq!(hits("rod-assembly_1"), vec![0, 1], "by a leading path");
        assert_eq!(hits("rod-assembly_1/rod_1"), vec![1], "by the whole path");
        assert_eq!(
            hits("rod-assembly"),
            Vec::<usize>::new(),
            "whole segments only"
        );
        assert_eq!(hits("*nut_?"), vec![0, 2]);
        assert_eq!(hits("#2"), vec![2]);
        assert_eq!(hits("#x"), Vec::<usize>::new());
    }
}
