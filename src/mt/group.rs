//! Coarse groups of mesh patches (issue 30): a level above the patches, as meshoptimizer's
//! clusterlod (`demo/clusterlod.h`) and Nanite group clusters, but **without border
//! locking** — fat borders (the `balazs-fat-borders` paper) cover the gap between any two
//! adjacent drawn units simplified independently, each drawing its own fat border at its own
//! error, so a group and a neighbouring member patch of another group may be drawn side by
//! side at different levels.
//!
//! A group has its own MT hierarchy (Holst and Schumann, `holst-reduced-mt-hierarchy`) built
//! from the *original* triangles of its members, so its node errors are certified against
//! the original surface by the same bounds as a patch's (`bound`): no error composition.
//! What this module holds is level-independent: which units a group stands for ([`Unit`]),
//! the error from which a group pays ([`switch_error`]: its cut is no larger than one patch's
//! target and no larger than its members' cuts together, at that error and every coarser
//! one), and the choice of drawn units for a view ([`select`]): top-down, a group is drawn
//! instead of its members when the ε the view wants for it is at least its switch error.
//! The groups form a forest over the patches, so every patch is drawn exactly once, by itself
//! or by one group holding it — never both, never neither.
//!
//! Not done here: grouping (which patches form a group: `prep::groups`) and drawing.

use super::{MtHierarchy, NEVER};

/// A drawable unit of a grouped mesh: a patch (its id) or a group (its index in the scene's
/// groups; members of a group always come before it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Unit {
    Patch(u32),
    Group(u32),
}

/// The triangle count of every cut of a hierarchy, by error: the creators' and the
/// removers' errors, sorted (a triangle is in the cut for ε when its creator's error is ≤ ε
/// and its remover's is not).
#[derive(Clone, Debug, Default)]
pub struct CutSizes {
    made: Vec<f64>,
    gone: Vec<f64>,
}

impl CutSizes {
    pub fn of(h: &MtHierarchy) -> CutSizes {
        let error = |n: u32| h.node_error[n as usize];
        let mut made: Vec<f64> = h.created_by.iter().map(|&n| error(n)).collect();
        let mut gone: Vec<f64> = (h.removed_by.iter())
            .filter(|&&n| n != NEVER)
            .map(|&n| error(n))
            .collect();
        made.sort_unstable_by(f64::total_cmp);
        gone.sort_unstable_by(f64::total_cmp);
        CutSizes { made, gone }
    }

    /// Triangles of the cut for `eps` (= `MtHierarchy::cut(eps)`'s length: errors are
    /// monotone, so a triangle removed at ε was also created at ε).
    pub fn at(&self, eps: f64) -> usize {
        let made = self.made.partition_point(|&e| e <= eps);
        let gone = self.gone.partition_point(|&e| e <= eps);
        made - gone
    }

    /// Every error at which the count may change.
    fn breaks(&self) -> impl Iterator<Item = f64> + '_ {
        self.made.iter().chain(&self.gone).copied()
    }
}

/// How much larger than its members' cuts together a group's cut may be and still pay:
/// drawing one unit instead of several also saves the fat borders the members draw along
/// the borders they share, and a culling test per member. Without it one triangle more at
/// one coarse error kept a group from ever being drawn below it (`models/spot.obj`: the
/// group of its 4 patches paid from 10.7 % of the diagonal on instead of from 0.8 %).
pub const SWITCH_SLACK: f64 = 0.125;

/// The smallest error from which the group whose hierarchy is `group` pays: at it and at
/// every coarser error (every error where a cut changes) the group's cut has at most
/// `target` triangles (about one patch, so a drawn group costs no more than a patch to cull
/// and upload) and no more than the `members`' cuts together, give or take
/// [`SWITCH_SLACK`]. `f64::INFINITY` when no error does (a group without collapses never
/// pays).
pub fn switch_error(group: &MtHierarchy, members: &[&MtHierarchy], target: usize) -> f64 {
    if group.is_original() {
        return f64::INFINITY;
    }
    let theirs: Vec<CutSizes> = members.iter().map(|h| CutSizes::of(h)).collect();
    switch_of_sizes(&CutSizes::of(group), &theirs, target)
}

