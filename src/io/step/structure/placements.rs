//! Placements as matrices, after ISO 10303-42 (`axis2_placement_3d` with `build_axes`,
//! `cartesian_transformation_operator_3d`): a missing, unreadable or degenerate direction
//! gets the standard's default, a location that cannot be read makes the placement unreadable
//! (`None`), and no matrix is ever non-finite.

use glam::{DMat4, DVec3};

use crate::io::step::p21::{P21File, Param, Record};

/// A point or direction `(name, (x, y[, z]))` as a vector; `None` if not finite.
fn vector(file: &P21File, id: u64, record: &str) -> Option<DVec3> {
    let r = file.get(id)?.part(record)?;
    let c = r.list_at(1)?;
    let x = c.first()?.as_f64()?;
    let y = c.get(1)?.as_f64()?;
    let z = c.get(2).and_then(Param::as_f64).unwrap_or(0.0);
    let v = DVec3::new(x, y, z);
    v.is_finite().then_some(v)
}

/// Optional direction attribute: `Some(None)` for `$` or an unreadable direction.
fn direction(file: &P21File, r: &Record, i: usize) -> Option<DVec3> {
    r.ref_at(i)
        .and_then(|id| vector(file, id, "DIRECTION"))
        .and_then(|d| d.try_normalize())
}

/// A unit vector perpendicular to `z` (unit), as close to `hint` as possible.
fn perpendicular(z: DVec3, hint: Option<DVec3>) -> DVec3 {
    let project = |v: DVec3| (v - v.dot(z) * z).try_normalize();
    hint.and_then(project)
        .or_else(|| project(DVec3::X))
        .or_else(|| project(DVec3::Y))
        .unwrap_or(DVec3::X)
}

/// Object → parent matrix of an `AXIS2_PLACEMENT_3D` or `CARTESIAN_TRANSFORMATION_OPERATOR_3D`.
pub fn placement(file: &P21File, id: u64) -> Option<DMat4> {
    let e = file.get(id)?;
    let m = if let Some(r) = e.part("AXIS2_PLACEMENT_3D") {
        let origin = vector(file, r.ref_at(1)?, "CARTESIAN_POINT")?;
        let z = direction(file, r, 2).unwrap_or(DVec3::Z);
        let x = perpendicular(z, direction(file, r, 3));
        let y = z.cross(x);
        DMat4::from_cols(
            x.extend(0.0),
            y.extend(0.0),
            z.extend(0.0),
            origin.extend(1.0),
        )
    } else if let Some(r) = e
        .parts
        .iter()
        .find(|r| r.name == "CARTESIAN_TRANSFORMATION_OPERATOR_3D")
    {
        // (name, [description,] axis1, axis2, local_origin, scale, axis3)
        let k = if r.args.len() >= 7 { 1 } else { 0 };
        let origin = vector(file, r.ref_at(k + 3)?, "CARTESIAN_POINT")?;
        let scale = r.f64_at(k + 4).unwrap_or(1.0);
        let scale = if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        };
        let z = direction(file, r, k + 5).unwrap_or(DVec3::Z);
        let x = perpendicular(z, direction(file, r, k + 1));
        let y_hint = direction(file, r, k + 2).unwrap_or_else(|| z.cross(x));
        let y = (y_hint - y_hint.dot(z) * z - y_hint.dot(x) * x)
            .try_normalize()
            .unwrap_or_else(|| z.cross(x));
        DMat4::from_cols(
            (x * scale).extend(0.0),
            (y * scale).extend(0.0),
            (z * scale).extend(0.0),
            origin.extend(1.0),
        )
    } else {
        return None;
    };
    m.is_finite().then_some(m)
}

/// Inverse of an affine matrix, if it is safely invertible.
pub(super) fn inverse(m: DMat4) -> Option<DMat4> {
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    let inv = m.inverse();
    inv.is_finite().then_some(inv)
}

#[cfg(test)]
mod tests {
    use glam::{DMat4, DVec3};

    use super::super::fixtures::{assert_close, assert_rigid};
    use super::*;
    use crate::io::step::p21::parse;

    #[test]
    fn degenerate_placements_stay_finite_and_rigid() {
        let file = parse(
            "ISO-10303-21;HEADER;ENDSEC;DATA;\
             #1=CARTESIAN_POINT('',(1.,2.));#2=DIRECTION('',(0.,0.,0.));\
             #3=DIRECTION('',(0.,0.,5.));#4=DIRECTION('',(1.,0.,0.));\
             #10=AXIS2_PLACEMENT_3D('',#1,#2,#3);#11=AXIS2_PLACEMENT_3D('',#1,#3,#3);\
             #12=AXIS2_PLACEMENT_3D('',#1,#4,$);#13=AXIS2_PLACEMENT_3D('',#99,$,$);\
             #14=CARTESIAN_TRANSFORMATION_OPERATOR_3D('','',$,$,#1,2.,$);ENDSEC;",
        )
        .expect("parses");
        for id in [10, 11, 12] {
            let m = placement(&file, id).expect("readable");
            assert_rigid(m);
            assert_eq!(m.w_axis, glam::DVec4::new(1.0, 2.0, 0.0, 1.0));
        }
        assert_eq!(placement(&file, 13), None);
        let m = placement(&file, 14).expect("operator");
        assert_close(
            m,
            DMat4::from_scale_rotation_translation(
                DVec3::splat(2.0),
                glam::DQuat::IDENTITY,
                DVec3::new(1.0, 2.0, 0.0),
            ),
        );
    }
}
