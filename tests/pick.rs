//! `stats --pick X,Y` (issue 32): what a pixel of `render`'s image shows — part, face (STEP
//! entity id), surface type, the 3-D point — and the distance between two picks. Judged on a
//! 20 mm cube whose face centres are known: the pixel is where the camera projects a face's
//! centre, the face is the one whose plane holds that point.

mod common;

use std::process::{Command, Output};

use glam::DVec3;
use patchwork::model::PatchSurface;
use patchwork::view::View;
use serde_json::Value;

const SIZE: (u32, u32) = (400, 300);
const EYE: DVec3 = DVec3::new(50.0, -40.0, 45.0);
const TARGET: DVec3 = DVec3::new(10.0, 10.0, 10.0);
const MODEL: &str = "edges/cube.step";

fn stats(picks: &[String], json: bool) -> Output {
    let v = |p: DVec3| format!("{},{},{}", p.x, p.y, p.z);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_patchwork"));
    cmd.arg("stats")
        .arg(common::root().join("models").join(MODEL))
        .args(["--size", &format!("{}x{}", SIZE.0, SIZE.1)])
        .args(["--eye", &v(EYE), "--target", &v(TARGET), "--up", "0,0,1"]);
    for p in picks {
        cmd.args(["--pick", p]);
    }
    if json {
        cmd.arg("--json");
    }
    cmd.output().expect("patchwork runs")
}

/// The pixel (column, row) where `p` projects under the test's camera.
fn pixel_of(p: DVec3) -> String {
    let scene = common::load(MODEL);
    let view = View::new(
        EYE,
        TARGET,
        DVec3::Z,
        45f64.to_radians(),
        SIZE,
        &scene.bounds,
    );
    let (x, y, _) = view.project(p).expect("in front of the camera");
    format!("{},{}", x.floor(), y.floor())
}

/// The STEP id of the cube face whose plane is `axis` = `value`.
fn face_id(axis: usize, value: f64) -> u64 {
    let scene = common::load(MODEL);
    let ids: Vec<u64> = scene
        .patches
        .iter()
        .filter_map(|p| match &p.surface {
            PatchSurface::Trimmed(f) => Some(f),
            _ => None,
        })
        .filter(|f| (f.bounds.center[axis] - value).abs() < 1e-6)
        .map(|f| f.id)
        .collect();
    assert_eq!(ids.len(), 1, "one face at {axis} = {value}");
    ids[0]
}

fn json(o: &Output) -> Value {
    assert!(
        o.status.success(),
        "stats failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

#[test]
fn a_pick_names_the_face_its_surface_and_the_point() {
    let centre = DVec3::new(20.0, 10.0, 10.0);
    let o = stats(&[pixel_of(centre)], true);
    let report = json(&o);
    let pick = &report["picks"][0];
    let hit = &pick["hit"];
    assert_eq!(hit["face"].as_u64(), Some(face_id(0, 20.0)), "{pick}");
    assert_eq!(hit["surface"], "plane");
    assert_eq!(hit["on_triangles"], true);
    let p: Vec<f64> = hit["point"]
        .as_array()
        .expect("point")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect();
    // On the face's plane, within a pixel of its centre (0.1 mm here).
    assert!((p[0] - 20.0).abs() < 1e-3, "{p:?}");
    assert!(DVec3::new(p[0], p[1], p[2]).distance(centre) < 0.2, "{p:?}");
}

#[test]
fn two_picks_give_their_distance_and_text_says_it() {
    let a = DVec3::new(20.0, 10.0, 10.0);
    let b = DVec3::new(10.0, 10.0, 20.0);
    let report = json(&stats(&[pixel_of(a), pixel_of(b)], true));
    let picks = report["picks"].as_array().expect("picks");
    assert_eq!(picks[1]["hit"]["face"].as_u64(), Some(face_id(2, 20.0)));
    let d = picks[1]["distance_from_previous"]
        .as_f64()
        .expect("distance");
    assert!((d - a.distance(b)).abs() < 0.3, "{d}");
    assert!(picks[0]["distance_from_previous"].is_null());
    // The text report: one line per pick, then the distance.
    let o = stats(&[pixel_of(a), pixel_of(b)], false);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("pick {}", pixel_of(a))))
        .unwrap_or_else(|| panic!("no pick line in:\n{text}"));
    assert!(
        line.contains(&format!("face #{} plane", face_id(0, 20.0))),
        "{line}"
    );
    assert!(
        text.contains(&format!("distance          {d:.4} mm")),
        "{d}: {text}"
    );
}

#[test]
fn the_background_is_nothing_and_outside_the_image_is_an_error() {
    let report = json(&stats(&["0,0".into()], true));
    assert!(report["picks"][0]["hit"].is_null());
    let o = stats(&["0,0".into()], false);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("nothing at 0,0 (background)"));
    for outside in ["400,10", "10,300", "-1,5"] {
        let o = stats(&[outside.into()], false);
        assert_eq!(o.status.code(), Some(2), "{outside}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("outside the 400x300 image"),
            "{outside}: {err}"
        );
    }
    let o = stats(&["12".into()], false);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("X,Y"));
}
