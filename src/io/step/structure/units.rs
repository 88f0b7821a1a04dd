//! Units of a STEP file: millimetres per length unit and radians per plane-angle unit, from the
//! `GLOBAL_UNIT_ASSIGNED_CONTEXT`s (`SI_UNIT` with its prefix, or `CONVERSION_BASED_UNIT`
//! through its measure, e.g. inch and degree), and the distance uncertainty
//! (`UNCERTAINTY_MEASURE_WITH_UNIT`). No geometry is converted here; representations with
//! different length units get a warning and the first unit is assumed.

use super::ShellInstance;
use super::links::Graph;
use crate::io::step::p21::{P21File, Param};

/// Millimetres per file length unit, from the contexts of the representations holding the
/// placed shells (or, if they name none, of any context in the file).
pub(super) fn length_unit(
    file: &P21File,
    graph: &Graph,
    instances: &[ShellInstance],
    warnings: &mut Vec<String>,
) -> Option<f64> {
    let mut contexts: Vec<u64> = Vec::new();
    for i in instances {
        if let Some(&ctx) = i.representation.and_then(|r| graph.rep_context.get(&r))
            && !contexts.contains(&ctx)
        {
            contexts.push(ctx);
        }
    }
    let mut units = distinct_length_units(file, &contexts);
    if units.is_empty() {
        let all: Vec<u64> = file
            .entities
            .iter()
            .filter(|e| e.has("GLOBAL_UNIT_ASSIGNED_CONTEXT"))
            .map(|e| e.id)
            .collect();
        units = distinct_length_units(file, &all);
    }
    if units.len() > 1 {
        let list: Vec<String> = units.iter().map(|u| format!("{u} mm")).collect();
        warnings.push(format!(
            "representations use different length units ({}); not converted, {} assumed",
            list.join(", "),
            list.first().map_or("", String::as_str)
        ));
    }
    units.first().copied()
}

/// The different length units (in mm) of `contexts`, in order of first use.
fn distinct_length_units(file: &P21File, contexts: &[u64]) -> Vec<f64> {
    let mut units: Vec<f64> = Vec::new();
    for &ctx in contexts {
        if let Some(mm) = context_length_mm(file, ctx)
            && !units.iter().any(|u| (u - mm).abs() <= 1e-9 * mm)
        {
            units.push(mm);
        }
    }
    units
}

fn context_length_mm(file: &P21File, ctx: u64) -> Option<f64> {
    let units = file
        .get(ctx)?
        .part("GLOBAL_UNIT_ASSIGNED_CONTEXT")?
        .list_at(0)?;
    units
        .iter()
        .filter_map(Param::as_ref)
        .find_map(|u| unit_mm(file, u, 0))
}

/// What a unit measures: its SI name, the record that marks a conversion-based unit of that
/// kind, and what one SI unit is in the scale wanted.
type UnitKind = (&'static str, &'static str, f64);

/// Lengths in millimetres.
const LENGTH_MM: UnitKind = ("METRE", "LENGTH_UNIT", 1000.0);

/// Plane angles in radians.
const ANGLE_RAD: UnitKind = ("RADIAN", "PLANE_ANGLE_UNIT", 1.0);

/// Millimetres in length unit `id` (`None` if it is not a length unit).
fn unit_mm(file: &P21File, id: u64, depth: usize) -> Option<f64> {
    unit_value(file, id, LENGTH_MM, depth)
}

/// One unit `id` of `kind` in `kind`'s scale (`None` if it is not such a unit): an `SI_UNIT`
/// with its prefix, or a `CONVERSION_BASED_UNIT` through its measure.
fn unit_value(file: &P21File, id: u64, kind: UnitKind, depth: usize) -> Option<f64> {
    let (si_name, marker, si_scale) = kind;
    if depth > 8 {
        return None;
    }
    let e = file.get(id)?;
    let value = if let Some(si) = e.part("SI_UNIT") {
        // Complex form SI_UNIT(prefix, name); simple form SI_UNIT(dimensions, prefix, name).
        let n = si.args.len();
        if n < 2 || si.args.get(n - 1)?.as_enum()? != si_name {
            return None;
        }
        let prefix = match si.args.get(n - 2)?.as_enum() {
            None => 1.0,
            Some(p) => si_prefix(p)?,
        };
        si_scale * prefix
    } else if let Some(cbu) = e.part("CONVERSION_BASED_UNIT") {
        if !e.has(marker) {
            return None;
        }
        let factor = file.get(cbu.ref_at(1)?)?;
        let measure = factor
            .parts
            .iter()
            .find(|r| r.f64_at(0).is_some() && r.ref_at(1).is_some())?;
        measure.f64_at(0)? * unit_value(file, measure.ref_at(1)?, kind, depth + 1)?
    } else {
        return None;
    };
    (value.is_finite() && value > 0.0).then_some(value)
}

/// Radians in the plane-angle unit of the first context that names one.
pub(super) fn plane_angle_unit(file: &P21File) -> Option<f64> {
    file.entities
        .iter()
        .filter_map(|e| e.part("GLOBAL_UNIT_ASSIGNED_CONTEXT"))
        .filter_map(|r| r.list_at(0))
        .flat_map(|units| units.iter().filter_map(Param::as_ref))
        .find_map(|u| unit_value(file, u, ANGLE_RAD, 0))
}

/// The largest distance uncertainty any context declares (file length units).
pub(super) fn uncertainty(file: &P21File) -> Option<f64> {
    file.entities
        .iter()
        .filter_map(|e| e.part("UNCERTAINTY_MEASURE_WITH_UNIT"))
        .filter_map(|r| r.f64_at(0))
        .filter(|u| u.is_finite() && *u > 0.0)
        .reduce(f64::max)
}

fn si_prefix(p: &str) -> Option<f64> {
    Some(match p {
        "EXA" => 1e18,
        "PETA" => 1e15,
        "TERA" => 1e12,
        "GIGA" => 1e9,
        "MEGA" => 1e6,
        "KILO" => 1e3,
        "HECTO" => 1e2,
        "DECA" => 1e1,
        "DECI" => 1e-1,
        "CENTI" => 1e-2,
        "MILLI" => 1e-3,
        "MICRO" => 1e-6,
        "NANO" => 1e-9,
        "PICO" => 1e-12,
        "FEMTO" => 1e-15,
        "ATTO" => 1e-18,
        _ => return None,
    })
}
