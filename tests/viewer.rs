//! The interactive viewer for real: a window on an X display (a private Xvfb when DISPLAY is
//! not set), scripted frames and keys, the last frame compared with a golden, and the window's
//! pixels read back from the X server (`xwd`) to prove the frame reaches the screen. Needs
//! `xvfb` and `x11-apps` (`.ci/run` installs them); without them these tests fail and say so.

mod common;

use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, Stdio};

use patchwork::check::golden::{GoldenOutcome, Thresholds, compare_with_golden};

/// A display for the viewer: DISPLAY if set, else a private Xvfb killed on drop.
struct Display {
    name: String,
    server: Option<Child>,
}

impl Display {
    fn open() -> Display {
        if let Ok(d) = std::env::var("DISPLAY")
            && !d.is_empty()
        {
            return Display {
                name: d,
                server: None,
            };
        }
        // Xvfb picks a free display number and writes it to fd 1. `-noreset`: by default the
        // server resets when its last client disconnects, and a connection made during the
        // reset is refused (seen once under load: "Failed to open connection to X server").
        let mut server = Command::new("Xvfb")
            .args([
                "-noreset",
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x1024x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| {
                panic!(
                    "the viewer test needs an X display and found neither DISPLAY nor Xvfb \
                     ({e}): apt-get install -y xvfb"
                )
            });
        let mut line = String::new();
        let stdout = server.stdout.take().expect("piped");
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .expect("Xvfb reports its display");
        let n = line.trim();
        assert!(!n.is_empty(), "Xvfb did not start");
        Display {
            name: format!(":{n}"),
            server: Some(server),
        }
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(s) = self.server.as_mut() {
            let _ = s.kill();
            let _ = s.wait();
        }
    }
}

/// Runs `patchwork view` on the teapot for `frames` frames with `keys`, returns the last frame.
fn view(display: &Display, name: &str, frames: usize, keys: &str) -> image::RgbaImage {
    view_with(display, name, frames, keys, &[])
}

/// As [`view`], with more arguments.
fn view_with(
    display: &Display,
    name: &str,
    frames: usize,
    keys: &str,
    extra: &[&str],
) -> image::RgbaImage {
    view_model(display, name, "teapot.bpt", "400x300", frames, keys, extra)
}

/// As [`view_with`], on `models/MODEL` in a window of `size`.
fn view_model(
    display: &Display,
    name: &str,
    model: &str,
    size: &str,
    frames: usize,
    keys: &str,
    extra: &[&str],
) -> image::RgbaImage {
    let out = common::scratch("viewer").join(format!("{name}.png"));
    let _ = std::fs::remove_file(&out);
    let model = common::root().join("models").join(model);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_patchwork"));
    cmd.arg("view")
        .arg(&model)
        .args(["--size", size, "--frames", &frames.to_string()])
        .arg("--screenshot")
        .arg(&out)
        .args(extra)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY");
    if !keys.is_empty() {
        cmd.args(["--keys", keys]);
    }
    let result = cmd.output().expect("patchwork runs");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "viewer failed: {stderr}");
    // Every frame reached the window.
    assert!(
        stderr.contains(&format!("{frames} frames ({frames} presented)")),
        "{stderr}"
    );
    image::open(&out).expect("screenshot written").to_rgba8()
}

fn surface_pixels(img: &image::RgbaImage) -> impl Iterator<Item = [u8; 3]> + '_ {
    img.pixels()
        .map(|p| [p.0[0], p.0[1], p.0[2]])
        .filter(|c| *c != [255, 255, 255])
}

