//! Honest output (issue 21): a full disk is an error and the previous file stays
//! byte-identical; permissions and symlinks of a replaced file are kept; SIGTERM during a write
//! leaves no temporary file; `implode` never leaves a stale or short frame set.
//!
//! A full disk is simulated in the child process with a file-size limit (`ulimit -f`, with
//! SIGXFSZ ignored so that a write past the limit fails with EFBIG instead of killing it).

#![cfg(unix)]

mod common;

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_patchwork")
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

fn fresh(name: &str) -> PathBuf {
    let dir = common::scratch("honest-writes").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs the binary with files limited to `blocks` × 512 bytes (dash) or × 1 KiB (bash).
fn patchwork_limited(blocks: u32, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -f {blocks} && trap '' XFSZ && exec \"$0\" \"$@\""
        ))
        .arg(bin())
        .args(args)
        .env("PATCHWORK_CACHE", "off")
        .env("MESA_SHADER_CACHE_DISABLE", "true")
        .output()
        .expect("sh runs")
}

fn patchwork(args: &[&str]) -> Output {
    Command::new(bin())
        .args(args)
        .env("PATCHWORK_CACHE", "off")
        .output()
        .expect("the binary runs")
}

/// Names in `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_full_disk_is_an_error_and_the_old_image_stays() {
    let dir = fresh("full");
    let out = dir.join("view.png");
    let depth = dir.join("depth.png");
    let old: Vec<u8> = (0..6000u32).map(|k| (k * 7 % 251) as u8).collect();
    std::fs::write(&out, &old).expect("old image");
    // The control: without the limit the same command replaces it.
    let args = [
        "render",
        &teapot(),
        "-o",
        s(&out),
        "--size",
        "160x120",
        "--depth-out",
        s(&depth),
    ];
    let o = patchwork_limited(1, &args);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("view.png") && e.contains("cannot write"), "{e}");
    assert!(e.contains("File too large"), "{e}");
    assert_eq!(std::fs::read(&out).expect("old"), old, "old image changed");
    assert_eq!(entries(&dir), ["view.png"]);

    let o = patchwork(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(image::open(&out).is_ok());
    assert_eq!(entries(&dir), ["depth.png", "view.png"]);
}

#[test]
fn a_full_disk_during_implode_keeps_the_previous_run() {
    let dir = fresh("implode-full");
    let out = dir.join("anim");
    let args = |frames: &'static str| {
        vec![
            "implode".to_owned(),
            teapot(),
            "-o".to_owned(),
            s(&out).to_owned(),
            "--frames".to_owned(),
            frames.to_owned(),
            "--size".to_owned(),
            "96x72".to_owned(),
            "--no-mp4".to_owned(),
        ]
    };
    let a = args("3");
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let o = patchwork(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    let before: Vec<(String, Vec<u8>)> = entries(&out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).expect("read");
            (n, bytes)
        })
        .collect();
    assert_eq!(before.len(), 5, "3 frames, the GIF, frames.csv");
    let b = args("4");
    let b: Vec<&str> = b.iter().map(String::as_str).collect();
    let o = patchwork_limited(1, &b);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot write"), "{}", stderr(&o));
    let after: Vec<(String, Vec<u8>)> = entries(&out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).expect("read");
            (n, bytes)
        })
        .collect();
    assert!(
        before == after,
        "the previous run changed: {:?}",
        entries(&out)
    );
}

#[test]
fn a_shorter_implode_removes_the_longer_runs_frames() {
    let dir = fresh("implode-stale");
    let out = dir.join("anim");
    std::fs::create_dir_all(&out).expect("out");
    // Not ours: kept.
    std::fs::write(out.join("notes.txt"), b"mine").expect("notes");
    std::fs::write(out.join("frame-cover.png"), b"mine").expect("cover");
    for (frames, gif) in [("6", false), ("2", true)] {
        let mut args = vec![
            "implode",
            "models/teapot.bpt",
            "-o",
            s(&out),
            "--frames",
            frames,
            "--size",
            "64x48",
            "--no-mp4",
        ];
        if !gif {
            args.push("--no-gif");
        }
        let o = Command::new(bin())
            .current_dir(common::root())
            .args(&args)
            .env("PATCHWORK_CACHE", "off")
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(
        entries(&out),
        [
            "frame-0000.png",
            "frame-0001.png",
            "frame-cover.png",
            "frames.csv",
            "implode.gif",
            "notes.txt"
        ]
    );
    let csv = std::fs::read_to_string(out.join("frames.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 3, "{csv}");
}

#[test]
fn permissions_and_symlinks_of_the_output_are_kept() {
    let dir = fresh("perm");
    let out = dir.join("private.png");
    std::fs::write(&out, b"old").expect("old");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    let o = patchwork(&["render", &teapot(), "-o", s(&out), "--size", "32x24"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(image::open(&out).is_ok());
    let mode = std::fs::metadata(&out).expect("meta").permissions().mode();
    assert_eq!(mode & 0o777, 0o600, "mode {mode:o}");

    let real = dir.join("images").join("real.png");
    std::fs::create_dir_all(real.parent().expect("parent")).expect("images");
    std::fs::write(&real, b"old").expect("old");
    let link = dir.join("latest.png");
    std::os::unix::fs::symlink("images/real.png", &link).expect("symlink");
    let o = patchwork(&["render", &teapot(), "-o", s(&link), "--size", "32x24"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = std::fs::symlink_metadata(&link).expect("link");
    assert!(meta.file_type().is_symlink(), "the link was replaced");
    assert!(image::open(&real).is_ok(), "the target was not written");
    assert_eq!(entries(&dir), ["images", "latest.png", "private.png"]);
    assert_eq!(entries(&dir.join("images")), ["real.png"]);
}

/// Whether `dir` holds a temporary file of ours.
fn has_temporary(dir: &Path) -> bool {
    entries(dir)
        .iter()
        .any(|n| n.starts_with('.') && n.contains(".tmp"))
}

#[test]
fn sigterm_during_a_write_leaves_no_temporary_file() {
    let dir = fresh("signal");
    let out = dir.join("big.png");
    // A large image: its PNG takes a while to encode, so the temporary file lives long enough
    // to be caught. A run that finishes before the signal is tried again.
    for attempt in 0..5 {
        let mut child = Command::new(bin())
            .args(["render", &teapot(), "-o", s(&out), "--size", "3000x2000"])
            .env("PATCHWORK_CACHE", "off")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        let start = Instant::now();
        let mut seen = false;
        while start.elapsed() < Duration::from_secs(120) {
            if has_temporary(&dir) {
                seen = true;
                break;
            }
            if child.try_wait().expect("wait").is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        if seen {
            let kill = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status()
                .expect("kill");
            assert!(kill.success());
        }
        let o = child.wait_with_output().expect("wait");
        assert!(!has_temporary(&dir), "left: {:?}", entries(&dir));
        if seen && o.status.code() == Some(143) {
            assert!(
                stderr(&o).contains("temporary output file(s) removed"),
                "{}",
                stderr(&o)
            );
            return;
        }
        eprintln!(
            "attempt {attempt}: finished before the signal ({:?})",
            o.status
        );
    }
    panic!("never caught a write in progress");
}
