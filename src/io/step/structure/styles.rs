//! Colours of styled items, after the CAx-IF *Recommended Practices for Model Styling and
//! Organization*: `STYLED_ITEM` → `PRESENTATION_STYLE_ASSIGNMENT` → … → `COLOUR_RGB` or
//! `DRAUGHTING_PRE_DEFINED_COLOUR`, a surface colour before any other, `OVER_RIDING_STYLED_ITEM`s
//! on top. Only styles and colours are followed, within a budget per item; layers, invisibility
//! and transparency are not read.

use std::collections::{HashMap, HashSet};

use crate::io::step::p21::{Entity, P21File, Param};

/// Colours of `STYLED_ITEM`s, then `OVER_RIDING_STYLED_ITEM`s on top.
pub(super) fn colours(file: &P21File) -> HashMap<u64, [f32; 3]> {
    let mut colours = HashMap::new();
    for overriding in [false, true] {
        for e in &file.entities {
            let Some(r) = e.parts.iter().find(|r| {
                let is_override = r.name == "OVER_RIDING_STYLED_ITEM"
                    || r.name == "CONTEXT_DEPENDENT_OVER_RIDING_STYLED_ITEM";
                (is_override || r.name == "STYLED_ITEM") && is_override == overriding
            }) else {
                continue;
            };
            // Complex instances carry the attributes on the STYLED_ITEM record.
            let r = e
                .parts
                .iter()
                .find(|r| r.list_at(1).is_some() && r.ref_at(2).is_some())
                .unwrap_or(r);
            let (Some(styles), Some(item)) = (r.list_at(1), r.ref_at(2)) else {
                continue;
            };
            if let Some(c) = style_colour(file, styles) {
                colours.insert(item, c);
            }
        }
    }
    colours
}

/// Most entities visited when looking for the colour of one styled item.
const STYLE_BUDGET: usize = 256;

/// The colour a list of presentation styles gives: the first surface colour found, else the
/// first other (curve, point, text) colour.
fn style_colour(file: &P21File, styles: &[Param]) -> Option<[f32; 3]> {
    let mut stack: Vec<(u64, usize, bool)> = Vec::new();
    push_refs(styles, 0, false, &mut stack);
    let mut seen = HashSet::new();
    let mut other = None;
    while let Some((id, depth, surface)) = stack.pop() {
        if seen.len() >= STYLE_BUDGET || !seen.insert((id, surface)) {
            continue;
        }
        let Some(e) = file.get(id) else {
            continue;
        };
        if let Some(c) = colour_value(e) {
            if surface {
                return Some(c);
            }
            other.get_or_insert(c);
            continue;
        }
        // Only styles and colours are followed, never back into geometry or representations.
        if depth >= 12
            || !e
                .parts
                .iter()
                .any(|r| r.name.contains("STYLE") || r.name.contains("COLOUR"))
        {
            continue;
        }
        let surface = surface
            || e.parts.iter().any(|r| {
                r.name.starts_with("SURFACE_STYLE")
                    || r.name == "SURFACE_SIDE_STYLE"
                    || r.name.starts_with("FILL_AREA_STYLE")
            });
        for r in e.parts.iter().rev() {
            push_refs(&r.args, depth + 1, surface, &mut stack);
        }
    }
    other
}

/// Pushes the references in `params` (and nested lists) so that the first is popped first.
fn push_refs(params: &[Param], depth: usize, surface: bool, stack: &mut Vec<(u64, usize, bool)>) {
    for p in params.iter().rev() {
        match p {
            Param::Ref(id) => stack.push((*id, depth, surface)),
            Param::List(items) => push_refs(items, depth, surface, stack),
            Param::Typed(_, inner) => push_refs(std::slice::from_ref(inner), depth, surface, stack),
            _ => {}
        }
    }
}