#[test]
fn scripted_frames_match_the_golden() {
    let display = Display::open();
    let img = view(&display, "teapot", 8, "");
    let golden = common::root().join("golden/viewer-teapot.png");
    match compare_with_golden(&golden, &img, Thresholds::default()) {
        Ok(GoldenOutcome::Matched(score)) => eprintln!("viewer: {score:?}"),
        Ok(GoldenOutcome::Updated) => eprintln!("viewer: golden rewritten (GOLDEN_UPDATE=1)"),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn keys_switch_the_heat_map_and_patch_ids() {
    let display = Display::open();
    // Heat map after the queue has settled: every visible patch on target (green).
    let heat = view(&display, "heat", 6, "h");
    let (mut green, mut all) = (0, 0);
    for c in surface_pixels(&heat) {
        all += 1;
        if c[1] > c[0] && c[1] > c[2] {
            green += 1;
        }
    }
    assert!(all > 10_000, "the teapot covers the view: {all}");
    assert!(
        green * 100 >= all * 95,
        "{green} of {all} surface pixels green"
    );
    // Patch-ID colours: many distinct colours, none of them the lit grey.
    let ids = view(&display, "ids", 3, "i");
    let colours: std::collections::BTreeSet<[u8; 3]> = surface_pixels(&ids).collect();
    assert!(colours.len() >= 20, "{} colours", colours.len());
}

/// `e` cycles the edges off → feature → all → off; `--edges` sets the first mode.
#[test]
fn the_e_key_cycles_the_edges() {
    let display = Display::open();
    // Edge pixels are near black; the lit teapot's darkest shade is above 40.
    let dark = |img: &image::RgbaImage| {
        img.pixels()
            .filter(|p| p.0[..3].iter().all(|&c| c < 30))
            .count()
    };
    let off = dark(&view(&display, "edges-off", 3, ""));
    let feature = dark(&view(&display, "edges-feature", 3, "e"));
    let all = dark(&view(&display, "edges-all", 3, "e,e"));
    let again = dark(&view(&display, "edges-off-again", 4, "e,e,e"));
    let flag = dark(&view_with(
        &display,
        "edges-flag",
        3,
        "",
        &["--edges", "all"],
    ));
    assert!(off < 10, "{off} dark pixels without edges");
    // Feature edges: the rims of the lid and the body, the spout's end (~100 pixels at
    // 400 x 300); all edges: every patch border too (~1 000).
    assert!(feature > 50, "{feature} edge pixels with feature edges");
    assert!(all > 3 * feature, "all {all}, feature {feature}");
    assert!(again < 10, "{again} dark pixels after cycling back");
    assert!(
        flag.abs_diff(all) * 10 <= all,
        "--edges all {flag}, e,e {all}"
    );
}

/// Bounding box (width, height) of the non-background pixels.
fn extent(img: &image::RgbaImage) -> (u32, u32) {
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for (x, y, p) in img.enumerate_pixels() {
        if [p.0[0], p.0[1], p.0[2]] != [255, 255, 255] {
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        }
    }
    (x1.saturating_sub(x0), y1.saturating_sub(y0))
}

#[test]
fn implode_plays_and_space_pauses() {
    let display = Display::open();
    let args = ["--implode", "--by", "patches", "--implode-frames", "6"];
    // Played: 6 frames of implosion, then assembled.
    let played = view_with(&display, "implode-played", 8, "", &args);
    // Paused at once: still exploded.
    let paused = view_with(&display, "implode-paused", 8, "space", &args);
    let (a, b) = (extent(&played), extent(&paused));
    assert!(
        b.0 > a.0 * 3 / 2 && b.1 > a.1 * 3 / 2,
        "exploded {b:?} vs assembled {a:?}"
    );
    // Resumed after a pause: it plays on to the assembled teapot.
    let resumed = view_with(&display, "implode-resumed", 9, "space,space", &args);
    assert_eq!(extent(&resumed), a);
}

/// The X server's root window as RGB rows, read with `xwd` (ZPixmap, 24/32 bits per pixel).
fn capture_root(display: &Display) -> Option<(usize, usize, Vec<[u8; 3]>)> {
    let out = Command::new("xwd")
        .args(["-root", "-silent", "-display", &display.name])
        .output()
        .unwrap_or_else(|e| {
            panic!("reading the screen needs xwd ({e}): apt-get install -y x11-apps")
        });
    if !out.status.success() {
        return None;
    }
    let b = out.stdout;
    let u32_at = |i: usize| -> Option<u32> {
        let s = b.get(4 * i..4 * i + 4)?;
        Some(u32::from_be_bytes([s[0], s[1], s[2], s[3]]))
    };
    let header = u32_at(0)? as usize;
    let (format, width, height) = (u32_at(2)?, u32_at(4)? as usize, u32_at(5)? as usize);
    let (byte_order, bpp, line) = (u32_at(7)?, u32_at(11)?, u32_at(12)? as usize);
    let masks = [u32_at(14)?, u32_at(15)?, u32_at(16)?];
    let ncolors = u32_at(19)? as usize;
    assert_eq!(format, 2, "xwd: not a ZPixmap");
    assert!(bpp == 32 || bpp == 24, "xwd: {bpp} bits per pixel");
    let data = b.get(header + 12 * ncolors..)?;
    let step = bpp as usize / 8;
    let mut pixels = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let o = y * line + x * step;
            let p = data.get(o..o + step)?;
            let mut v = [0u8; 4];
            v[..step].copy_from_slice(p);
            let v = if byte_order == 0 {
                u32::from_le_bytes(v)
            } else {
                u32::from_be_bytes(v) >> (8 * (4 - step))
            };
            let channel = |m: u32| ((v & m) >> m.trailing_zeros()) as u8;
            pixels.push([channel(masks[0]), channel(masks[1]), channel(masks[2])]);
        }
    }
    Some((width, height, pixels))
}

