//! Tests of [`super`] (crack).

use super::*;

fn frame(w: u32, h: u32, depth: Vec<f32>, bg: [u8; 3], surf: [u8; 3]) -> Frame {
    let color = depth
        .iter()
        .flat_map(|z| {
            let c = if z.is_finite() { surf } else { bg };
            [c[0], c[1], c[2], 255]
        })
        .collect();
    Frame {
        width: w,
        height: h,
        color,
        depth: Some(depth),
        ids: None,
    }
}

fn test_view() -> View {
    let s = crate::model::Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
    };
    View::new(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        1.0,
        (8, 8),
        &s,
    )
}

#[test]
fn background_hole_and_far_surface_are_cracks_growth_is_counted() {
    let (w, h) = (8u32, 8u32);
    let inf = f32::INFINITY;
    // Reference: a 6×6 block in the middle at depth 5.
    let rd: Vec<f32> = (0..64)
        .map(|i| {
            let (x, y) = (i % 8, i / 8);
            if (1..7).contains(&x) && (1..7).contains(&y) {
                5.0
            } else {
                inf
            }
        })
        .collect();
    let reference = frame(w, h, rd.clone(), SENTINEL, [128; 3]);
    let mut ad = rd.clone();
    ad[3 * 8 + 3] = inf; // a hole showing the background
    ad[4 * 8 + 4] = 9.0; // the far side showing through
    ad[5 * 8 + 4] = 5.001; // within tolerance: not a crack
    ad[0] = 5.0; // growth 1 px outside: not counted (distance 1)
    let actual = frame(w, h, ad, SENTINEL, [128; 3]);
    let (c, _) = classify(&reference, &actual, &test_view(), 0.5, SENTINEL).expect("comparable");
    assert_eq!(c.inside, 4 * 4);
    assert_eq!(c.background, 1);
    assert_eq!(c.behind, 1);
    assert_eq!(c.growth, 0);

    // Growth two pixels out: reference smaller.
    let small: Vec<f32> = (0..64)
        .map(|i| {
            let (x, y) = (i % 8, i / 8);
            if (4..7).contains(&x) && (4..7).contains(&y) {
                5.0
            } else {
                inf
            }
        })
        .collect();
    let reference = frame(w, h, small, SENTINEL, [128; 3]);
    let (c, _) = classify(&reference, &actual, &test_view(), 0.5, SENTINEL).expect("comparable");
    assert!(c.growth > 0);
    assert!(c.growth_max_px >= 2);
}

#[test]
fn identical_images_have_no_cracks() {
    let d: Vec<f32> = (0..64)
        .map(|i| {
            if i % 8 > 0 && i % 8 < 7 {
                3.0
            } else {
                f32::INFINITY
            }
        })
        .collect();
    let f = frame(8, 8, d, SENTINEL, [128; 3]);
    let (c, _) = classify(&f, &f, &test_view(), 0.5, SENTINEL).expect("comparable");
    assert_eq!(c.cracks(), 0);
    assert_eq!(c.growth, 0);
    assert!(c.inside > 0);
}

/// Images that cannot be compared are an error, never "no cracks" (it used to return zero
/// counts: a check on a frame rendered without depth passed).
#[test]
fn incomparable_images_are_errors() {
    let d: Vec<f32> = (0..64)
        .map(|i| if i % 8 > 0 { 3.0 } else { f32::INFINITY })
        .collect();
    let good = frame(8, 8, d.clone(), SENTINEL, [128; 3]);
    let v = test_view();
    let mut no_depth = good.clone();
    no_depth.depth = None;
    assert!(matches!(
        classify(&good, &no_depth, &v, 0.5, SENTINEL),
        Err(CheckError::MissingDepth("actual"))
    ));
    assert!(matches!(
        classify(&no_depth, &good, &v, 0.5, SENTINEL),
        Err(CheckError::MissingDepth("reference"))
    ));
    let wide = frame(16, 4, d.clone(), SENTINEL, [128; 3]);
    assert!(matches!(
        classify(&good, &wide, &v, 0.5, SENTINEL),
        Err(CheckError::SizeMismatch {
            reference: (8, 8),
            actual: (16, 4)
        })
    ));
    let mut short = good.clone();
    short.depth = Some(d[..60].to_vec());
    assert!(matches!(
        classify(&good, &short, &v, 0.5, SENTINEL),
        Err(CheckError::BufferLength {
            buffer: "depth",
            len: 60,
            ..
        })
    ));
    let mut short = good.clone();
    short.color.truncate(4 * 63);
    assert!(matches!(
        classify(&short, &good, &v, 0.5, SENTINEL),
        Err(CheckError::BufferLength {
            which: "reference",
            buffer: "colour",
            ..
        })
    ));
    assert!(classify(&good, &good, &v, 0.5, SENTINEL).is_ok());
}

#[test]
fn random_views_are_reproducible() {
    let a = SplitMix64::new(7).next_u64();
    assert_eq!(a, SplitMix64::new(7).next_u64());
    assert_ne!(a, SplitMix64::new(8).next_u64());
}