/// The RGB of a `COLOUR_RGB` or `DRAUGHTING_PRE_DEFINED_COLOUR` entity.
fn colour_value(e: &Entity) -> Option<[f32; 3]> {
    if let Some(r) = e.part("COLOUR_RGB") {
        let k = if r.args.len() >= 4 { 1 } else { 0 };
        let mut c = [0.0f32; 3];
        for (i, v) in c.iter_mut().enumerate() {
            let x = r.f64_at(k + i)?;
            if !x.is_finite() {
                return None;
            }
            *v = x.clamp(0.0, 1.0) as f32;
        }
        return Some(c);
    }
    let r = e.part("DRAUGHTING_PRE_DEFINED_COLOUR")?;
    let name = r.str_at(0)?.trim().to_ascii_lowercase();
    Some(match name.as_str() {
        "red" => [1.0, 0.0, 0.0],
        "green" => [0.0, 1.0, 0.0],
        "blue" => [0.0, 0.0, 1.0],
        "yellow" => [1.0, 1.0, 0.0],
        "magenta" => [1.0, 0.0, 1.0],
        "cyan" => [0.0, 1.0, 1.0],
        "black" => [0.0, 0.0, 0.0],
        "white" => [1.0, 1.0, 1.0],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{model, step};

    #[test]
    fn ctc_colours_and_unsupported_wireframe() {
        let s = model("nist_ctc_01_asme1_rd.stp");
        let steel = s.colors.get(&101).expect("solid colour");
        assert!((steel[0] - 0.596_063_2).abs() < 1e-6 && (steel[2] - 0.686_259_25).abs() < 1e-6);
        assert_eq!(s.instances[0].solid, Some(101));
        assert_eq!(
            s.unsupported,
            [
                ("GEOMETRIC_CURVE_SET".to_owned(), 1),
                ("VERTEX_LOOP".to_owned(), 2)
            ]
        );
    }

    #[test]
    fn colours_prefer_surface_and_overrides() {
        let s = step(
            "#1=COLOUR_RGB('',0.1,0.2,0.3);#2=DRAUGHTING_PRE_DEFINED_COLOUR('yellow');\
             #3=CURVE_STYLE('',$,$,#2);\
             #4=SURFACE_STYLE_USAGE(.BOTH.,#5);#5=SURFACE_SIDE_STYLE('',(#6));\
             #6=SURFACE_STYLE_FILL_AREA(#7);#7=FILL_AREA_STYLE('',(#8));\
             #8=FILL_AREA_STYLE_COLOUR('',#1);\
             #9=PRESENTATION_STYLE_ASSIGNMENT((#3,#4));\
             #10=STYLED_ITEM('',(#9),#100);\
             #11=STYLED_ITEM('',(#12),#101);#12=PRESENTATION_STYLE_ASSIGNMENT((#3));\
             #13=OVER_RIDING_STYLED_ITEM('',(#12),#100,#10);\
             #14=STYLED_ITEM('',(#15),#102);#15=PRESENTATION_STYLE_ASSIGNMENT((#16));\
             #16=SURFACE_STYLE_USAGE(.BOTH.,#17);#17=SURFACE_SIDE_STYLE('',(#18));\
             #18=SURFACE_STYLE_FILL_AREA(#19);#19=FILL_AREA_STYLE('',(#20));\
             #20=FILL_AREA_STYLE_COLOUR('',#21);#21=COLOUR_RGB('',2.,-1.,0.5);",
        );
        assert_eq!(
            s.colors.get(&101),
            Some(&[1.0, 1.0, 0.0]),
            "curve colour when alone"
        );
        assert_eq!(s.colors.get(&100), Some(&[1.0, 1.0, 0.0]), "override wins");
        assert_eq!(s.colors.get(&102), Some(&[1.0, 0.0, 0.5]), "clamped");
        let s = step(
            "#1=COLOUR_RGB('',0.1,0.2,0.3);#2=DRAUGHTING_PRE_DEFINED_COLOUR('yellow');\
             #3=CURVE_STYLE('',$,$,#2);#4=SURFACE_STYLE_USAGE(.BOTH.,#5);\
             #5=SURFACE_SIDE_STYLE('',(#6));#6=SURFACE_STYLE_FILL_AREA(#7);\
             #7=FILL_AREA_STYLE('',(#8));#8=FILL_AREA_STYLE_COLOUR('',#1);\
             #9=PRESENTATION_STYLE_ASSIGNMENT((#3,#4));#10=STYLED_ITEM('',(#9),#100);",
        );
        assert_eq!(
            s.colors.get(&100),
            Some(&[0.1, 0.2, 0.3]),
            "surface before curve"
        );
    }
}