/// [`switch_error`] from the cut sizes of the group (`own`) and of its members (`theirs`).
fn switch_of_sizes(own: &CutSizes, theirs: &[CutSizes], target: usize) -> f64 {
    let mut breaks: Vec<f64> = own.breaks().collect();
    for m in theirs {
        breaks.extend(m.breaks());
    }
    breaks.push(0.0);
    breaks.sort_unstable_by(f64::total_cmp);
    breaks.dedup();
    let pays = |eps: f64| {
        let n = own.at(eps);
        let members = theirs.iter().map(|m| m.at(eps)).sum::<usize>() as f64;
        n <= target && n as f64 <= members * (1.0 + SWITCH_SLACK)
    };
    // Counts are constant between breaks: scanning them from the coarsest down, the last
    // one from which every coarser break pays.
    let mut from = f64::INFINITY;
    for &eps in breaks.iter().rev() {
        if !pays(eps) {
            break;
        }
        from = eps;
    }
    from
}

/// The links of one group: what it stands for and from which error it is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupLinks {
    pub members: Vec<Unit>,
    pub switch_error: f64,
}

/// The units no group holds (patches `0..patch_count` and groups of `groups`), in order:
/// where [`select`] starts.
pub fn roots(groups: &[GroupLinks], patch_count: usize) -> Vec<Unit> {
    let mut held_patch = vec![false; patch_count];
    let mut held_group = vec![false; groups.len()];
    for g in groups {
        for &m in &g.members {
            match m {
                Unit::Patch(p) => held_patch[p as usize] = true,
                Unit::Group(h) => held_group[h as usize] = true,
            }
        }
    }
    let patches = (0..patch_count as u32).filter(|&p| !held_patch[p as usize]);
    let groups = (0..groups.len() as u32).filter(|&g| !held_group[g as usize]);
    patches
        .map(Unit::Patch)
        .chain(groups.map(Unit::Group))
        .collect()
}

/// The units to draw (appended to `out`): from `roots` down, a group whose wanted error
/// `eps(unit)` is at least its switch error is drawn, else its members are considered.
/// Every patch under `roots` is covered by exactly one drawn unit.
pub fn select(
    groups: &[GroupLinks],
    roots: &[Unit],
    eps: &mut dyn FnMut(Unit) -> f64,
    out: &mut Vec<Unit>,
) {
    let mut stack: Vec<Unit> = roots.iter().rev().copied().collect();
    while let Some(u) = stack.pop() {
        match u {
            Unit::Patch(_) => out.push(u),
            Unit::Group(g) => {
                let links = &groups[g as usize];
                if eps(u) >= links.switch_error {
                    out.push(u);
                } else {
                    stack.extend(links.members.iter().rev().copied());
                }
            }
        }
    }
}

