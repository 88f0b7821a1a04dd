//! Sharded `check` and `bench --scale` runs (issue 33): shards merge to what the unsharded
//! run prints and exits with; `merge` refuses shards that are missing, given twice or of
//! another run; `--shard auto` reads the batch engine's index; the Slurm script and the
//! Kubernetes manifest's scripts run with a fake index and their merge step gives the
//! unsharded result.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Every variable `--shard auto` reads: removed from each child, so that the machine the
/// tests run on (a GitLab runner, a Slurm node) does not choose a shard.
const ENGINE_VARIABLES: [&str; 9] = [
    "JOB_COMPLETION_INDEX",
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_ARRAY_TASK_STEP",
    "SLURM_ARRAY_TASK_COUNT",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "CI_NODE_INDEX",
    "CI_NODE_TOTAL",
];

/// The corpus: paths relative to the repository root (case ids are the paths as given).
const TEAPOT: &str = "models/teapot.bpt";
const SCREW: &str = "models/screw.step";
/// Small, quick views; the stress tessellation makes the uncovered cracks show (fat borders
/// off) and, on the teapot's view 0, one crack pixel with the narrowest fat borders: the run
/// fails (exit 1), so the merge must reproduce a failure, not only a pass.
const CHECK_ARGS: [&str; 5] = ["--views", "6", "--size", "160x120", "--stress"];

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_patchwork")
}

/// A command run in the repository root, without any batch engine's variables.
fn command(program: &str) -> Command {
    let mut c = Command::new(program);
    c.current_dir(common::root());
    for v in ENGINE_VARIABLES {
        c.env_remove(v);
    }
    c
}

fn patchwork(args: &[&str]) -> Output {
    command(bin()).args(args).output().expect("the binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn code(o: &Output) -> i32 {
    o.status.code().expect("exited, not killed")
}

/// A fresh scratch folder.
fn fresh(name: &str) -> PathBuf {
    let dir = common::scratch("shard").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A model file that fails to load, at a path relative to the repository root.
fn bad_model() -> &'static str {
    static BAD: OnceLock<()> = OnceLock::new();
    const PATH: &str = "target/test-output/shard/bad.bpt";
    BAD.get_or_init(|| {
        common::scratch("shard");
        std::fs::write(common::root().join(PATH), "1\n3 3\n0 0 nan\n").expect("bad model");
    });
    PATH
}

/// A corpus list (`--files-from`) of the teapot and the screw.
fn corpus_list() -> PathBuf {
    let list = common::scratch("shard").join("files.txt");
    std::fs::write(&list, format!("# the corpus\n{TEAPOT}\n\n{SCREW}\n")).expect("list");
    list
}

fn check_args<'a>(files: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["check"];
    args.extend_from_slice(files);
    args.extend_from_slice(&CHECK_ARGS);
    args.extend_from_slice(more);
    args
}

/// The unsharded run of the teapot and the screw: stdout, exit code, time.
fn unsharded() -> &'static (String, i32, Duration) {
    static RUN: OnceLock<(String, i32, Duration)> = OnceLock::new();
    RUN.get_or_init(|| {
        let t = Instant::now();
        let o = patchwork(&check_args(&[TEAPOT, SCREW], &[]));
        let elapsed = t.elapsed();
        assert_eq!(
            code(&o),
            1,
            "the corpus fails unsharded: {}",
            text(&o.stderr)
        );
        (text(&o.stdout), 1, elapsed)
    })
}

/// Runs `check --shard I/total --out DIR/shard-I.json` for every shard of `files`; returns the
/// shard files and the longest shard's time.
fn run_shards(dir: &Path, files: &[&str], more: &[&str], total: usize) -> (Vec<PathBuf>, Duration) {
    let mut paths = Vec::new();
    let mut longest = Duration::ZERO;
    for i in 1..=total {
        let path = dir.join(format!("shard-{i}.json"));
        let shard = format!("{i}/{total}");
        let mut args = check_args(files, more);
        args.extend_from_slice(&["--shard", &shard, "--out", s(&path)]);
        let t = Instant::now();
        let o = patchwork(&args);
        longest = longest.max(t.elapsed());
        assert!(
            path.exists(),
            "shard {shard} wrote no file (exit {}): {}",
            code(&o),
            text(&o.stderr)
        );
        paths.push(path);
    }
    (paths, longest)
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).expect("shard file");
    serde_json::from_str(&text).expect("shard JSON")
}

