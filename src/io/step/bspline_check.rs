//! B-spline entities checked on our own scan ([`super::p21`]) before truck-stepio sees them
//! (issue 21): truck-geometry expands knot multiplicities eagerly (a multiplicity of 10⁹
//! allocates gigabytes and ends in the OOM killer), and ruststep panics when an enumeration
//! such as `.F.` stands where a control point's reference is expected.
//!
//! A B-spline curve or surface (simple `B_SPLINE_CURVE_WITH_KNOTS` /
//! `B_SPLINE_SURFACE_WITH_KNOTS`, or the complex `B_SPLINE_CURVE(…) B_SPLINE_CURVE_WITH_KNOTS(…)`
//! forms, rational or not) is refused unless, per direction (ISO 10303-42, 4.3.4.3):
//! every control point is an entity reference; the degree p is ≥ 1 and < the number of
//! control points n; the multiplicities and knots lists have the same length; every
//! multiplicity is ≥ 1; and the multiplicities sum to exactly n + p + 1. The expanded knot
//! vector is then at most 2n long: bounded by the file's size, whatever the numbers say.
//! A refused entity is not given to truck; faces that use it are skipped with its reason.

use std::collections::BTreeMap;

use super::p21::{Entity, P21File, Param, Record};

/// Refused B-spline entities: id → reason (naming the rule).
pub fn refused(file: &P21File) -> BTreeMap<u64, String> {
    let mut out = BTreeMap::new();
    for e in &file.entities {
        if let Some(Err(reason)) = check(e) {
            out.insert(e.id, reason);
        }
    }
    out
}

/// `None` when `e` is no B-spline with knots, else whether it passes.
fn check(e: &Entity) -> Option<Result<(), String>> {
    if let Some(r) = e.part("B_SPLINE_CURVE_WITH_KNOTS") {
        return Some(if e.is_complex() {
            // B_SPLINE_CURVE(degree, points, form, closed, self_intersect) +
            // B_SPLINE_CURVE_WITH_KNOTS(multiplicities, knots, spec).
            let Some(base) = e.part("B_SPLINE_CURVE") else {
                return Some(Err(
                    "B_SPLINE_CURVE_WITH_KNOTS without B_SPLINE_CURVE".into()
                ));
            };
            curve(base.arg(0), base.arg(1), r.arg(0), r.arg(1))
        } else {
            // (name, degree, points, form, closed, self_intersect, multiplicities, knots, spec)
            curve(r.arg(1), r.arg(2), r.arg(6), r.arg(7))
        });
    }
    if let Some(r) = e.part("B_SPLINE_SURFACE_WITH_KNOTS") {
        return Some(if e.is_complex() {
            // B_SPLINE_SURFACE(u_degree, v_degree, points, form, u_closed, v_closed, self_int) +
            // B_SPLINE_SURFACE_WITH_KNOTS(u_mults, v_mults, u_knots, v_knots, spec).
            let Some(base) = e.part("B_SPLINE_SURFACE") else {
                return Some(Err(
                    "B_SPLINE_SURFACE_WITH_KNOTS without B_SPLINE_SURFACE".into()
                ));
            };
            surface(base, 0, r, 0)
        } else {
            // (name, u_degree, v_degree, points, form, u_closed, v_closed, self_int,
            //  u_mults, v_mults, u_knots, v_knots, spec)
            surface(r, 1, r, 8)
        });
    }
    None
}

fn curve(
    degree: Option<&Param>,
    points: Option<&Param>,
    mults: Option<&Param>,
    knots: Option<&Param>,
) -> Result<(), String> {
    let points = points
        .and_then(Param::as_list)
        .ok_or("the control points are not a list")?;
    refs_only(points)?;
    direction("", degree, points.len(), mults, knots)
}

/// `base` holds degrees at `b`, `b + 1` and the point grid at `b + 2`; `knots` holds the
/// u and v multiplicities at `k`, `k + 1` and the knots at `k + 2`, `k + 3`.
fn surface(base: &Record, b: usize, knots: &Record, k: usize) -> Result<(), String> {
    let rows = base
        .arg(b + 2)
        .and_then(Param::as_list)
        .ok_or("the control points are not a list of lists")?;
    let mut columns = None;
    for row in rows {
        let row = row.as_list().ok_or("a control point row is not a list")?;
        refs_only(row)?;
        if *columns.get_or_insert(row.len()) != row.len() {
            return Err("control point rows of different lengths".into());
        }
    }
    let columns = columns.unwrap_or(0);
    direction(
        "u ",
        base.arg(b),
        rows.len(),
        knots.arg(k),
        knots.arg(k + 2),
    )?;
    direction(
        "v ",
        base.arg(b + 1),
        columns,
        knots.arg(k + 1),
        knots.arg(k + 3),
    )
}

fn refs_only(points: &[Param]) -> Result<(), String> {
    match points.iter().position(|p| p.as_ref().is_none()) {
        Some(i) => Err(format!(
            "control point {i} is not an entity reference ({:?})",
            points[i]
        )),
        None => Ok(()),
    }
}