/// The patches `unit` stands for, appended to `out`.
pub fn patches_of(groups: &[GroupLinks], unit: Unit, out: &mut Vec<u32>) {
    match unit {
        Unit::Patch(p) => out.push(p),
        Unit::Group(g) => {
            for &m in &groups[g as usize].members {
                patches_of(groups, m, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two levels over 10 patches: groups 0 = {0..4}, 1 = {4..8}, 2 = {g0, g1}; 8 and 9 alone.
    fn forest() -> Vec<GroupLinks> {
        let g = |members: Vec<Unit>, switch_error| GroupLinks {
            members,
            switch_error,
        };
        vec![
            g((0..4).map(Unit::Patch).collect(), 1.0),
            g((4..8).map(Unit::Patch).collect(), 2.0),
            g(vec![Unit::Group(0), Unit::Group(1)], 4.0),
        ]
    }

    #[test]
    fn roots_are_the_units_no_group_holds() {
        let roots = roots(&forest(), 10);
        assert_eq!(roots, vec![Unit::Patch(8), Unit::Patch(9), Unit::Group(2)]);
    }

    #[test]
    fn every_patch_is_drawn_exactly_once_at_any_mix_of_errors() {
        let groups = forest();
        let roots = roots(&groups, 10);
        // Wanted errors per group from a small pseudo-random sequence: every mix of levels.
        let mut seed = 7u64;
        let mut mixes = std::collections::HashSet::new();
        for _ in 0..400 {
            let mut eps = |_: Unit| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 33) as f64 / (1u64 << 31) as f64 * 5.0
            };
            let mut drawn = Vec::new();
            select(&groups, &roots, &mut eps, &mut drawn);
            let mut patches = Vec::new();
            for &u in &drawn {
                patches_of(&groups, u, &mut patches);
            }
            patches.sort_unstable();
            assert_eq!(patches, (0..10).collect::<Vec<u32>>(), "drawn {drawn:?}");
            drawn.sort_unstable();
            mixes.insert(drawn);
        }
        // Top group; both groups; one group and the other's patches; all patches.
        assert!(mixes.len() >= 4, "{mixes:?}");
    }

    #[test]
    fn a_group_is_drawn_from_its_switch_error_on() {
        let groups = forest();
        let roots = roots(&groups, 10);
        let drawn = |e: f64| {
            let mut out = Vec::new();
            select(&groups, &roots, &mut |_| e, &mut out);
            out
        };
        assert_eq!(drawn(4.0).len(), 3);
        assert_eq!(drawn(2.0).len(), 4);
        assert_eq!(drawn(1.0).len(), 2 + 1 + 4);
        assert_eq!(drawn(0.5).len(), 10);
    }

    /// Cut sizes from (error, count) steps: the count is `count` from `error` on (steps
    /// from the finest error, counts falling).
    fn sizes(steps: &[(f64, usize)]) -> CutSizes {
        // `count` triangles made at 0, the surplus of each step gone at its error.
        let start = steps[0].1;
        let mut gone = Vec::new();
        for w in steps.windows(2) {
            gone.extend(std::iter::repeat_n(w[1].0, w[0].1 - w[1].1));
        }
        CutSizes {
            made: vec![0.0; start],
            gone,
        }
    }

    #[test]
    fn a_group_one_triangle_over_its_members_at_a_coarse_error_still_pays() {
        // Members: 200 triangles at 0, 100 from 1, 50 from 4. The group: 160, 60 from 1,
        // and 51 from 4 — one over its members there.
        let members = [sizes(&[(0.0, 200), (1.0, 100), (4.0, 50)])];
        let group = sizes(&[(0.0, 160), (1.0, 60), (4.0, 51)]);
        assert_eq!((group.at(4.0), members[0].at(4.0)), (51, 50));
        assert_eq!(switch_of_sizes(&group, &members, 1000), 0.0);
        // Under the patch target only from 1 on.
        assert_eq!(switch_of_sizes(&group, &members, 100), 1.0);
        // Far over its members (a quarter more) from 4 on: never pays.
        let fewer = [sizes(&[(0.0, 200), (1.0, 100), (4.0, 40)])];
        assert_eq!(switch_of_sizes(&group, &fewer, 1000), f64::INFINITY);
    }

    #[test]
    fn cut_sizes_count_the_cuts() {
        let m = super::super::fixtures::bumpy(12);
        let mut h = MtHierarchy::build(&m.positions, &m.triangles);
        h.reduce_within(5.0, super::super::MAX_MERGE_ERROR_RATIO);
        let sizes = CutSizes::of(&h);
        let mut cut = Vec::new();
        for &e in h.node_error.iter().chain(&[0.0, 1e9]) {
            for eps in [e, e * 0.999, e * 1.001] {
                h.cut(eps, &mut cut);
                assert_eq!(sizes.at(eps), cut.len(), "eps {eps}");
            }
        }
    }
}