#[test]
fn the_window_shows_the_frame() {
    let display = Display::open();
    let out = common::scratch("viewer").join("window.png");
    let _ = std::fs::remove_file(&out);
    // Enough frames to keep the window open while the screen is read; the camera is still,
    // so after the first frames every frame is the same picture.
    let mut child = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .arg("view")
        .arg(common::root().join("models/teapot.bpt"))
        .args(["--size", "400x300", "--frames", "400", "--keys", "h"])
        .arg("--screenshot")
        .arg(&out)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .stderr(Stdio::null())
        .spawn()
        .expect("patchwork runs");
    // Wait until the heat-map teapot (green) shows at the top left (no window manager on
    // Xvfb: the window sits at the origin).
    let start = std::time::Instant::now();
    let mut screen = None;
    while start.elapsed() < std::time::Duration::from_secs(30) {
        std::thread::sleep(std::time::Duration::from_millis(300));
        if let Some((w, h, px)) = capture_root(&display)
            && w >= 400
            && h >= 300
        {
            let green = (0..300)
                .flat_map(|y| (0..400).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let c = px[y * w + x];
                    c[1] > 100 && c[1] > c[0] + 40 && c[1] > c[2] + 40
                })
                .count();
            if green > 5_000 {
                screen = Some((w, px));
                break;
            }
        }
    }
    let status = child.wait().expect("viewer exits");
    assert!(status.success());
    let (w, px) = screen.expect("the teapot never showed in the window");
    // The window's pixels are the frame the viewer drew (its last frame, written at exit).
    let shot = image::open(&out).expect("screenshot").to_rgba8();
    let mut differ = 0;
    for y in 0..300 {
        for x in 0..400 {
            let a = px[y * w + x];
            let b = shot.get_pixel(x as u32, y as u32).0;
            if (0..3).any(|k| (a[k] as i32 - b[k] as i32).abs() > 2) {
                differ += 1;
            }
        }
    }
    if differ * 1000 > 400 * 300 {
        let mut img = image::RgbImage::new(400, 300);
        for (x, y, p) in img.enumerate_pixels_mut() {
            p.0 = px[y as usize * w + x as usize];
        }
        let saved = common::scratch("viewer").join("window-actual.png");
        img.save(&saved).expect("scratch is writable");
        panic!(
            "{differ} of 120000 pixels differ between the window ({}) and the frame ({})",
            saved.display(),
            out.display()
        );
    }
}

