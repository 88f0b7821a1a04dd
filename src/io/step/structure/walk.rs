//! The traversal of the representation groups (step 3 of [`super::analyse`]): depth first
//! from a group, multiplying the link transforms, one [`ShellInstance`] per shell and path
//! (a part used twice gives two instances), named by the occurrences along the path. Cycles
//! are cut where they close, depth is capped at [`MAX_DEPTH`], instances at [`MAX_INSTANCES`]
//! and group visits at [`MAX_VISITS`] (so hostile sharing cannot make it exponential); each cut
//! is counted for a warning.

use std::collections::{HashMap, HashSet};

use glam::DMat4;

use super::links::Graph;
use super::{MAX_DEPTH, MAX_INSTANCES, MAX_VISITS, PartInfo, ShellInstance};

#[derive(Debug, Default)]
pub(super) struct Walk {
    pub(super) instances: Vec<ShellInstance>,
    pub(super) parts: Vec<PartInfo>,
    /// Product-less shell → its `shell #id` part.
    pub(super) shell_parts: HashMap<u64, usize>,
    pub(super) visited_groups: HashSet<usize>,
    /// Shells placed from the products (pass 1): not emitted again by later passes.
    pub(super) placed: HashSet<u64>,
    /// Shells skipped because of `placed`.
    pub(super) repeated: usize,
    pub(super) on_path: Vec<usize>,
    pub(super) names: Vec<String>,
    pub(super) cycles: usize,
    pub(super) too_deep: usize,
    pub(super) visits: usize,
    pub(super) truncated: bool,
}

impl Walk {
    pub(super) fn walk(
        &mut self,
        graph: &Graph,
        group: usize,
        transform: DMat4,
        part: Option<usize>,
        depth: usize,
    ) {
        if self.on_path.contains(&group) {
            self.cycles += 1;
            return;
        }
        if depth > MAX_DEPTH {
            self.too_deep += 1;
            return;
        }
        if self.visits >= MAX_VISITS {
            self.truncated = true;
            return;
        }
        self.visits += 1;
        let Some(g) = graph.groups.get(group) else {
            return;
        };
        self.visited_groups.insert(group);
        self.on_path.push(group);

        // The group's part: its first member with a product, else what the caller passed.
        let group_part = g
            .members
            .iter()
            .find_map(|(rep, _)| graph.rep_part.get(rep).copied())
            .or(part);
        let name = self
            .names
            .iter()
            .filter(|n| !n.is_empty())
            .cloned()
            .collect::<Vec<_>>()
            .join("/");
        for (rep, shells) in &g.members {
            let rep_part = graph.rep_part.get(rep).copied().or(group_part);
            for &(shell, solid) in shells {
                if self.placed.contains(&shell) {
                    self.repeated += 1;
                    continue;
                }
                if self.instances.len() >= MAX_INSTANCES {
                    self.truncated = true;
                    break;
                }
                let part = match rep_part {
                    Some(p) => p,
                    None => self.shell_part(shell),
                };
                self.instances.push(ShellInstance {
                    shell,
                    solid,
                    representation: Some(*rep),
                    transform,
                    part,
                    instance_name: name.clone(),
                });
            }
        }
        for link in &g.links {
            if self.truncated {
                break;
            }
            self.names.push(link.name.clone());
            self.walk(
                graph,
                link.child,
                transform * link.transform,
                link.part.or(group_part),
                depth + 1,
            );
            self.names.pop();
        }
        self.on_path.pop();
    }

    /// The `shell #id` part of a shell that belongs to no product.
    pub(super) fn shell_part(&mut self, shell: u64) -> usize {
        let next = self.parts.len();
        let index = *self.shell_parts.entry(shell).or_insert(next);
        if index == next {
            self.parts.push(PartInfo {
                name: format!("shell #{shell}"),
                product_definition: None,
            });
        }
        index
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::step;
    use super::*;

    #[test]
    fn cycles_terminate_with_a_warning() {
        // #10 maps #20, #20 maps #10, and a transform relation #20 → #10 too.
        let s = step(
            "#1=CARTESIAN_POINT('',(0.,0.,0.));#2=CARTESIAN_POINT('',(1.,0.,0.));\
             #3=AXIS2_PLACEMENT_3D('',#1,$,$);#4=AXIS2_PLACEMENT_3D('',#2,$,$);\
             #10=SHAPE_REPRESENTATION('',(#11,#12),$);#11=MANIFOLD_SOLID_BREP('',#13);\
             #13=CLOSED_SHELL('',());#12=MAPPED_ITEM('',#14,#4);#14=REPRESENTATION_MAP(#3,#20);\
             #20=SHAPE_REPRESENTATION('',(#21,#22),$);#21=MANIFOLD_SOLID_BREP('',#23);\
             #23=CLOSED_SHELL('',());#22=MAPPED_ITEM('',#24,#4);#24=REPRESENTATION_MAP(#3,#10);\
             #30=(REPRESENTATION_RELATIONSHIP('','',#10,#20)\
                  REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#31)\
                  SHAPE_REPRESENTATION_RELATIONSHIP());\
             #31=ITEM_DEFINED_TRANSFORMATION('','',#3,#4);",
        );
        assert!(!s.instances.is_empty());
        for shell in [13, 23] {
            assert!(s.instances.iter().any(|i| i.shell == shell));
        }
        assert!(s.instances.len() <= 4, "{}", s.instances.len());
        assert!(
            s.warnings.iter().any(|w| w.contains("cycles")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn exponential_sharing_is_capped() {
        // Each level maps the next one twice: 2^70 paths, cut by depth and instance limits.
        let mut data = String::from(
            "#1=CARTESIAN_POINT('',(0.,0.,0.));#2=AXIS2_PLACEMENT_3D('',#1,$,$);\
             #3=CLOSED_SHELL('',());",
        );
        for level in 0..70u64 {
            let rep = 1000 + 10 * level;
            let next = rep + 10;
            if level == 69 {
                data += &format!("#{rep}=SHAPE_REPRESENTATION('',(#3),$);");
            } else {
                data += &format!(
                    "#{rep}=SHAPE_REPRESENTATION('',(#{a},#{b}),$);\
                     #{a}=MAPPED_ITEM('',#{m},#2);#{b}=MAPPED_ITEM('',#{m},#2);\
                     #{m}=REPRESENTATION_MAP(#2,#{next});",
                    a = rep + 1,
                    b = rep + 2,
                    m = rep + 3
                );
            }
        }
        let start = std::time::Instant::now();
        let s = step(&data);
        assert!(start.elapsed().as_secs() < 30);
        assert!(!s.instances.is_empty() && s.instances.len() <= MAX_INSTANCES);
        assert!(!s.warnings.is_empty());
    }
}
