//! Unit tests of the viewer's camera framing and orbit.

use super::*;
use crate::model::Sphere;

fn scene() -> Scene {
    let mut s = Scene::from_bezier(Vec::new(), crate::model::UpAxis::Z);
    s.bounds = Sphere {
        center: DVec3::new(1.0, 2.0, 3.0),
        radius: 2.0,
    };
    s
}

#[test]
fn orbit_fit_reproduces_the_framing_view() {
    let s = scene();
    let fov = 45f64.to_radians();
    let o = Orbit::fit(&s, None, &Framing::default(), fov, (640, 480));
    let v = View::framing(&s.bounds, s.up.vector(), fov, (640, 480));
    assert!(o.eye().distance(v.eye) < 1e-9, "{} vs {}", o.eye(), v.eye);
}

/// Orthographic (`--ortho`, key `5`): the fitted orbit's view is the framed orthographic
/// view, and zooming shrinks its height.
#[test]
fn orbit_fit_reproduces_the_orthographic_framing() {
    let s = scene();
    let fov = 45f64.to_radians();
    let framing = Framing {
        ortho: true,
        ..Framing::default()
    };
    let mut o = Orbit::fit(&s, None, &framing, fov, (640, 480));
    let want = View::framed(&s.bounds, s.up.vector(), &framing, fov, (640, 480));
    let got = o.view(&s, fov, (640, 480), true);
    let height = |v: &View| match v.projection {
        Projection::Orthographic { height } => height,
        Projection::Perspective => panic!("perspective"),
    };
    assert!((height(&got) - height(&want)).abs() < 1e-9);
    assert!((got.forward() - want.forward()).length() < 1e-9);
    assert!(!o.view(&s, fov, (640, 480), false).is_orthographic());
    o.zoom(0.5);
    let closer = o.view(&s, fov, (640, 480), true);
    assert!((height(&closer) - 0.5 * height(&want)).abs() < 1e-9);
}

#[test]
fn orbit_rotation_keeps_distance_and_clamps_pitch() {
    let mut o = Orbit::fit(
        &scene(),
        None,
        &Framing::default(),
        45f64.to_radians(),
        (640, 480),
    );
    let d = o.distance;
    o.rotate(1.0, 10.0);
    assert!((o.eye().distance(o.target) - d).abs() < 1e-9);
    assert!(o.pitch <= 89f64.to_radians() + 1e-12);
    o.zoom(0.5);
    assert!((o.eye().distance(o.target) - d * 0.5).abs() < 1e-9);
    // Panning by a view's height moves the target by the height of the view there.
    let t = o.target;
    o.pan(0.0, 480.0, 45f64.to_radians(), 480);
    let moved = o.target.distance(t);
    let expected = o.distance * 2.0 * (22.5f64.to_radians()).tan();
    assert!((moved - expected).abs() < 1e-9, "{moved} vs {expected}");
}
