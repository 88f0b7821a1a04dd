//! The `patchwork` command: renders, reports, and fails cleanly (non-zero exit, a message that
//! names the file, no output file) on bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn patchwork(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn out_path(name: &str) -> PathBuf {
    let p = common::scratch("cli").join(name);
    let _ = std::fs::remove_file(&p);
    p
}

fn teapot() -> String {
    common::root()
        .join("models/teapot.bpt")
        .to_string_lossy()
        .into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let out = out_path("render.png");
    let depth = out_path("render-depth.png");
    let o = patchwork(&[
        "render",
        &teapot(),
        "-o",
        s(&out),
        "--size",
        "160x120",
        "--depth-out",
        s(&depth),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("adapter:"),
        "says which adapter it used: {}",
        stderr(&o)
    );
    let img = image::open(&out).expect("a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (160, 120));
    // Not blank: the teapot covers a good part of the image with non-background pixels.
    let covered = img
        .pixels()
        .filter(|p| p[0] != 255 || p[1] != 255 || p[2] != 255)
        .count();
    assert!(
        covered > 160 * 120 / 20,
        "only {covered} non-background pixels"
    );
    let d = image::open(&depth).expect("a depth PNG");
    assert!(
        matches!(d, image::DynamicImage::ImageLuma16(_)),
        "depth is 16-bit grey"
    );
    let d = d.to_luma16();
    let min = d.pixels().map(|p| p[0]).min().unwrap_or(0);
    assert!(
        min > 0 && min < 65535,
        "model depth lies between the planes: {min}"
    );
    assert!(
        d.pixels().any(|p| p[0] == 65535),
        "background is the far plane"
    );
}

#[test]
fn every_shading_mode_and_variant_renders() {
    for (shading, fb, msaa) in [("flat", "off", "1"), ("ids", "2", "4"), ("lit", "4", "1")] {
        let out = out_path(&format!("mode-{shading}.png"));
        let o = patchwork(&[
            "render",
            &teapot(),
            "-o",
            s(&out),
            "--size",
            "64x48",
            "--shading",
            shading,
            "--fat-borders",
            fb,
            "--msaa",
            msaa,
            "--background",
            "10,20,30",
        ]);
        assert!(o.status.success(), "{shading}: {}", stderr(&o));
        let img = image::open(&out).expect("a PNG").to_rgba8();
        assert_eq!(
            img.get_pixel(0, 0).0,
            [10, 20, 30, 255],
            "background colour"
        );
    }
}

#[test]
fn explicit_camera_is_used() {
    let out = out_path("camera.png");
    let o = patchwork(&[
        "render",
        &teapot(),
        "-o",
        s(&out),
        "--size",
        "64x48",
        "--eye",
        "0,-12,1.5",
        "--target",
        "0,0,1.5",
        "--up",
        "0,0,1",
        "--fov",
        "30",
        "--pixel-error",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn bad_model_files_fail_with_the_file_named_and_no_output() {
    let dir = common::root().join("tests/data/bad");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).expect("fixtures") {
        let path = entry.expect("entry").path();
        let out = out_path("bad.png");
        let o = patchwork(&["render", s(&path), "-o", s(&out), "--size", "32x32"]);
        let msg = stderr(&o);
        assert!(!o.status.success(), "{}: accepted", path.display());
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        assert!(
            msg.contains(&name),
            "{name}: message does not name the file: {msg}"
        );
        assert!(!msg.contains("panicked"), "{name}: panicked: {msg}");
        assert!(!out.exists(), "{name}: an output file was written");
        n += 1;
    }
    assert!(n >= 10, "expected the bad-input fixtures, found {n}");
}

#[test]
fn missing_file_and_unknown_format_are_errors() {
    for (file, needle) in [
        ("no/such/model.bpt", "cannot read"),
        ("Cargo.toml", "unsupported"),
    ] {
        let out = out_path("missing.png");
        let path = common::root().join(file);
        let o = patchwork(&["render", s(&path), "-o", s(&out)]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(needle), "{}", stderr(&o));
        assert!(!out.exists());
    }
}

#[test]
fn unwritable_output_is_an_error_and_leaves_nothing() {
    let out = common::scratch("cli").join("no-such-dir").join("x.png");
    let o = patchwork(&["render", &teapot(), "-o", s(&out), "--size", "32x32"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no-such-dir"), "{}", stderr(&o));
    assert!(!out.exists());
    assert!(!out.parent().expect("parent").exists());
}

#[test]
fn zero_image_size_and_bad_flags_are_rejected() {
    let out = out_path("zero.png");
    let model = teapot();
    for flags in [
        &["--size", "0x100"][..],
        &["--size", "100"],
        &["--msaa", "3"],
        &["--fat-borders", "5"],
        &["--shading", "toon"],
        &["--primitives", "fans"],
        &["--pixel-error", "0"],
        &["--pixel-error", "nan"],
        &["--fov", "0"],
        &["--eye", "1,2"],
        &["--background", "300,0,0"],
        &["--eye", "0,0,0", "--target", "0,0,0"],
    ] {
        let mut args = vec!["render", model.as_str(), "-o", s(&out)];
        args.extend_from_slice(flags);
        let o = patchwork(&args);
        assert!(!o.status.success(), "{flags:?} accepted");
        assert!(
            !stderr(&o).contains("panicked"),
            "{flags:?}: {}",
            stderr(&o)
        );
        assert!(!out.exists(), "{flags:?} wrote an image");
    }
}

#[test]
fn stats_prints_the_figures() {
    let o = patchwork(&["stats", &teapot()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for key in [
        "patches           32",
        "triangles",
        "border vertices",
        "eps range",
        "tessellation",
    ] {
        assert!(text.contains(key), "missing {key:?} in\n{text}");
    }
}

#[test]
fn check_reports_no_cracks_and_cracks_without_fat_borders() {
    let o = patchwork(&["check", &teapot(), "--views", "3", "--size", "256x192"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}\n{}", stderr(&o));
    assert!(
        text.contains("OK: no crack pixel with fat borders"),
        "{text}"
    );
    assert!(text.contains("fat borders off"), "{text}");
}

#[test]
fn no_adapter_fails_with_what_to_install() {
    // A backend this platform does not have: no adapter can be found.
    let out = out_path("noadapter.png");
    let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["render", &teapot(), "-o", s(&out), "--size", "32x32"])
        .env("WGPU_BACKEND", "metal")
        .output()
        .expect("runs");
    assert!(!o.status.success());
    let msg = stderr(&o);
    assert!(
        msg.contains("no graphics adapter") && msg.contains("mesa-vulkan-drivers"),
        "{msg}"
    );
    assert!(!out.exists());
}

#[test]
fn implode_writes_numbered_frames_a_gif_and_a_csv() {
    let dir = common::scratch("cli-implode");
    let _ = std::fs::remove_dir_all(&dir);
    let o = patchwork(&[
        "implode",
        &teapot(),
        "-o",
        s(&dir),
        "--frames",
        "5",
        "--by",
        "patches",
        "--size",
        "160x120",
        "--check",
        "--no-mp4",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("frames per second"), "{stdout}");
    assert!(stdout.contains("crack pixels"), "{stdout}");
    for k in 0..5 {
        let img = image::open(dir.join(format!("frame-{k:04}.png"))).expect("frame");
        assert_eq!((img.width(), img.height()), (160, 120));
    }
    assert!(!dir.join("frame-0005.png").exists());
    let first = image::open(dir.join("frame-0000.png"))
        .expect("first")
        .to_rgba8();
    let last = image::open(dir.join("frame-0004.png"))
        .expect("last")
        .to_rgba8();
    assert_ne!(first, last, "the patches move");
    let gif = std::fs::read(dir.join("implode.gif")).expect("gif");
    assert!(gif.starts_with(b"GIF89a"));
    let csv = std::fs::read_to_string(dir.join("frames.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 6, "{csv}");
    // No temporary files left behind.
    for entry in std::fs::read_dir(&dir).expect("dir") {
        let name = entry.expect("entry").file_name();
        assert!(!name.to_string_lossy().starts_with('.'), "{name:?}");
    }
}

#[test]
fn implode_rejects_bad_arguments() {
    let dir = common::scratch("cli-implode-bad");
    for (args, why) in [
        (vec!["--frames", "0"], "--frames"),
        (vec!["--distance=-1"], "--distance"),
        (vec!["--by", "atoms"], "parts or patches"),
        (vec!["--fps", "0"], "--fps"),
    ] {
        let mut all = vec!["implode", "models/teapot.bpt", "-o", s(&dir)];
        all.extend(args);
        let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
            .current_dir(common::root())
            .args(&all)
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(2), "{all:?}");
        assert!(stderr(&o).contains(why), "{all:?}: {}", stderr(&o));
    }
    // An output folder named like the GIF: refused before anything is made.
    let gif = dir.join("anim.gif");
    let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .current_dir(common::root())
        .args(["implode", "models/teapot.bpt", "-o", s(&gif)])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("names the output folder"),
        "{}",
        stderr(&o)
    );
    assert!(!gif.exists(), "no folder named anim.gif");
}