#[test]
fn without_a_display_the_viewer_says_what_to_do() {
    let model = common::root().join("models/teapot.bpt");
    let result = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .arg("view")
        .arg(Path::new(&model))
        .args(["--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("patchwork runs");
    assert_eq!(result.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("xvfb"), "{stderr}");
    assert!(
        !stderr.contains(".cargo") && !stderr.contains("registry") && !stderr.contains(".."),
        "no path inside the dependencies, no double stop: {stderr}"
    );
}

/// A mesh is shown at once at full resolution; its hierarchies, built on a background thread,
/// replace it while the viewer runs and land in the cache, from which the next run reads them.
#[test]
fn a_mesh_is_shown_at_once_and_its_hierarchies_swapped_in() {
    let display = Display::open();
    let dir = common::scratch("viewer").join("mesh-swap");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    // A bumpy 40 × 40 grid, 3 200 triangles.
    let n = 40u32;
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 * 0.1, j as f32 * 0.1);
            obj += &format!("v {x} {y} {}\n", 0.2 * (3.0 * x).sin() * (2.0 * y).cos());
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            obj += &format!("f {} {} {}\n", at(i, j), at(i + 1, j), at(i + 1, j + 1));
            obj += &format!("f {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
    let model = dir.join("grid.obj");
    std::fs::write(&model, obj).expect("writes the model");
    let cache = dir.join("cache");
    let run = || {
        let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
            .arg("view")
            .arg(&model)
            .args(["--size", "320x240", "--frames", "40"])
            .arg("--screenshot")
            .arg(dir.join("last.png"))
            .env("DISPLAY", &display.name)
            .env("PATCHWORK_CACHE", &cache)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("patchwork runs");
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "viewer failed: {stderr}");
        stderr
    };
    let first = run();
    assert!(first.contains("hierarchies built"), "{first}");
    assert!(
        first.contains("hierarchies ready"),
        "never swapped: {first}"
    );
    let files = std::fs::read_dir(&cache).map_or(0, |d| d.count());
    assert_eq!(files, 1, "cache not written");
    let second = run();
    assert!(
        !second.contains("hierarchies built") && !second.contains("hierarchies ready"),
        "the cache was not used: {second}"
    );
}

/// A scripted `q` draws its frame, writes the screenshot and closes (exit 0): `--keys z,q`
/// with 6 frames draws 2; `view --help` lists the keys.
#[test]
fn scripted_quit_still_writes_the_screenshot() {
    let display = Display::open();
    let out = common::scratch("viewer").join("quit.png");
    let _ = std::fs::remove_file(&out);
    let result = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .arg("view")
        .arg(common::root().join("models/teapot.bpt"))
        .args([
            "--size",
            "200x150",
            "--frames",
            "6",
            "--keys",
            "z,q",
            "--screenshot",
        ])
        .arg(&out)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("patchwork runs");
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.contains("2 frames (2 presented)"), "{stderr}");
    assert!(out.is_file(), "the screenshot is written: {stderr}");
    let help = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["view", "--help"])
        .output()
        .expect("help");
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("wireframe") && help.contains("PageUp"),
        "{help}"
    );
}

/// `--ortho` starts orthographic, framed as `render --ortho` frames it (same extent); the
/// `5` key toggles back to perspective (a different image); `view --help` names the key.
#[test]
fn ortho_flag_and_the_5_key() {
    let display = Display::open();
    let ortho = view_with(&display, "ortho", 4, "", &["--ortho"]);
    let toggled = view_with(&display, "ortho-5", 4, "5", &["--ortho"]);
    let out = common::scratch("viewer").join("ortho-render.png");
    let r = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .arg("render")
        .arg(common::root().join("models/teapot.bpt"))
        .args(["--size", "400x300", "--ortho", "-q", "-o"])
        .arg(&out)
        .output()
        .expect("patchwork runs");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let rendered = image::open(&out).expect("rendered").to_rgba8();
    let (a, b) = (extent(&ortho), extent(&rendered));
    assert!(
        a.0.abs_diff(b.0) <= 2 && a.1.abs_diff(b.1) <= 2,
        "viewer {a:?} vs render {b:?}"
    );
    let differ = ortho
        .pixels()
        .zip(toggled.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 24))
        .count();
    assert!(differ > 500, "key 5 changed {differ} pixels");
    let help = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["view", "--help"])
        .output()
        .expect("help");
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("5 orthographic / perspective"), "{help}");
}

/// Share of pixels that differ between two images of one size.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let n = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    n as f64 / (a.width() * a.height()) as f64
}

#[test]
fn section_flag_and_the_c_key() {
    let display = Display::open();
    let plain = view(&display, "section-plain", 6, "");
    let cut = ["--section", "0,0,0,0,-1,0"];
    let sectioned = view_with(&display, "section-cut", 6, "", &cut);
    // `c` on the first frame turns the planes off: the plain teapot again.
    let toggled = view_with(&display, "section-off", 6, "c", &cut);
    let (d_cut, d_off) = (differing(&plain, &sectioned), differing(&plain, &toggled));
    assert!(
        d_cut > 0.05,
        "--section changed {:.1} % of the pixels",
        d_cut * 100.0
    );
    assert!(
        d_off < 0.002,
        "with c, {:.2} % of the pixels differ",
        d_off * 100.0
    );
}