/// One parameter direction: degree p, n control points, multiplicities and knots.
fn direction(
    dir: &str,
    degree: Option<&Param>,
    n: usize,
    mults: Option<&Param>,
    knots: Option<&Param>,
) -> Result<(), String> {
    let p = match degree {
        Some(Param::Int(p)) if *p >= 1 && (*p as u64) < n as u64 => *p as u64,
        _ => {
            return Err(format!(
                "{dir}degree {degree:?} is not between 1 and the {n} control points − 1"
            ));
        }
    };
    let mults = mults
        .and_then(Param::as_list)
        .ok_or_else(|| format!("{dir}knot multiplicities are not a list"))?;
    let knots = knots
        .and_then(Param::as_list)
        .ok_or_else(|| format!("{dir}knots are not a list"))?;
    if mults.len() != knots.len() {
        return Err(format!(
            "{} {dir}knot multiplicities for {} knots",
            mults.len(),
            knots.len()
        ));
    }
    let expected = n as u64 + p + 1;
    let mut sum: u64 = 0;
    for m in mults {
        match m {
            Param::Int(m) if *m >= 1 => sum = sum.saturating_add(*m as u64),
            _ => return Err(format!("{dir}knot multiplicity {m:?} is not ≥ 1")),
        }
    }
    if sum != expected {
        return Err(format!(
            "{dir}knot multiplicities sum to {sum}, not control points + degree + 1 = {expected} (the limit on the expanded knot vector)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused_of(data: &str) -> BTreeMap<u64, String> {
        let text = super::super::p21::fixtures::wrap(data);
        refused(&super::super::p21::parse(&text).expect("parses"))
    }

    #[test]
    fn valid_curves_and_surfaces_pass_and_each_rule_refuses() {
        let ok = "#1=B_SPLINE_CURVE_WITH_KNOTS('',2,(#5,#6,#7),.UNSPECIFIED.,.F.,.F.,(3,3),(0.,1.),.UNSPECIFIED.);\n\
                  #2=(BOUNDED_CURVE()B_SPLINE_CURVE(1,(#5,#6),.UNSPECIFIED.,.F.,.F.)B_SPLINE_CURVE_WITH_KNOTS((2,2),(0.,1.),.UNSPECIFIED.)CURVE()GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_CURVE((1.,1.))REPRESENTATION_ITEM(''));\n\
                  #3=B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#5,#6),(#7,#8)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);";
        assert!(refused_of(ok).is_empty(), "{:?}", refused_of(ok));
        for (bad, needle) in [
            (
                "#1=B_SPLINE_CURVE_WITH_KNOTS('',2,(#5,#6,#7),.UNSPECIFIED.,.F.,.F.,(1000000000,3),(0.,1.),.UNSPECIFIED.);",
                "sum to 1000000003",
            ),
            (
                "#1=B_SPLINE_CURVE_WITH_KNOTS('',2,(.F.,#6,#7),.UNSPECIFIED.,.F.,.F.,(3,3),(0.,1.),.UNSPECIFIED.);",
                "control point 0",
            ),
            (
                "#1=B_SPLINE_CURVE_WITH_KNOTS('',3,(#5,#6,#7),.UNSPECIFIED.,.F.,.F.,(4,3),(0.,1.),.UNSPECIFIED.);",
                "degree",
            ),
            (
                "#1=B_SPLINE_CURVE_WITH_KNOTS('',2,(#5,#6,#7),.UNSPECIFIED.,.F.,.F.,(3,0,3),(0.,0.5,1.),.UNSPECIFIED.);",
                "multiplicity",
            ),
            (
                "#1=B_SPLINE_CURVE_WITH_KNOTS('',2,(#5,#6,#7),.UNSPECIFIED.,.F.,.F.,(3,3),(0.,0.5,1.),.UNSPECIFIED.);",
                "2 knot multiplicities for 3 knots",
            ),
            (
                "#1=(BOUNDED_CURVE()B_SPLINE_CURVE(1,(#5,#6),.UNSPECIFIED.,.F.,.F.)B_SPLINE_CURVE_WITH_KNOTS((2,999999999),(0.,1.),.UNSPECIFIED.)CURVE());",
                "sum to",
            ),
            (
                "#1=B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#5,#6),(#7,#8)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,1000000000),(0.,1.),(0.,1.),.UNSPECIFIED.);",
                "v knot multiplicities sum",
            ),
            (
                "#1=B_SPLINE_SURFACE_WITH_KNOTS('',1,1,((#5,.T.),(#7,#8)),.UNSPECIFIED.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);",
                "control point 1",
            ),
        ] {
            let r = refused_of(bad);
            let reason = r.get(&1).unwrap_or_else(|| panic!("accepted: {bad}"));
            assert!(reason.contains(needle), "{bad}: {reason}");
        }
    }
}
