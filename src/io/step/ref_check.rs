//! The reference graph of a STEP file checked on our own scan ([`super::p21`]) before
//! truck-stepio sees it (issue 21): truck resolves an entity's references recursively
//! (`get_owned` → `into_owned` → `get_owned` …), so a reference cycle (`#1=SURFACE_CURVE('',#1,…)`)
//! or a chain of thousands of nested curves overflows the stack — an abort no `catch_unwind`
//! can turn into an error.
//!
//! Every entity gets its height: the longest chain of references below it (an entity that
//! references nothing has height 0). One depth-first pass computes it without recursion; an
//! entity that reaches a cycle (a reference back to an entity still on the path) has no
//! height. Such entities, and those higher than [`MAX_REFERENCE_HEIGHT`], are refused: not
//! given to truck, so the faces using them are skipped with the reason.
//!
//! Real files are shallow: a B-spline face's longest chain (face → bound → loop → oriented
//! edge → edge curve → surface curve → pcurve → definitional representation → curve → point)
//! is about 10, and the public corpus' tallest entity is below 20.

use std::collections::{BTreeMap, HashMap};

use super::p21::{P21File, Param};

/// The tallest reference chain given to truck. At about 1 KiB of stack per level of truck's
/// resolution, this stays far inside a 2 MiB worker thread's stack.
pub(crate) const MAX_REFERENCE_HEIGHT: usize = 64;

/// Refused entities: id → reason (a cycle, or the height and the limit).
pub fn refused(file: &P21File) -> BTreeMap<u64, String> {
    let heights = heights(file);
    let mut out = BTreeMap::new();
    for e in &file.entities {
        match heights.get(&e.id) {
            Some(Height::Cyclic(at)) => {
                out.insert(
                    e.id,
                    format!("its references run in a cycle (through #{at})"),
                );
            }
            Some(Height::Finite(h)) if *h > MAX_REFERENCE_HEIGHT => {
                out.insert(
                    e.id,
                    format!("its references nest {h} deep (the limit is {MAX_REFERENCE_HEIGHT})"),
                );
            }
            _ => {}
        }
    }
    out
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Height {
    /// On the current path (grey).
    Open,
    Finite(usize),
    /// Reaches a cycle, closed by a reference to this entity.
    Cyclic(u64),
}

/// Every entity's height, by an iterative depth-first search. References to ids the file
/// does not define are ignored (truck fails to look them up, which is an error, not a loop).
fn heights(file: &P21File) -> HashMap<u64, Height> {
    let mut height: HashMap<u64, Height> = HashMap::with_capacity(file.entities.len());
    // The path: (entity, its references, next reference to visit, its height so far).
    let mut stack: Vec<(u64, Vec<u64>, usize, Height)> = Vec::new();
    for root in &file.entities {
        if height.contains_key(&root.id) {
            continue;
        }
        height.insert(root.id, Height::Open);
        stack.push((root.id, references(file, root.id), 0, Height::Finite(0)));
        while let Some(top) = stack.last_mut() {
            if let Some(&child) = top.1.get(top.2) {
                top.2 += 1;
                match height.get(&child) {
                    Some(&h) => top.3 = join(top.3, h, child),
                    None if file.get(child).is_some() => {
                        height.insert(child, Height::Open);
                        stack.push((child, references(file, child), 0, Height::Finite(0)));
                    }
                    None => {}
                }
                continue;
            }
            let (id, h) = (top.0, top.3);
            stack.pop();
            height.insert(id, h);
            if let Some(parent) = stack.last_mut() {
                parent.3 = join(parent.3, h, id);
            }
        }
    }
    height
}

/// A parent's height so far after meeting `child` of height `h`: a child still on the path
/// closes a cycle.
fn join(acc: Height, h: Height, child: u64) -> Height {
    match (acc, h) {
        (Height::Cyclic(_), _) => acc,
        (_, Height::Open) => Height::Cyclic(child),
        (_, Height::Cyclic(at)) => Height::Cyclic(at),
        (Height::Finite(a), Height::Finite(c)) => Height::Finite(a.max(c + 1)),
        // (A height so far starts finite; never reached.)
        (Height::Open, Height::Finite(c)) => Height::Finite(c + 1),
    }
}

/// Every reference in the entity's records, in order (lists and typed values included).
fn references(file: &P21File, id: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let mut todo: Vec<&Param> = Vec::new();
    if let Some(e) = file.get(id) {
        for r in &e.parts {
            todo.extend(r.args.iter().rev());
        }
    }
    while let Some(p) = todo.pop() {
        match p {
            Param::Ref(r) => out.push(*r),
            Param::List(items) => todo.extend(items.iter().rev()),
            Param::Typed(_, inner) => todo.push(inner),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused_of(data: &str) -> BTreeMap<u64, String> {
        let text = super::super::p21::fixtures::wrap(data);
        refused(&super::super::p21::parse(&text).expect("parses"))
    }

    fn chain(n: u64) -> String {
        let mut s = String::new();
        for i in 1..n {
            s += &format!(
                "#{i}=SURFACE_CURVE('',#{},(#{}),.CURVE_3D.);\n",
                i + 1,
                i + 1
            );
        }
        s + &format!("#{n}=CARTESIAN_POINT('',(0.,0.,0.));")
    }

    #[test]
    fn cycles_and_everything_above_them_are_refused() {
        let r = refused_of(
            "#1=ADVANCED_FACE('',(#2),#9,.T.);\n#2=FACE_BOUND('',#3,.T.);\n\
             #3=SURFACE_CURVE('',#4,(#3),.CURVE_3D.);\n#4=LINE('',#5,#6);\n\
             #5=CARTESIAN_POINT('',(0.,0.,0.));\n#6=VECTOR('',#7,1.);\n\
             #7=DIRECTION('',(1.,0.,0.));\n#9=PLANE('',#10);\n#10=AXIS2_PLACEMENT_3D('',#5,$,$);\n\
             #20=TRIMMED_CURVE('',#21,(),(),.T.,.PARAMETER.);\n#21=TRIMMED_CURVE('',#20,(),(),.T.,.PARAMETER.);",
        );
        let ids: Vec<u64> = r.keys().copied().collect();
        assert_eq!(ids, [1, 2, 3, 20, 21], "{r:?}");
        assert!(r[&1].contains("cycle (through #3)"), "{r:?}");
        assert!(r[&20].contains("cycle (through #20)"), "{r:?}");
    }

    #[test]
    fn heights_count_the_longest_chain_and_stop_at_the_limit() {
        let limit = MAX_REFERENCE_HEIGHT as u64;
        // Entity 1 of a chain of n has height n − 1.
        assert!(refused_of(&chain(limit + 1)).is_empty());
        let r = refused_of(&chain(limit + 2));
        assert_eq!(r.keys().copied().collect::<Vec<_>>(), [1], "{r:?}");
        assert!(r[&1].contains(&format!("nest {} deep", limit + 1)), "{r:?}");
        // A long chain is walked without recursion: 100 000 deep, everything above the limit.
        assert_eq!(
            refused_of(&chain(100_000)).len(),
            100_000 - limit as usize - 1
        );
    }

    #[test]
    fn shared_entities_and_missing_references_are_not_cycles() {
        // A diamond (two paths to #4) and a reference to an undefined #99.
        let r = refused_of(
            "#1=A(#2,#3);\n#2=B(#4);\n#3=C((#4,#99));\n#4=CARTESIAN_POINT('',(0.,0.,0.));",
        );
        assert!(r.is_empty(), "{r:?}");
    }
}
