//! Inputs on the command line: several files per run (`stats a b`, `check a b`: one block or
//! one JSON object per file, the exit code the worst) and `-` for stdin with `--format EXT`.

mod common;

use std::io::Write;
use std::process::{Command, Output, Stdio};

use serde_json::Value;

fn model(name: &str) -> String {
    common::root()
        .join("models")
        .join(name)
        .display()
        .to_string()
}

fn patchwork(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(args)
        .env("PATCHWORK_CACHE", "off")
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("patchwork runs");
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().expect("piped");
        // A run that refuses `-` before reading it closes the pipe: a broken pipe is fine.
        let _ = pipe.write_all(bytes);
    }
    child.wait_with_output().expect("patchwork ends")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `stats a b --json`: an array, one object per file in order; text: one block per file,
/// each under a `== FILE ==` line. One file keeps its single object.
#[test]
fn stats_reports_each_file() {
    let (teapot, screw) = (model("teapot.bpt"), model("screw.step"));
    let o = patchwork(&["stats", &teapot, &screw, "--json"], None);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let files: Vec<&str> = v
        .as_array()
        .expect("an array")
        .iter()
        .map(|o| o["file"].as_str().expect("file"))
        .collect();
    assert_eq!(files, [teapot.as_str(), screw.as_str()]);
    assert_eq!(v[0]["patches"], 32);
    let one: Value = serde_json::from_slice(&patchwork(&["stats", &teapot, "--json"], None).stdout)
        .expect("JSON");
    assert!(one.is_object(), "{one}");
    let o = patchwork(&["stats", &teapot, &screw], None);
    let out = text(&o.stdout);
    let blocks: Vec<&str> = out.lines().filter(|l| l.starts_with("== ")).collect();
    assert_eq!(
        blocks,
        [format!("== {teapot} =="), format!("== {screw} ==")]
    );
    assert_eq!(out.matches("\npatches").count(), 2, "{out}");
}

/// A file that cannot be read does not stop the others: its error on stderr, an `error`
/// entry in the JSON array, and exit code 2 (the worst) after every file was tried.
#[test]
fn the_worst_file_sets_the_exit_code() {
    let teapot = model("teapot.bpt");
    for command in ["stats", "check"] {
        let mut args = vec![command, "missing.bpt", &teapot, "--json"];
        if command == "check" {
            args.extend(["--views", "1", "--size", "96x72"]);
        }
        let o = patchwork(&args, None);
        assert_eq!(o.status.code(), Some(2), "{command}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        assert!(
            err.contains("missing.bpt") && err.contains("1 of 2 files failed"),
            "{err}"
        );
        let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
        assert!(
            v[0]["error"]
                .as_str()
                .is_some_and(|e| e.contains("missing.bpt")),
            "{v}"
        );
        assert_eq!(v[1]["file"], teapot.as_str(), "{v}");
    }
    // Both readable: check passes (exit 0) with one verdict per file.
    let o = patchwork(
        &[
            "check", &teapot, &teapot, "--json", "--views", "1", "--size", "96x72",
        ],
        None,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v.as_array().map(Vec::len), Some(2));
    assert!(
        v.as_array()
            .expect("array")
            .iter()
            .all(|o| o["crack_free"] == true)
    );
}

/// `-` reads the model from stdin in the format `--format` names: the same figures as the
/// file; without `--format`, or with a format no reader has, exit 2 with a message that names
/// `<stdin>` (not the temporary file), and no temporary folder is left behind.
#[test]
fn stdin_with_format() {
    let teapot = std::fs::read(model("teapot.bpt")).expect("teapot");
    let o = patchwork(&["stats", "-", "--format", "bpt", "--json"], Some(&teapot));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let file: Value =
        serde_json::from_slice(&patchwork(&["stats", &model("teapot.bpt"), "--json"], None).stdout)
            .expect("JSON");
    assert_eq!(v["patches"], file["patches"]);
    assert_eq!(v["bbox"], file["bbox"]);
    let o = patchwork(&["stats", "-"], Some(&teapot));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("needs --format"),
        "{}",
        text(&o.stderr)
    );
    let step = std::fs::read(model("screw.step")).expect("screw");
    let o = patchwork(&["stats", "-", "--format", "bpt"], Some(&step));
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert!(err.contains("<stdin>") && !err.contains("tmp"), "{err}");
    let o = patchwork(
        &["render", "-", "--format", "../x", "-o", "x.png"],
        Some(&step),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--format"), "{}", text(&o.stderr));
    let left = std::fs::read_dir(std::env::temp_dir())
        .expect("temp dir")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".patchwork-stdin"))
        .collect::<Vec<_>>();
    assert!(left.is_empty(), "left behind: {left:?}");
    // A STEP file through stdin.
    let o = patchwork(&["stats", "-", "--format", "step", "--json"], Some(&step));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["unit"], "mm");
}

/// `render a b`: one scene, each file a top-level part (`--only b` keeps one file).
#[test]
fn render_draws_several_files_as_one_scene() {
    let (teapot, screw) = (model("teapot.bpt"), model("screw.step"));
    let out = common::scratch("cli-inputs").join("two.png");
    let render = |extra: &[&str]| -> Value {
        let mut args = vec![
            "render",
            teapot.as_str(),
            screw.as_str(),
            "--json",
            "--size",
        ];
        args.extend(["160x120", "-o", out.to_str().expect("utf-8 path")]);
        args.extend(extra);
        let o = patchwork(&args, None);
        assert!(o.status.success(), "{}", text(&o.stderr));
        serde_json::from_slice(&o.stdout).expect("JSON")
    };
    assert_eq!(render(&[])["patches"], 32 + 10);
    assert_eq!(render(&["--only", "screw.step"])["patches"], 10);
    assert_eq!(render(&["--hide", "screw.step"])["patches"], 32);
}

/// Merging a glTF (metres, drawn where its points are) with a STEP file (millimetres, placed
/// faces): in either order the STEP file is scaled into metres, and the merge says so.
#[test]
fn a_merge_puts_every_file_in_one_unit() {
    use patchwork::model::merge::{Named, merge};
    let load = |name: &str| Named {
        name: name.to_owned(),
        scene: common::load(name),
    };
    let screw = common::load("screw.step");
    for order in [["alien.glb", "screw.step"], ["screw.step", "alien.glb"]] {
        let m = merge(order.iter().map(|n| load(n)).collect()).expect("merged");
        assert_eq!(m.scene.unit, Some("m"));
        assert!(
            m.notes
                .iter()
                .any(|n| n.contains("screw.step: mm scaled to m")),
            "{:?}",
            m.notes
        );
        let scaled: Vec<_> = m
            .scene
            .patches
            .iter()
            .filter(|p| {
                m.scene.instances[p.instance as usize]
                    .name
                    .starts_with("screw.step")
            })
            .collect();
        assert_eq!(scaled.len(), screw.patches.len());
        for (p, q) in scaled.iter().zip(&screw.patches) {
            assert!((p.bounds.radius - q.bounds.radius * 1e-3).abs() < 1e-12);
            assert!((p.bounds.center - q.bounds.center * 1e-3).length() < 1e-12);
        }
    }
}