/// The part panel's tests run on the l-bracket assembly (18 placed parts) in a 640 × 480
/// window; the panel is 240 pixels wide on the left (Xvfb: one pixel per point). Rows as
/// egui 0.37 lays them out (Cargo.lock pins it): "colour by part" at y 36, the explode
/// slider from x 14 to 108 at y 59, the tree from y 114 in rows of 23 — the third,
/// `plate_1` (instance 10), is a leaf with its checkbox at x 15.
fn view_assembly(display: &Display, name: &str, frames: usize, keys: &str) -> image::RgbaImage {
    view_model(
        display,
        name,
        "as1-oc-214.stp",
        "640x480",
        frames,
        keys,
        &[],
    )
}

/// `t` opens the panel: the window's left 240 columns show it (dark, with its rows) where
/// the frame — written without the panel — shows the model and white; the rest of the
/// window is the frame. The capture is kept as `panel-window.png` (README's picture).
#[test]
fn the_t_key_shows_the_part_panel() {
    let display = Display::open();
    let out = common::scratch("viewer").join("panel-frame.png");
    let _ = std::fs::remove_file(&out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .arg("view")
        .arg(common::root().join("models/as1-oc-214.stp"))
        .args(["--size", "640x480", "--frames", "300", "--keys", "t"])
        .arg("--screenshot")
        .arg(&out)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .stderr(Stdio::null())
        .spawn()
        .expect("patchwork runs");
    let dark = |c: [u8; 3]| c.iter().all(|&v| v < 60);
    let start = std::time::Instant::now();
    let mut screen = None;
    while start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(300));
        if let Some((w, h, px)) = capture_root(&display)
            && w >= 640
            && h >= 480
        {
            let panel = (0..480)
                .flat_map(|y| (0..240).map(move |x| (x, y)))
                .filter(|&(x, y)| dark(px[y * w + x]))
                .count();
            // The model shows right of the panel too (the frame reached the window).
            let model = (0..480)
                .flat_map(|y| (240..640).map(move |x| (x, y)))
                .filter(|&(x, y)| px[y * w + x] != [255, 255, 255] && !dark(px[y * w + x]))
                .count();
            if panel > 240 * 480 * 8 / 10 && model > 5_000 {
                screen = Some((w, px));
                break;
            }
        }
    }
    let status = child.wait().expect("viewer exits");
    assert!(status.success());
    let (w, px) = screen.expect("the panel never showed in the window");
    let mut img = image::RgbImage::new(640, 480);
    for (x, y, p) in img.enumerate_pixels_mut() {
        p.0 = px[y as usize * w + x as usize];
    }
    let saved = common::scratch("viewer").join("panel-window.png");
    img.save(&saved).expect("scratch is writable");
    let shot = image::open(&out).expect("screenshot").to_rgba8();
    let differs = |x: usize, y: usize| {
        let (a, b) = (px[y * w + x], shot.get_pixel(x as u32, y as u32).0);
        (0..3).any(|k| a[k].abs_diff(b[k]) > 2)
    };
    let in_panel = (0..480)
        .flat_map(|y| (0..240).map(move |x| (x, y)))
        .filter(|&(x, y)| differs(x, y))
        .count();
    let outside = (0..480)
        .flat_map(|y| (240..640).map(move |x| (x, y)))
        .filter(|&(x, y)| differs(x, y))
        .count();
    assert!(
        in_panel > 240 * 480 * 9 / 10,
        "{in_panel} panel pixels differ from the frame ({})",
        saved.display()
    );
    assert!(
        outside < 400 * 480 / 100,
        "{outside} pixels right of the panel differ from the frame ({})",
        saved.display()
    );
}

/// Pixels that are not the white background.
fn covered(img: &image::RgbaImage) -> usize {
    img.pixels()
        .filter(|p| [p.0[0], p.0[1], p.0[2]] != [255, 255, 255])
        .count()
}

/// Unchecking `plate_1` in the panel (a scripted click on its checkbox, through egui) draws
/// the assembly without the plate: the same image as `part:10` (the panel's own hook),
/// far fewer pixels covered than with every part; `isolate` keeps only the plate.
#[test]
fn unchecking_a_part_in_the_panel_hides_it() {
    let display = Display::open();
    let all = view_assembly(&display, "panel-all", 5, "t");
    let clicked = view_assembly(&display, "panel-uncheck", 5, "t,z,click:15:160");
    let hooked = view_assembly(&display, "panel-part10", 5, "t,z,part:10");
    let (a, c) = (covered(&all), covered(&clicked));
    assert!(
        c * 10 < a * 7,
        "the plate hidden: {c} pixels covered, {a} with every part"
    );
    assert!(
        differing(&clicked, &hooked) < 0.001,
        "click and part:10 differ in {:.2} % of the pixels",
        differing(&clicked, &hooked) * 100.0
    );
    // `isolate` on the plate's row: the plate alone, which covers less than all but far
    // more than the rest without it.
    let isolated = view_assembly(&display, "panel-isolate", 5, "t,z,click:100:160");
    let i = covered(&isolated);
    assert!(i < a && i > a - c, "isolated {i}, all {a}, without {c}");
}