fn merge(paths: &[&Path], more: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(paths.iter().map(|p| s(p)));
    args.extend_from_slice(more);
    patchwork(&args)
}

#[test]
fn three_shards_merge_to_the_unsharded_run() {
    let (want, want_code, unsharded_time) = unsharded();
    let dir = fresh("three");
    let (paths, longest) = run_shards(&dir, &[TEAPOT, SCREW], &[], 3);
    for p in &paths {
        let cases = json(p)["cases"].as_array().map_or(0, Vec::len);
        assert!(cases > 0, "{}: every shard has cases here", p.display());
    }
    eprintln!(
        "12 cases: unsharded {:.2} s, longest of 3 shards {:.2} s",
        unsharded_time.as_secs_f64(),
        longest.as_secs_f64()
    );
    let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    // In any order.
    let o = merge(&[refs[2], refs[0], refs[1]], &[]);
    assert_eq!(code(&o), *want_code, "{}", text(&o.stderr));
    assert_eq!(&text(&o.stdout), want, "merged text = unsharded text");

    // --json: the same objects.
    let o = merge(&refs, &["--json"]);
    let unsharded_json = patchwork(&check_args(&[TEAPOT, SCREW], &["--json"]));
    assert_eq!(code(&o), code(&unsharded_json));
    assert_eq!(text(&o.stdout), text(&unsharded_json.stdout));
}

#[test]
fn a_file_that_fails_fails_the_merge_as_it_fails_the_run() {
    let files = [TEAPOT, bad_model(), SCREW];
    let want = patchwork(&check_args(&files, &[]));
    assert_eq!(code(&want), 2, "{}", text(&want.stderr));
    let dir = fresh("bad");
    let (paths, _) = run_shards(&dir, &files, &[], 3);
    let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let o = merge(&refs, &[]);
    assert_eq!(code(&o), 2);
    assert_eq!(text(&o.stdout), text(&want.stdout));
    let errors = |o: &Output| -> Vec<String> {
        text(&o.stderr)
            .lines()
            .filter(|l| l.starts_with("error: "))
            .map(str::to_owned)
            .collect()
    };
    assert_eq!(errors(&o), errors(&want));
    assert!(errors(&o)[0].contains("bad.bpt:3"), "{:?}", errors(&o));
}

#[test]
fn merge_refuses_missing_duplicated_or_foreign_shards() {
    let dir = fresh("refuse");
    // The teapot's views 0..6 fall in all three shards (2, 1, 1, 1, 1, 3).
    let (paths, _) = run_shards(&dir, &[TEAPOT], &[], 3);
    let [one, two, three] = [&paths[0], &paths[1], &paths[2]].map(PathBuf::as_path);
    let refused = |o: &Output, message: &str| {
        assert_eq!(code(o), 2, "{}", text(&o.stderr));
        assert!(o.stdout.is_empty(), "nothing printed: {}", text(&o.stdout));
        assert!(
            text(&o.stderr).contains(message),
            "expected {message:?} in {}",
            text(&o.stderr)
        );
    };
    assert_eq!(code(&merge(&[one, two, three], &[])), 1, "the three merge");
    refused(&merge(&[one, three], &[]), "missing shard(s) 2 of 3");
    refused(
        &merge(&[one, two, three, two], &[]),
        "shard 2/3 given twice",
    );

    // Another run's shard: another seed, or another number of shards.
    let (seed2, _) = run_shards(&fresh("refuse-seed"), &[TEAPOT], &["--seed", "2"], 3);
    refused(&merge(&[one, &seed2[1], three], &[]), "not of one run");
    let (halves, _) = run_shards(&fresh("refuse-halves"), &[TEAPOT], &[], 2);
    refused(&merge(&[one, two, &halves[1]], &[]), "number of shards");

    // Edited shard files: a case dropped, a case moved to the wrong shard.
    let mut edited = json(three);
    let dropped = edited["cases"]
        .as_array_mut()
        .and_then(Vec::pop)
        .expect("shard 3 has a case");
    let dropped_path = dir.join("shard-3-dropped.json");
    std::fs::write(&dropped_path, edited.to_string()).expect("write");
    refused(
        &merge(&[one, two, &dropped_path], &[]),
        "1 case(s) of the run are in no shard",
    );
    let mut moved = json(one);
    if let Some(cases) = moved["cases"].as_array_mut() {
        cases.push(dropped);
    }
    let moved_path = dir.join("shard-1-moved.json");
    std::fs::write(&moved_path, moved.to_string()).expect("write");
    refused(
        &merge(&[&moved_path, two, &dropped_path], &[]),
        "belongs to another shard",
    );
    let not_json = dir.join("notes.json");
    std::fs::write(&not_json, "shard 2 of 3").expect("write");
    refused(
        &merge(&[one, &not_json, three], &[]),
        "not a patchwork shard file",
    );
}

