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
//! What this module holds: which units a group stands for ([`Unit`]), the finest error at
//! which a group can pay at all ([`switch_error`]), and the choice of drawn units for a view
//! ([`select`]).
//!
//! **The switch rule.** A group is drawn instead of its members exactly where its cut, at the
//! ε the view wants for the group, has no more triangles than its members would draw at the
//! ε each of them is wanted at (each member itself the cheaper of its own cut and its
//! members', bottom-up). Every drawn unit is certified within the ε wanted for it either way,
//! so the rule gives the fewest triangles the forest offers for the errors asked, and never
//! draws a group that costs more than what it replaces — at any mix of errors, not only at
//! one tolerance for all. A tie goes to the group: one unit instead of several, without the
//! fat borders its members would draw along the borders they share.
//!
//! Two earlier rules, and why not: a threshold (drawn from the error on from which the group
//! paid at every coarser error, and its cut within one patch target) kept Spot's group of its
//! 4 patches from being drawn at 0.5 % of the diagonal, 1 546 triangles against the patches'
//! 1 719 (over the 1 500 target), and needed a 12.5 % slack to let the group be drawn at all
//! below 10 %, where it then drew up to 8 % more than its patches. A fixed patch target
//! bounds what one unit uploads and culls, which a renderer drawing groups may still want as
//! a condition of its own; for a cut it only costs triangles.
//!
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

/// The number of triangles of `h`'s cut for `eps` (`MtHierarchy::cut(eps)`'s length, in one
/// pass and without allocating).
pub fn cut_len(h: &MtHierarchy, eps: f64) -> usize {
    let error = |n: u32| h.node_error[n as usize];
    (h.created_by.iter().zip(&h.removed_by))
        .filter(|&(&made, &gone)| error(made) <= eps && (gone == NEVER || error(gone) > eps))
        .count()
}

/// The finest error at which the group whose hierarchy is `group` can pay: the smallest
/// error where its cut has no more triangles than the `members`' cuts together. [`select`]
/// never draws it below (a quick no, and no counting); above, it decides by the cut sizes
/// at the errors the view wants. `f64::INFINITY` when no error pays, and for a group without
/// collapses (its cut is always its members' original triangles: never worth a switch).
pub fn switch_error(group: &MtHierarchy, members: &[&MtHierarchy]) -> f64 {
    if group.is_original() {
        return f64::INFINITY;
    }
    let theirs: Vec<CutSizes> = members.iter().map(|h| CutSizes::of(h)).collect();
    switch_of_sizes(&CutSizes::of(group), &theirs)
}

/// [`switch_error`] from the cut sizes of the group (`own`) and of its members (`theirs`).
fn switch_of_sizes(own: &CutSizes, theirs: &[CutSizes]) -> f64 {
    let mut breaks: Vec<f64> = own.breaks().collect();
    for m in theirs {
        breaks.extend(m.breaks());
    }
    breaks.push(0.0);
    breaks.sort_unstable_by(f64::total_cmp);
    breaks.dedup();
    // Counts are constant between breaks: the first break at which the group pays.
    (breaks.into_iter())
        .find(|&eps| own.at(eps) <= theirs.iter().map(|m| m.at(eps)).sum::<usize>())
        .unwrap_or(f64::INFINITY)
}

/// The links of one group: what it stands for, and below which error it is never drawn.
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