/// The explode slider (a scripted click near its right end) moves the parts apart: what
/// they cover spreads wider and taller, and `explode:0` is the assembled picture.
#[test]
fn the_explode_slider_moves_the_parts() {
    let display = Display::open();
    let assembled = view_assembly(&display, "explode-0", 5, "t");
    let exploded = view_assembly(&display, "explode-click", 5, "t,z,click:60:59");
    let back = view_assembly(&display, "explode-back", 6, "t,z,click:60:59,z,explode:0");
    let (a, e) = (extent(&assembled), extent(&exploded));
    assert!(
        e.0 > a.0 * 5 / 4 && e.1 > a.1 * 5 / 4,
        "exploded {e:?}, assembled {a:?}"
    );
    assert!(
        differing(&assembled, &back) < 0.001,
        "back at 0: {:.2} % differ",
        differing(&assembled, &back) * 100.0
    );
}

/// Without `--section`, `c` cuts the model with a plane through its centre facing the
/// viewer (capped: the cut shows the model's colours, no hole to the background); `]`
/// moves it along its normal (less cut away), `c` again removes it.
#[test]
fn the_c_key_cuts_the_model_and_brackets_move_the_plane() {
    let display = Display::open();
    let plain = view(&display, "cut-plain", 6, "");
    let cut = view(&display, "cut-c", 6, "c");
    let moved = view(&display, "cut-moved", 8, "c,],]");
    let removed = view(&display, "cut-removed", 6, "c,c");
    let d = differing(&plain, &cut);
    assert!(d > 0.05, "c changed {:.1} % of the pixels", d * 100.0);
    let m = differing(&cut, &moved);
    assert!(
        m > 0.01,
        "] moved the cut by {:.2} % of the pixels",
        m * 100.0
    );
    // The cap: the cut teapot covers (nearly) what the whole one covers.
    let (p, c) = (covered(&plain), covered(&cut));
    assert!(c * 10 > p * 8, "cut covers {c} pixels, whole {p}");
    let r = differing(&plain, &removed);
    assert!(r < 0.002, "c, c: {:.2} % differ", r * 100.0);
}

/// What the panel hides is not in the drawn scene (`Panel::shown`: no patch of a hidden
/// instance, so neither its surfaces nor its fat borders nor its edges are drawn), and what
/// stays is drawn crack-free: the crack check over random views of the assembly without
/// its plate and one bracket assembly, coloured by part.
#[test]
fn hidden_parts_leave_the_drawn_scene_which_stays_crack_free() {
    use patchwork::check::{CheckOptions, run_check};
    let full = common::load("as1-oc-214.stp");
    let mut panel = patchwork::viewer::Panel::new(&full);
    panel.toggle(10);
    for i in 11..=17 {
        panel.toggle(i);
    }
    panel.colour_by_part = true;
    let shown = panel.shown(&full);
    let hidden = |p: &patchwork::model::Patch| p.instance == 10 || p.instance >= 11;
    let kept = full.patches.iter().filter(|p| !hidden(p)).count();
    assert_eq!(shown.patches.len(), kept);
    assert!(kept > 0 && kept < full.patches.len());
    assert!(shown.patches.iter().all(|p| !hidden(p)));
    assert!(
        shown
            .patches
            .iter()
            .all(|p| p.color == Some(patchwork::viewer::part_colour(p.part)))
    );
    let mut renderer = common::renderer();
    let opts = CheckOptions {
        views: 6,
        save_failures: Some(common::scratch("viewer-hidden-cracks")),
        ..CheckOptions::default()
    };
    let r = run_check(&mut renderer, &shown, &opts, |_| {}).expect("rendering works");
    assert!(
        r.crack_free(),
        "{:?}",
        r.total(patchwork::render::FatBorders::Six)
    );
}