/// The model and patch columns of a `bench --scale` table, and the line above it.
fn scale_table(stdout: &str) -> (String, Vec<String>) {
    let heading = stdout
        .lines()
        .find(|l| l.starts_with("scale sweep:"))
        .unwrap_or_default()
        .to_owned();
    let rows = stdout
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| model"))
        .map(|l| l.split('|').take(3).collect::<Vec<_>>().join("|"))
        .collect();
    (heading, rows)
}

/// `bench --scale` loops over points (grids and files): sharded over 3 (one empty), its
/// points (one failing: a missing file) merge to the unsharded table, in its order, with its
/// exit code. Timings differ from run to run, so the rows are compared by model and patch count.
#[test]
fn bench_scale_shards_merge_to_the_unsharded_table() {
    let missing = "target/test-output/shard/missing.step";
    let args = [
        "bench", "--scale", "--sizes", "1,2", "--frames", "2", "--size", "64x48", TEAPOT, SCREW,
        missing,
    ];
    let want = patchwork(&args);
    assert_eq!(code(&want), 1, "a point failed: {}", text(&want.stderr));
    let (heading, rows) = scale_table(&text(&want.stdout));
    assert_eq!(rows.len(), 4, "{}", text(&want.stdout));
    let dir = fresh("scale");
    let mut paths = Vec::new();
    for i in 1..=3 {
        let path = dir.join(format!("shard-{i}.json"));
        let shard = format!("{i}/3");
        let mut a = args.to_vec();
        a.extend_from_slice(&["--shard", &shard, "--out", s(&path)]);
        let o = patchwork(&a);
        assert!(path.exists(), "shard {shard}: {}", text(&o.stderr));
        // grid#1, the screw and the missing file; grid#2 and the teapot; nothing: an empty
        // shard still writes its file, and merge still wants it.
        let cases = json(&path)["cases"].as_array().map_or(0, Vec::len);
        assert_eq!(cases, [3, 2, 0][i - 1], "shard {shard}'s points");
        paths.push(path);
    }
    let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let o = merge(&[refs[1], refs[2], refs[0]], &[]);
    assert_eq!(code(&o), 1, "{}", text(&o.stderr));
    assert_eq!(scale_table(&text(&o.stdout)), (heading, rows));
    assert!(
        text(&o.stderr).contains("missing.step"),
        "{}",
        text(&o.stderr)
    );
    let o = merge(&refs[..2], &[]);
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("missing shard(s) 3 of 3"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn shard_auto_reads_the_batch_engines_index() {
    let dir = fresh("auto");
    let out = dir.join("slurm.json");
    let o = command(bin())
        .args(check_args(
            &[TEAPOT],
            &["--shard", "auto", "--out", s(&out)],
        ))
        .env("SLURM_ARRAY_TASK_ID", "7")
        .env("SLURM_ARRAY_TASK_MIN", "5")
        .env("SLURM_ARRAY_TASK_COUNT", "3")
        .output()
        .expect("runs");
    assert!(code(&o) <= 1, "{}", text(&o.stderr));
    let shard = json(&out)["shard"].clone();
    assert_eq!(shard, serde_json::json!({ "index": 3, "total": 3 }));
    assert_eq!(json(&out)["cases"][0]["id"], "models/teapot.bpt#view005");

    let o = command(bin())
        .args(check_args(&[TEAPOT], &["--shard", "auto"]))
        .env("JOB_COMPLETION_INDEX", "1")
        .output()
        .expect("runs");
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("give --shard auto/N"),
        "{}",
        text(&o.stderr)
    );
    let o = patchwork(&check_args(&[TEAPOT], &["--shard", "auto/3"]));
    assert_eq!(code(&o), 2);
    assert!(
        text(&o.stderr).contains("no batch index in the environment"),
        "{}",
        text(&o.stderr)
    );
}

/// `deploy/slurm-array.sh`: every array task with a fake SLURM_ARRAY_TASK_ID, then its merge
/// step; and `submit` with a stand-in `sbatch` that records what it was asked.
#[test]
fn slurm_array_script_shards_and_merges() {
    let (want, want_code, _) = unsharded();
    let dir = fresh("slurm");
    let results = dir.join("results");
    let list = corpus_list();
    let script = common::root().join("deploy/slurm-array.sh");
    let run = |mode: &str, task: Option<usize>| {
        let mut c = command("bash");
        c.arg(&script)
            .arg(mode)
            .env("SHARDS", "3")
            .env("CORPUS_LIST", &list)
            .env("CHECK_ARGS", CHECK_ARGS.join(" "))
            .env("RESULTS", &results)
            .env("PATCHWORK", bin());
        if let Some(id) = task {
            // What Slurm sets for --array=0-2.
            c.env("SLURM_ARRAY_JOB_ID", "4242")
                .env("SLURM_ARRAY_TASK_ID", id.to_string())
                .env("SLURM_ARRAY_TASK_MIN", "0")
                .env("SLURM_ARRAY_TASK_MAX", "2")
                .env("SLURM_ARRAY_TASK_COUNT", "3");
        }
        c.output().expect("bash runs")
    };
    std::fs::create_dir_all(&results).expect("results");
    for id in 0..3 {
        let o = run("shard", Some(id));
        assert_eq!(code(&o), 0, "task {id}: {}", text(&o.stderr));
        let shard = json(&results.join(format!("shard-{id}.json")));
        assert_eq!(shard["shard"]["index"], id + 1);
    }
    let o = run("merge", None);
    assert_eq!(code(&o), *want_code, "{}", text(&o.stderr));
    assert_eq!(&text(&o.stdout), want);

    std::fs::remove_file(results.join("shard-1.json")).expect("remove");
    let o = run("merge", None);
    assert_eq!(code(&o), 2);
    assert!(text(&o.stderr).contains("missing shard(s) 2 of 3"));

    // submit: an array of 3 tasks, and the merge after it (afterany: also when one failed).
    let fake = dir.join("bin");
    std::fs::create_dir_all(&fake).expect("bin");
    let calls = dir.join("sbatch-calls.txt");
    let sbatch = fake.join("sbatch");
    std::fs::write(
        &sbatch,
        format!(
            "#!/bin/sh\necho \"$*\" >> '{}'\necho '4242;cluster'\n",
            calls.display()
        ),
    )
    .expect("fake sbatch");
    make_executable(&sbatch);
    let path = format!(
        "{}:{}",
        fake.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let o = command("bash")
        .arg(&script)
        .arg("submit")
        .env("PATH", path)
        .env("SHARDS", "3")
        .env("RESULTS", &results)
        .output()
        .expect("bash runs");
    assert_eq!(code(&o), 0, "{}", text(&o.stderr));
    let calls = std::fs::read_to_string(&calls).expect("sbatch was called");
    let lines: Vec<&str> = calls.lines().collect();
    assert_eq!(lines.len(), 2, "{calls}");
    assert!(
        lines[0].contains("--array=0-2") && lines[0].ends_with(" shard"),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].contains("--dependency=afterany:4242 ") && lines[1].ends_with(" merge"),
        "{}",
        lines[1]
    );
}

fn make_executable(path: &Path) {
    use std::os::unix::fs::PermissionsExt;
    let mut p = std::fs::metadata(path).expect("exists").permissions();
    p.set_mode(0o755);
    std::fs::set_permissions(path, p).expect("chmod");
}

/// The `- |` block scalars of a YAML file (the containers' shell scripts), dedented.
fn block_scalars(yaml: &str) -> Vec<String> {
    let lines: Vec<&str> = yaml.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut blocks = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.trim() != "- |" {
            continue;
        }
        let body: Vec<&str> = lines[i + 1..]
            .iter()
            .take_while(|l| l.trim().is_empty() || indent(l) > indent(line))
            .copied()
            .collect();
        let cut = body
            .iter()
            .find(|l| !l.trim().is_empty())
            .map_or(0, |l| indent(l));
        let text: Vec<&str> = body.iter().map(|l| l.get(cut..).unwrap_or("")).collect();
        blocks.push(text.join("\n"));
    }
    blocks
}

