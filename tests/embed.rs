//! `examples/embed.rs` headless: patchwork's teapot drawn into a caller's own pass beside the
//! caller's triangle, depth-tested against it both ways, and the embed API's refusals.

mod common;

#[path = "../examples/embed.rs"]
#[allow(dead_code)] // (The example's `main` and some of its constants.)
mod example;

use example::{BACKGROUND, HEIGHT, Layers, TRIANGLE_COLOUR, WIDTH};
use glam::{DVec3, Mat4};
use image::RgbaImage;
use patchwork::embed::{Camera, EmbedError, EmbedOptions, Renderer};

fn draw(layers: Layers) -> RgbaImage {
    example::draw(layers)
        .unwrap_or_else(|e| panic!("this test draws on a graphics adapter and could not: {e}"))
}

fn is_triangle(p: &image::Rgba<u8>) -> bool {
    p.0 == TRIANGLE_COLOUR
}

fn is_background(p: &image::Rgba<u8>) -> bool {
    p.0 == BACKGROUND
}

/// The one-pass image shows the caller's triangle where only it is, the lit teapot where
/// only it is, the triangle where its plane lies in front of the whole teapot and the teapot
/// where the plane lies behind it.
#[test]
fn the_example_draws_the_teapot_beside_and_through_the_callers_triangle() {
    let out = common::scratch("embed").join("embed.png");
    let both = example::run(&out)
        .unwrap_or_else(|e| panic!("this test draws on a graphics adapter and could not: {e}"));
    let written = image::open(&out)
        .unwrap_or_else(|e| panic!("{}: {e}", out.display()))
        .to_rgba8();
    assert!(written == both, "the PNG written is not the image drawn");
    let triangle = draw(Layers {
        triangle: true,
        teapot: false,
    });
    let teapot = draw(Layers {
        triangle: false,
        teapot: true,
    });
    let columns = example::columns();
    assert!(columns.front_max < columns.behind_min && columns.behind_min < WIDTH);

    let (mut triangle_only, mut teapot_only, mut in_front, mut behind) = (0, 0, 0, 0);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (t, p, b) = (
                triangle.get_pixel(x, y),
                teapot.get_pixel(x, y),
                both.get_pixel(x, y),
            );
            let on_triangle = is_triangle(t);
            let on_teapot = !is_background(p);
            assert!(
                !is_triangle(p),
                "the teapot alone shows the triangle's colour at ({x}, {y})"
            );
            match (on_triangle, on_teapot) {
                (false, false) => {
                    assert!(is_background(b), "({x}, {y}): {b:?} where nothing is drawn")
                }
                (true, false) => {
                    triangle_only += 1;
                    assert!(is_triangle(b), "({x}, {y}): {b:?}, not the triangle alone");
                }
                (false, true) => {
                    teapot_only += 1;
                    assert!(b == p, "({x}, {y}): {b:?}, not the teapot alone ({p:?})");
                }
                (true, true) if x <= columns.front_max => {
                    in_front += 1;
                    assert!(
                        is_triangle(b),
                        "({x}, {y}): {b:?} where the triangle lies in front of the teapot"
                    );
                }
                (true, true) if x >= columns.behind_min => {
                    behind += 1;
                    assert!(
                        b == p,
                        "({x}, {y}): {b:?} where the triangle lies behind the teapot ({p:?})"
                    );
                }
                (true, true) => {
                    assert!(is_triangle(b) || b == p, "({x}, {y}): {b:?}, neither");
                }
            }
        }
    }
    // Each case is really seen, not vacuously true.
    for (what, n) in [
        ("the triangle alone", triangle_only),
        ("the teapot alone", teapot_only),
        ("the triangle in front of the teapot", in_front),
        ("the triangle behind the teapot", behind),
    ] {
        assert!(n >= 200, "only {n} pixels of {what}");
    }
    // The teapot is shaded: lit, so its pixels are not all one colour.
    let shades: std::collections::HashSet<[u8; 4]> = teapot
        .pixels()
        .filter(|p| !is_background(p))
        .map(|p| p.0)
        .collect();
    assert!(shades.len() > 50, "{} shades on the teapot", shades.len());
}

