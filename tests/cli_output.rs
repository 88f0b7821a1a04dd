//! The command line for scripts and other tools: `--json` output that parses, `-q`, `render
//! --ref` both ways, named camera views, and exports other tools read (glTF y-up metres with
//! the assembly tree, `.gltf` + `.bin`, STL; an unknown extension refused).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn patchwork(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn out_path(name: &str) -> PathBuf {
    let p = common::scratch("cli-output").join(name);
    let _ = std::fs::remove_file(&p);
    p
}

fn model(name: &str) -> String {
    common::root()
        .join("models")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn json_of(o: &Output) -> Value {
    assert!(
        o.status.code().is_some_and(|c| c <= 1),
        "{}",
        text(&o.stderr)
    );
    let out = text(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 1, "one JSON line on stdout: {out}");
    serde_json::from_str(lines[0]).expect("stdout is JSON")
}

/// `stats --json`: one object with the figures, the box, the up axis and the unit.
#[test]
fn stats_json_parses_and_names_box_up_and_unit() {
    let o = patchwork(&["stats", &model("as1-oc-214.stp"), "--json", "--parts"]);
    let v = json_of(&o);
    assert_eq!(v["patches"], 160);
    assert_eq!(v["instances"], 18);
    assert_eq!(v["up"], "+z");
    assert_eq!(v["unit"], "mm");
    // The box holds the model's true box (Open CASCADE's `BRepBndLib::AddOptimal`: from
    // (−10, 0, −4) to (190, 150, 80) mm) and is at most 2 % of its diagonal larger on each
    // side: each face's box is its load probe's vertices grown by the probe's error and
    // tolerance (2 % of the face's radius), a bound, not the exact box.
    let max = v["bbox"]["max"].as_array().expect("bbox max");
    let min = v["bbox"]["min"].as_array().expect("bbox min");
    let slack = 0.02 * v["diagonal"].as_f64().expect("diagonal");
    let (true_min, true_max) = ([-10.0, 0.0, -4.0], [190.0, 150.0, 80.0]);
    for k in 0..3 {
        let (lo, hi) = (min[k].as_f64().expect("min"), max[k].as_f64().expect("max"));
        assert!(
            hi >= true_max[k] && hi <= true_max[k] + slack,
            "max {k}: {max:?} against {true_max:?}"
        );
        assert!(
            lo <= true_min[k] && lo >= true_min[k] - slack,
            "min {k}: {min:?} against {true_min:?}"
        );
    }
    assert!(v["trimmed"]["error_ratio"].as_f64().expect("ratio") <= 1.0);
    assert_eq!(
        v["instance_list"].as_array().expect("instances").len(),
        18,
        "--parts lists the instances"
    );
    let bpt = json_of(&patchwork(&["stats", &model("teapot.bpt"), "--json"]));
    assert_eq!(bpt["unit"], Value::Null, "a .bpt states no unit");
}

/// `-q`: nothing on stdout or stderr, the file still written; errors still reported.
#[test]
fn quiet_prints_only_errors() {
    let out = out_path("quiet.png");
    let o = patchwork(&[
        "-q",
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&out),
        "--size",
        "64x48",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(text(&o.stdout), "");
    assert!(
        !text(&o.stderr).contains("adapter") && !text(&o.stderr).contains("patches"),
        "{}",
        text(&o.stderr)
    );
    assert!(out.is_file());
    let o = patchwork(&["render", "-q", "no-such-model.bpt", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no-such-model.bpt"));
}

/// `render --ref`: the same picture passes (exit 0), a turned camera fails (exit 1) and writes
/// the FLIP map; a missing reference is an error (exit 2) and writes nothing.
#[test]
fn render_ref_passes_the_same_image_and_fails_another() {
    let reference = out_path("ref.png");
    let size = ["--size", "160x120"];
    let o = patchwork(
        &[
            &["render", &model("teapot.bpt"), "-o", s(&reference)],
            &size[..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));

    let same = out_path("ref-same.png");
    let args = [
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&same),
        "--ref",
        s(&reference),
    ];
    let v = json_of(&patchwork(&[&args[..], &size[..], &["--json"]].concat()));
    assert_eq!(v["reference"]["passed"], true, "{v}");
    assert!(v["reference"]["flip_mean"].as_f64().expect("mean") < 1e-6);

    let turned = out_path("ref-turned.png");
    let diff = out_path("ref-turned-diff.png");
    let args = [
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&turned),
        "--ref",
        s(&reference),
    ];
    let o = patchwork(&[&args[..], &size[..], &["--azimuth", "8"]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    assert!(text(&o.stdout).contains("DIFFERENT"), "{}", text(&o.stdout));
    assert!(diff.is_file(), "the FLIP map is written beside the output");
    // A looser threshold accepts the same pair.
    let o = patchwork(
        &[
            &args[..],
            &size[..],
            &["--azimuth", "8", "--ref-threshold", "0.9"],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stdout));
    assert!(!diff.exists(), "a passing comparison removes a stale map");

    let missing = out_path("ref-missing-out.png");
    let o = patchwork(&[
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&missing),
        "--ref",
        "no-such-reference.png",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no-such-reference.png"));
    assert!(!missing.exists());
}

fn render_rgba(extra: &[&str], name: &str) -> image::RgbaImage {
    let out = out_path(name);
    let as1 = model("as1-oc-214.stp");
    let args = [
        &["render", &as1, "-o", s(&out), "--size", "96x72"][..],
        extra,
    ]
    .concat();
    let o = patchwork(&args);
    assert!(o.status.success(), "{extra:?}: {}", text(&o.stderr));
    image::open(&out).expect("png").to_rgba8()
}

/// Named views are different pictures; `--azimuth 90` from the front is the right view;
/// `--view` with `--eye` is refused.
#[test]
fn named_views_and_turns() {
    let front = render_rgba(&["--view", "front"], "front.png");
    let top = render_rgba(&["--view", "top"], "top.png");
    let right = render_rgba(&["--view", "right"], "right.png");
    let turned = render_rgba(&["--view", "front", "--azimuth", "90"], "turned.png");
    assert_ne!(front, top);
    assert_ne!(front, right);
    let differing = right
        .pixels()
        .zip(turned.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differing * 200 < (96 * 72) as usize,
        "{differing} pixels differ between --view right and front + 90°"
    );
    let o = patchwork(&[
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&out_path("x.png")),
        "--view",
        "top",
        "--eye",
        "1,2,3",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = patchwork(&[
        "render",
        &model("teapot.bpt"),
        "-o",
        s(&out_path("x.png")),
        "--margin",
        "-2",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--margin"));
}

/// World box of a glTF document's meshes, composing the node hierarchy.
fn world_box(doc: &gltf::Document) -> (glam::Vec3, glam::Vec3) {
    fn walk(n: gltf::Node<'_>, parent: glam::Mat4, lo: &mut glam::Vec3, hi: &mut glam::Vec3) {
        let m = parent * glam::Mat4::from_cols_array_2d(&n.transform().matrix());
        if let Some(mesh) = n.mesh() {
            for p in mesh.primitives() {
                let b = p.bounding_box();
                for corner in 0..8 {
                    let pick = |i: usize| {
                        if corner >> i & 1 == 0 {
                            b.min[i]
                        } else {
                            b.max[i]
                        }
                    };
                    let c = m.transform_point3(glam::Vec3::new(pick(0), pick(1), pick(2)));
                    *lo = lo.min(c);
                    *hi = hi.max(c);
                }
            }
        }
        for c in n.children() {
            walk(c, m, lo, hi);
        }
    }
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    for n in doc.default_scene().expect("scene").nodes() {
        walk(n, glam::Mat4::IDENTITY, &mut lo, &mut hi);
    }
    (lo, hi)
}

/// as1 (z-up millimetres) exported as glTF is y-up metres, under one root named after the
/// file, with the sub-assemblies as groups; `.gltf` writes its `.bin`; STL keeps z-up
/// millimetres; `.obj` is refused without writing anything.
#[test]
fn exports_are_y_up_metres_with_the_tree() {
    let glb = out_path("as1.glb");
    let o = patchwork(&["export", &model("as1-oc-214.stp"), "-o", s(&glb)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (doc, _, _) = gltf::import(&glb).expect("imports");
    let roots: Vec<gltf::Node<'_>> = doc.default_scene().expect("scene").nodes().collect();
    assert_eq!(roots.len(), 1);
    assert_eq!(roots[0].name(), Some("as1-oc-214.stp"));
    let mut kids: Vec<&str> = roots[0].children().filter_map(|n| n.name()).collect();
    kids.sort();
    assert_eq!(
        kids,
        vec![
            "l-bracket-assembly_1",
            "l-bracket-assembly_2",
            "plate_1",
            "rod-assembly_1"
        ]
    );
    // as1 spans x 0..180, y 0..150, z 0..80 mm (plus bolts and rod): in y-up metres the
    // height (file y) is the old z, and the depth (file z) is minus the old y.
    let (lo, hi) = world_box(&doc);
    assert!(
        (hi.y - 0.080).abs() < 2e-3 && (lo.y + 0.004).abs() < 2e-3,
        "{lo} {hi}"
    );
    assert!(
        (lo.z + 0.150).abs() < 2e-3 && hi.z.abs() < 2e-3,
        "{lo} {hi}"
    );
    assert!((hi.x - lo.x - 0.2).abs() < 2e-3, "{lo} {hi}");

    let gltf_path = out_path("as1.gltf");
    let bin = out_path("as1.bin");
    let o = patchwork(&[
        "export",
        &model("as1-oc-214.stp"),
        "-o",
        s(&gltf_path),
        "--json",
    ]);
    let v = json_of(&o);
    assert_eq!(v["unit"], "m");
    // Every face of as1 tessellates: none left out (each would be listed, and warned about).
    assert_eq!(v["left_out"], serde_json::json!([]));
    assert!(bin.is_file());
    let (doc2, _, _) = gltf::import(&gltf_path).expect("imports .gltf + .bin");
    assert_eq!(doc2.meshes().count(), doc.meshes().count());

    let stl = out_path("as1.stl");
    let o = patchwork(&["export", &model("as1-oc-214.stp"), "-o", s(&stl)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let bytes = std::fs::read(&stl).expect("stl");
    let count = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as usize;
    assert_eq!(bytes.len(), 84 + 50 * count);
    let mut top = f32::MIN;
    for t in 0..count {
        for k in 0..3 {
            let at = 84 + 50 * t + 12 + 12 * k + 8;
            top = top.max(f32::from_le_bytes(bytes[at..at + 4].try_into().expect("z")));
        }
    }
    assert!(
        (top - 80.0).abs() < 0.5,
        "STL keeps z-up millimetres: top z {top}"
    );

    let obj = out_path("as1.obj");
    let o = patchwork(&["export", &model("as1-oc-214.stp"), "-o", s(&obj)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("unknown export format"));
    assert!(!obj.exists());
    let o = patchwork(&[
        "export",
        &model("teapot.bpt"),
        "-o",
        s(&out_path("t.glb")),
        "--unit",
        "mm",
    ]);
    assert_eq!(o.status.code(), Some(2), "a .bpt states no unit to convert");
}

/// `--only` and `--hide` keep the named instances (by part name, occurrence path or index);
/// a pattern naming nothing is an error that points at `stats --list-parts`.
#[test]
fn only_and_hide_choose_parts() {
    let as1 = model("as1-oc-214.stp");
    let patches = |extra: &[&str]| -> u64 {
        let out = out_path("parts.png");
        let args = [
            &["render", &as1, "-o", s(&out), "--size", "64x48", "--json"][..],
            extra,
        ]
        .concat();
        json_of(&patchwork(&args))["patches"]
            .as_u64()
            .expect("patches")
    };
    let all = patches(&[]);
    assert_eq!(all, 160);
    // rod-assembly_1 = 2 nuts + the rod.
    let rod_assembly = patches(&["--only", "rod-assembly_1"]);
    let nut = patches(&["--only", "#0"]);
    let rod = patches(&["--only", "rod"]);
    assert_eq!(rod_assembly, 2 * nut + rod, "{rod_assembly} {nut} {rod}");
    assert_eq!(patches(&["--hide", "rod-assembly_1"]), all - rod_assembly);
    assert_eq!(
        patches(&["--only", "rod-assembly_1", "--hide", "nut"]),
        rod,
        "--hide applies after --only"
    );
    let o = patchwork(&[
        "render",
        &as1,
        "-o",
        s(&out_path("none.png")),
        "--only",
        "zzz*",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("--list-parts"),
        "{}",
        text(&o.stderr)
    );
    let o = patchwork(&["stats", &as1, "--list-parts"]);
    assert!(text(&o.stdout).contains("rod-assembly_1/nut_1"));
}

/// `check --json` and `bench --flythrough --json`: one object each, with the verdict.
#[test]
fn check_and_bench_json_parse() {
    let teapot = model("teapot.bpt");
    let v = json_of(&patchwork(&[
        "check", &teapot, "--views", "1", "--size", "96x72", "--json",
    ]));
    assert_eq!(v["views"], 1);
    assert_eq!(v["crack_free"], true);
    let names: Vec<&str> = v["variants"]
        .as_array()
        .expect("variants")
        .iter()
        .map(|x| x["fat_borders"].as_str().expect("name"))
        .collect();
    assert_eq!(names, vec!["off", "6", "4", "2"]);
    let (csv, plot) = (out_path("fly.csv"), out_path("fly.png"));
    let v = json_of(&patchwork(&[
        "bench",
        &teapot,
        "--flythrough",
        "--frames",
        "6",
        "--size",
        "96x72",
        "--csv",
        s(&csv),
        "--plot",
        s(&plot),
        "--json",
    ]));
    assert_eq!(v["frames"], 6);
    assert_eq!(v["patches"], 32);
    assert!(v["frame_ms"]["p50"].as_f64().expect("p50") > 0.0);
    assert!(csv.is_file() && plot.is_file());
}

/// `implode` frames the assembled model (its last frame is the model at the size `render`
/// draws it); `--frame-flight` frames the whole flight, so the assembled model is smaller.
#[test]
fn implode_frames_the_assembled_model() {
    let as1 = model("as1-oc-214.stp");
    let covered = |extra: &[&str], tag: &str| -> usize {
        let dir = common::scratch("cli-output").join(tag);
        let _ = std::fs::remove_dir_all(&dir);
        let args = [
            &[
                "implode",
                &as1,
                "-o",
                s(&dir),
                "--frames",
                "3",
                "--size",
                "96x72",
                "--no-gif",
                "--no-mp4",
            ][..],
            extra,
        ]
        .concat();
        let o = patchwork(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
        if extra.contains(&"--json") {
            let v = json_of(&o);
            assert_eq!(v["frames"], 3);
            assert_eq!(v["groups"], 18, "as1's 18 placed solids fly");
            assert_eq!(v["check"], Value::Null, "no --check");
        }
        let last = image::open(dir.join("frame-0002.png"))
            .expect("last frame")
            .to_rgba8();
        last.pixels()
            .filter(|p| p.0[..3] != [255, 255, 255])
            .count()
    };
    let assembled = covered(&["--json"], "implode-assembled");
    let flight = covered(&["--frame-flight"], "implode-flight");
    let render = render_rgba(&[], "implode-render.png")
        .pixels()
        .filter(|p| p.0[..3] != [255, 255, 255])
        .count();
    assert!(assembled > 2 * flight, "{assembled} vs {flight}");
    assert!(
        assembled.abs_diff(render) * 50 < render,
        "the last frame is the rendered model: {assembled} vs {render}"
    );
}

/// `patchwork stats … | head -1`: the reader closes the pipe. `println!` panicked on the
/// next line ("failed printing to stdout: Broken pipe"), exit code 101 and a
/// backtrace; now the command stops printing and ends as it would have.
#[test]
fn stats_into_a_closed_pipe_ends_without_a_panic() {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["stats", &model("teapot.bpt"), "--tolerance", "0.01"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    // Close our end at once: stats loads and tessellates before its first line, so every
    // line it prints meets a closed pipe.
    drop(child.stdout.take().expect("piped"));
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("piped")
        .read_to_string(&mut err)
        .expect("stderr reads");
    let status = child.wait().expect("stats ends");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(status.code(), Some(0), "{err}");
}