/// The units to draw (appended to `out`) when `eps(unit)` is the error wanted for each unit
/// and `count(unit, eps)` the number of triangles of its cut for `eps` (see the module
/// documentation): bottom-up (members come before their groups), each group's cost is the
/// smaller of its own cut and its members' costs together, the group winning ties and never
/// drawn below its switch error; then from `roots` down, a group that won is drawn, else its
/// members are considered. Every patch under `roots` is covered by exactly one drawn unit.
pub fn select(
    groups: &[GroupLinks],
    roots: &[Unit],
    eps: &mut dyn FnMut(Unit) -> f64,
    count: &mut dyn FnMut(Unit, f64) -> usize,
    out: &mut Vec<Unit>,
) {
    let mut cost = vec![0usize; groups.len()];
    let mut whole = vec![false; groups.len()];
    for (g, links) in groups.iter().enumerate() {
        let theirs: usize = (links.members.iter())
            .map(|&m| match m {
                Unit::Patch(_) => count(m, eps(m)),
                Unit::Group(h) => cost[h as usize],
            })
            .fold(0, usize::saturating_add);
        let u = Unit::Group(g as u32);
        let e = eps(u);
        // Below its switch error the group's cut is larger than its members' at its ε, and
        // they are wanted at no finer ε (a group's bounds hold theirs): a sure no.
        let own = if e >= links.switch_error {
            count(u, e)
        } else {
            usize::MAX
        };
        whole[g] = own <= theirs;
        cost[g] = own.min(theirs);
    }
    let mut stack: Vec<Unit> = roots.iter().rev().copied().collect();
    while let Some(u) = stack.pop() {
        match u {
            Unit::Patch(_) => out.push(u),
            Unit::Group(g) if whole[g as usize] => out.push(u),
            Unit::Group(g) => stack.extend(groups[g as usize].members.iter().rev().copied()),
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

    /// Cut sizes where a group always draws fewer triangles than its members at the same
    /// error: a patch 100 / (1 + ε), a group 90 % of its members'.
    fn cheaper_groups(u: Unit, e: f64) -> usize {
        match u {
            Unit::Patch(_) => (100.0 / (1.0 + e)) as usize,
            Unit::Group(2) => (0.9 * 0.9 * 800.0 / (1.0 + e)) as usize,
            Unit::Group(_) => (0.9 * 400.0 / (1.0 + e)) as usize,
        }
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
            select(&groups, &roots, &mut eps, &mut cheaper_groups, &mut drawn);
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
            select(&groups, &roots, &mut |_| e, &mut cheaper_groups, &mut out);
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
    fn a_group_is_drawn_only_where_it_costs_no_more_than_its_members() {
        // Group 0 = {0..4}: 4 patches of 100 / (1 + ε); the group 300 triangles up to 2, then
        // 90 — more than its patches (80 and less) from 4 on. Its switch error is 1.
        let groups = forest();
        let roots = roots(&groups, 10);
        let mut count = |u: Unit, e: f64| match u {
            Unit::Patch(_) => (100.0 / (1.0 + e)) as usize,
            Unit::Group(0) => [300, 90][usize::from(e >= 2.0)],
            Unit::Group(_) => usize::MAX,
        };
        let mut drawn = |eps: &mut dyn FnMut(Unit) -> f64| {
            let mut out = Vec::new();
            select(&groups, &roots, eps, &mut count, &mut out);
            out.retain(|&u| u == Unit::Group(0) || u < Unit::Patch(4));
            out
        };
        let group = vec![Unit::Group(0)];
        let patches: Vec<Unit> = (0..4).map(Unit::Patch).collect();
        // At one ε for all: 400 vs 300 at 0.5, yet below the switch error; 200 vs 300 at
        // 1; 133 vs 90 at 2; 80 vs 90 at 4.
        assert_eq!(drawn(&mut |_| 0.5), patches);
        assert_eq!(drawn(&mut |_| 1.0), patches);
        assert_eq!(drawn(&mut |_| 2.0), group);
        assert_eq!(drawn(&mut |_| 4.0), patches);
        // The members' own errors count: wanted at 2 for the group but 9 for its patches
        // (40 triangles), the patches are cheaper than the group's 90.
        let mut mixed = |u: Unit| {
            if matches!(u, Unit::Patch(_)) {
                9.0
            } else {
                2.0
            }
        };
        assert_eq!(drawn(&mut mixed), patches);
    }

    #[test]
    fn the_switch_error_is_the_first_error_where_a_group_pays() {
        // Members: 200 triangles at 0, 100 from 1, 50 from 4.
        let members = [sizes(&[(0.0, 200), (1.0, 100), (4.0, 50)])];
        // 160, 60 from 1, and 51 from 4 (one over): pays from 0, whatever comes later.
        let group = sizes(&[(0.0, 160), (1.0, 60), (4.0, 51)]);
        assert_eq!(switch_of_sizes(&group, &members), 0.0);
        // 210 at 0: from 1.
        let later = sizes(&[(0.0, 210), (1.0, 60), (4.0, 51)]);
        assert_eq!(switch_of_sizes(&later, &members), 1.0);
        // Always over: never.
        let over = sizes(&[(0.0, 210), (1.0, 110), (4.0, 51)]);
        assert_eq!(switch_of_sizes(&over, &members), f64::INFINITY);
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
                assert_eq!(cut_len(&h, eps), cut.len(), "eps {eps}");
            }
        }
    }
}