fn teapot_camera(scene: &patchwork::model::Scene, distance: f64) -> Camera {
    let centre = scene.bounds.center;
    let eye = centre + DVec3::new(0.3, -1.0, 0.5).normalize() * distance * scene.bounds.radius;
    Camera {
        view: Mat4::look_at_rh(eye.as_vec3(), centre.as_vec3(), scene.up.vector().as_vec3()),
        projection: Mat4::perspective_rh(0.8, 4.0 / 3.0, 0.05, 100.0),
        viewport: (400, 300),
    }
}

/// The entry point refuses what it cannot draw with typed errors, and its frame loop
/// re-tessellates when the camera comes closer.
#[test]
fn the_embed_renderer_refuses_bad_input_and_follows_the_camera() {
    let (device, queue) = example::device()
        .unwrap_or_else(|e| panic!("this test draws on a graphics adapter and could not: {e}"));
    let new = |depth, options| {
        Renderer::new(
            &device,
            &queue,
            wgpu::TextureFormat::Rgba8Unorm,
            depth,
            common::teapot(),
            options,
        )
    };
    let colour_as_depth = new(wgpu::TextureFormat::Rgba8Unorm, EmbedOptions::default());
    assert!(
        matches!(colour_as_depth, Err(EmbedError::NotDepthFormat { .. })),
        "{colour_as_depth:?}"
    );
    let mut three = EmbedOptions::default();
    three.sample_count = 3;
    let three = new(wgpu::TextureFormat::Depth32Float, three);
    assert!(
        matches!(three, Err(EmbedError::BadSampleCount(3))),
        "{three:?}"
    );

    let mut unlimited = EmbedOptions::default();
    unlimited.lod.budget = std::time::Duration::from_secs(600);
    let mut renderer =
        new(wgpu::TextureFormat::Depth32Float, unlimited).unwrap_or_else(|e| panic!("{e}"));
    let far = teapot_camera(renderer.scene(), 6.0);
    let nan = renderer.prepare(&far, f64::NAN);
    assert!(matches!(nan, Err(EmbedError::BadPixelError(_))), "{nan:?}");
    let empty = renderer.prepare(
        &Camera {
            viewport: (0, 300),
            ..far
        },
        0.5,
    );
    assert!(
        matches!(empty, Err(EmbedError::EmptyViewport { .. })),
        "{empty:?}"
    );
    let left_handed = renderer.prepare(
        &Camera {
            projection: Mat4::perspective_lh(0.8, 4.0 / 3.0, 0.05, 100.0),
            ..far
        },
        0.5,
    );
    assert!(
        matches!(left_handed, Err(EmbedError::Camera(_))),
        "{left_handed:?}"
    );

    let first = renderer
        .prepare(&far, 0.5)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first.update.in_frustum, 32);
    assert!(first.upload.uploaded_bytes() > 0, "{first:?}");
    assert!(first.max_error_px <= 0.5 + 1e-9, "{first:?}");
    // Closer: the patches want a finer ε, and the frame loop (its budget unlimited here)
    // gets them there in one step and uploads them.
    let near = teapot_camera(renderer.scene(), 2.0);
    let closer = renderer
        .prepare(&near, 0.5)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(closer.update.retessellated > 0, "{closer:?}");
    assert!(
        closer.update.triangles > first.update.triangles,
        "{first:?} {closer:?}"
    );
    assert!(closer.upload.uploaded_bytes() > 0, "{closer:?}");
    assert!(closer.max_error_px <= 0.5 + 1e-9, "{closer:?}");
    // The same camera again: nothing left to do, nothing uploaded.
    let again = renderer
        .prepare(&near, 0.5)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.update.retessellated, 0, "{again:?}");
}