/// `deploy/k8s-indexed-job.yaml`: the Indexed Job's script with a fake JOB_COMPLETION_INDEX
/// for each pod, then the merge Job's; `kubectl apply --dry-run=client` when kubectl can
/// reach a cluster's API (it needs one to map the kinds).
#[test]
fn k8s_indexed_job_scripts_shard_and_merge() {
    let (want, want_code, _) = unsharded();
    let manifest = common::root().join("deploy/k8s-indexed-job.yaml");
    let yaml = std::fs::read_to_string(&manifest).expect("manifest");
    let scripts = block_scalars(&yaml);
    assert_eq!(scripts.len(), 2, "the check's script and the merge's");
    let dir = fresh("k8s");
    let results = dir.join("results");
    std::fs::create_dir_all(&results).expect("results");
    // `patchwork` on the PATH, as in the image.
    let fake = dir.join("bin");
    std::fs::create_dir_all(&fake).expect("bin");
    std::os::unix::fs::symlink(bin(), fake.join("patchwork")).expect("symlink");
    let path = format!(
        "{}:{}",
        fake.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let list = corpus_list();
    let run = |script: &str, index: Option<usize>| {
        let mut c = command("sh");
        c.args(["-c", script])
            .env("PATH", &path)
            .env("SHARDS", "3")
            .env("CHECK_ARGS", CHECK_ARGS.join(" "))
            .env("CORPUS", common::root())
            .env("CORPUS_LIST", &list)
            .env("RESULTS", &results)
            .env("WAIT_SECONDS", "0");
        if let Some(i) = index {
            c.env("JOB_COMPLETION_INDEX", i.to_string());
        }
        c.output().expect("sh runs")
    };
    for i in 0..3 {
        let o = run(&scripts[0], Some(i));
        assert_eq!(code(&o), 0, "pod {i}: {}", text(&o.stderr));
    }
    let o = run(&scripts[1], None);
    assert_eq!(code(&o), *want_code, "{}", text(&o.stderr));
    assert_eq!(&text(&o.stdout), want);

    match command("kubectl")
        .args(["apply", "--dry-run=client", "-f"])
        .arg(&manifest)
        .output()
    {
        Err(_) => eprintln!("kubectl not installed: manifest not checked by kubectl"),
        Ok(o) if o.status.success() => {
            let out = text(&o.stdout);
            assert!(
                out.contains("job.batch/patchwork-check") && out.contains("patchwork-merge"),
                "{out}"
            );
        }
        Ok(o) => {
            let err = text(&o.stderr);
            let no_cluster = [
                "connection refused",
                "server API group list",
                "openapi",
                "no such host",
            ]
            .iter()
            .any(|m| err.contains(m));
            assert!(no_cluster, "kubectl refuses the manifest: {err}");
            eprintln!(
                "kubectl has no cluster to map the kinds with: manifest not checked by kubectl"
            );
        }
    }
}
