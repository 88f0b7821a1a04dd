//! Whole-model STEP tessellation: patchwork against truck-meshalgo (the Rust baseline) and
//! Open CASCADE `BRepMesh` (what most CAD viewers use), on the same files at the same
//! tolerances, given as fractions of the bounding-box diagonal ([`REL_TOLERANCES`]).
//!
//! `cargo bench --bench step_compare` first prints a Markdown table (also written to
//! `target/step_compare.md`), one row per file × tolerance, with per tool: tessellation time,
//! triangles, faces meshed / faces total, and the *measured* maximum distance to the true surface
//! (absolute and as a multiple of the tolerance); then a criterion group `step/ours` times our
//! tessellation of each file at 1e-3 (criterion's arguments and filters apply to that group).
//!
//! * **ours**: `patchwork::prep::load`, then `tessellate_scene_tolerance`, timed as the median of
//!   [`OUR_RUNS`] runs; the error is the largest `PatchMesh::error` (each patch measures its own).
//! * **truck**: `Table::from_step` → `to_compressed_shell` → `Shell::extract` →
//!   `robust_triangulation(tol)` per shell, run in a child process (this executable with
//!   `PATCHWORK_TRUCK_CHILD=FILE|TOL_ABS`), because truck can abort the whole process (out of
//!   memory in `sub_parameter_division`); the child has a timeout ([`TRUCK_TIMEOUT_ENV`]) and an
//!   address-space limit ([`TRUCK_MEMORY_ENV`]). Its error is measured here: the centroid and
//!   the three edge midpoints of every triangle are projected on the face's surface with
//!   `search_nearest_parameter`; samples that cannot be projected are counted, not ignored.
//!   The non-robust `triangulation(tol)` is run after it (reported in its own table).
//! * **occt**: `python3 benches/occt_mesh.py` (`pip install cadquery-ocp`), which measures the
//!   same samples with `GeomAPI_ProjectPointOnSurf`, and reads the file in its own length unit,
//!   as we do (OCCT's default would be millimetres).
//!
//! Files: every `*.stp` / `*.step` in `models/`, plus the comma-separated list in
//! `PATCHWORK_BENCH_EXTRA`. `PATCHWORK_STEP_TABLE=0` skips the table; it is also skipped by
//! `--list` and outside `cargo bench` (e.g. `cargo test --benches`).
//!
//! What this does not measure: the distance *from the surface to the mesh* (a missing face or a
//! gap between faces is only visible in the faces-meshed count), nor cracks between faces.

use std::fmt::Write as _;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use patchwork::tessellate::tessellate_scene_tolerance;

/// Tolerances, as fractions of the model's bounding-box diagonal.
const REL_TOLERANCES: [f64; 3] = [1e-2, 3e-3, 1e-3];
/// Tolerance of the criterion group, as a fraction of the diagonal.
const CRITERION_REL_TOLERANCE: f64 = 1e-3;
/// Timed runs of our tessellation per table cell (the median is reported).
const OUR_RUNS: usize = 5;
/// Runs of truck's mesher per table cell when one run is quicker than [`REPEAT_BELOW`].
const TRUCK_RUNS: usize = 5;
const REPEAT_BELOW: Duration = Duration::from_millis(500);
/// Samples per model above which triangles are subsampled evenly (4 samples per triangle).
const MAX_SAMPLES: usize = 200_000;
/// Newton iterations of truck's `search_nearest_parameter` (truck's mesher uses 100).
const PROJECTION_TRIALS: usize = 100;

const CHILD_ENV: &str = "PATCHWORK_TRUCK_CHILD";
/// `FILE|REL,REL,...`: run our reader and tessellator in this process and print JSON lines.
const OURS_CHILD_ENV: &str = "PATCHWORK_OURS_CHILD";
const EXTRA_ENV: &str = "PATCHWORK_BENCH_EXTRA";
const TABLE_ENV: &str = "PATCHWORK_STEP_TABLE";
/// Seconds before a truck child is killed (default [`DEFAULT_TRUCK_TIMEOUT`]).
const TRUCK_TIMEOUT_ENV: &str = "PATCHWORK_TRUCK_TIMEOUT_S";
const DEFAULT_TRUCK_TIMEOUT: Duration = Duration::from_secs(120);
/// Address-space limit of a truck child in MiB (default: half the machine's memory, at most
/// 4 GiB; 0 = none), so that its runaway allocations end in an abort and not in the OOM killer.
const TRUCK_MEMORY_ENV: &str = "PATCHWORK_TRUCK_MEM_MB";
/// OCCT's angular deflection, radians (as set in `benches/occt_mesh.py`; for the table's text).
const OCCT_ANGULAR_DEFLECTION: f64 = 0.5;
const OCCT_TIMEOUT: Duration = Duration::from_secs(600);
/// Seconds before our child (reading + every tolerance) is killed (default
/// [`DEFAULT_OURS_TIMEOUT`]).
const OURS_TIMEOUT_ENV: &str = "PATCHWORK_OURS_TIMEOUT_S";
const DEFAULT_OURS_TIMEOUT: Duration = Duration::from_secs(300);
/// Our tessellation is run once only when a run takes longer than this.
const OURS_SLOW_RUN: Duration = Duration::from_secs(10);

fn main() {
    if let Ok(spec) = std::env::var(CHILD_ENV) {
        std::process::exit(truck_child::run(&spec));
    }
    if let Ok(spec) = std::env::var(OURS_CHILD_ENV) {
        std::process::exit(ours_child::run(&spec));
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let in_cargo_bench = args.iter().any(|a| a == "--bench");
    let listing = args.iter().any(|a| a == "--list");
    let table_off = std::env::var(TABLE_ENV).is_ok_and(|v| v == "0");
    let mut files = step_files();
    if in_cargo_bench && !listing && !table_off {
        let ok = table::run(&files);
        // Files our tessellator failed on (crash, hang) would stall criterion: leave them out.
        files.retain(|f| ok.contains(f));
    }
    let mut criterion = Criterion::default().configure_from_args();
    bench_ours(&mut criterion, &files);
    criterion.final_summary();
}

fn manifest_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every `*.stp` / `*.step` in `models/` (sorted), then the files of `PATCHWORK_BENCH_EXTRA`.
fn step_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(manifest_dir().join("models"))
        .map(|dir| {
            dir.filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| {
                    p.extension().is_some_and(|e| {
                        e.eq_ignore_ascii_case("stp") || e.eq_ignore_ascii_case("step")
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    if let Ok(extra) = std::env::var(EXTRA_ENV) {
        files.extend(
            extra
                .split(',')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(PathBuf::from),
        );
    }
    files
}

fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// criterion group `step/ours`: our tessellation of each file at [`CRITERION_REL_TOLERANCE`].
fn bench_ours(c: &mut Criterion, files: &[PathBuf]) {
    let mut group = c.benchmark_group("step/ours");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    for path in files {
        let scene = match patchwork::prep::load(path) {
            Ok(scene) => scene,
            Err(e) => {
                eprintln!("step/ours: skipping {}: {e}", path.display());
                continue;
            }
        };
        let tol = CRITERION_REL_TOLERANCE * scene.bbox_diagonal();
        if !(tol > 0.0 && tol.is_finite()) {
            eprintln!("step/ours: skipping {}: empty bounding box", path.display());
            continue;
        }
        let triangles: usize = tessellate_scene_tolerance(&scene, tol)
            .iter()
            .map(|m| m.triangles.len())
            .sum();
        group.throughput(Throughput::Elements(triangles as u64));
        group.bench_function(BenchmarkId::from_parameter(file_label(path)), |b| {
            b.iter(|| tessellate_scene_tolerance(std::hint::black_box(&scene), tol));
        });
    }
    group.finish();
}

/// Minimal JSON for the flat objects the tools print (one object per line): strings, numbers,
/// booleans and null, no nesting.
mod json {
    use std::collections::BTreeMap;
    use std::fmt::Write as _;

    #[derive(Clone, Debug, PartialEq)]
    pub enum Value {
        Str(String),
        Num(f64),
        Bool(bool),
        Null,
    }

    pub type Object = BTreeMap<String, Value>;

    /// Writes a flat object on one line, keys in the order given.
    pub fn write(fields: &[(&str, Value)]) -> String {
        let mut out = String::from("{");
        for (i, (k, v)) in fields.iter().enumerate() {
            if i > 0 {
                out.push_str(", ");
            }
            quote(&mut out, k);
            out.push_str(": ");
            match v {
                Value::Str(s) => quote(&mut out, s),
                Value::Num(x) if x.is_finite() => {
                    let _ = write!(out, "{x}");
                }
                Value::Num(_) | Value::Null => out.push_str("null"),
                Value::Bool(b) => {
                    let _ = write!(out, "{b}");
                }
            }
        }
        out.push('}');
        out
    }

    fn quote(out: &mut String, s: &str) {
        out.push('"');
        for c in s.chars() {
            match c {
                '"' => out.push_str("\\\""),
                '\\' => out.push_str("\\\\"),
                '\n' => out.push_str("\\n"),
                '\r' => out.push_str("\\r"),
                '\t' => out.push_str("\\t"),
                c if (c as u32) < 0x20 => {
                    let _ = write!(out, "\\u{:04x}", c as u32);
                }
                c => out.push(c),
            }
        }
        out.push('"');
    }

    /// Parses one flat object; `None` if the line is not one.
    pub fn parse(line: &str) -> Option<Object> {
        let mut p = Parser {
            s: line.trim().as_bytes(),
            i: 0,
        };
        let mut out = Object::new();
        p.eat(b'{')?;
        p.ws();
        if p.peek() == Some(b'}') {
            p.i += 1;
            return (p.i == p.s.len()).then_some(out);
        }
        loop {
            p.ws();
            let key = p.string()?;
            p.ws();
            p.eat(b':')?;
            p.ws();
            let value = p.value()?;
            out.insert(key, value);
            p.ws();
            match p.next()? {
                b',' => continue,
                b'}' => break,
                _ => return None,
            }
        }
        p.ws();
        (p.i == p.s.len()).then_some(out)
    }

    struct Parser<'a> {
        s: &'a [u8],
        i: usize,
    }

    impl Parser<'_> {
        fn peek(&self) -> Option<u8> {
            self.s.get(self.i).copied()
        }
        fn next(&mut self) -> Option<u8> {
            let c = self.peek()?;
            self.i += 1;
            Some(c)
        }
        fn eat(&mut self, c: u8) -> Option<()> {
            (self.next()? == c).then_some(())
        }
        fn ws(&mut self) {
            while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
                self.i += 1;
            }
        }
        fn literal(&mut self, word: &str, value: Value) -> Option<Value> {
            let end = self.i + word.len();
            (self.s.get(self.i..end)? == word.as_bytes()).then(|| {
                self.i = end;
                value
            })
        }
        fn value(&mut self) -> Option<Value> {
            match self.peek()? {
                b'"' => self.string().map(Value::Str),
                b't' => self.literal("true", Value::Bool(true)),
                b'f' => self.literal("false", Value::Bool(false)),
                b'n' => self.literal("null", Value::Null),
                _ => {
                    let start = self.i;
                    while self
                        .peek()
                        .is_some_and(|c| c.is_ascii_digit() || b"+-.eE".contains(&c))
                    {
                        self.i += 1;
                    }
                    let text = std::str::from_utf8(&self.s[start..self.i]).ok()?;
                    text.parse().ok().map(Value::Num)
                }
            }
        }
        fn string(&mut self) -> Option<String> {
            self.eat(b'"')?;
            let mut bytes = Vec::new();
            loop {
                match self.next()? {
                    b'"' => break,
                    b'\\' => match self.next()? {
                        b'n' => bytes.push(b'\n'),
                        b't' => bytes.push(b'\t'),
                        b'r' => bytes.push(b'\r'),
                        b'b' => bytes.push(8),
                        b'f' => bytes.push(12),
                        b'u' => {
                            let hex = std::str::from_utf8(self.s.get(self.i..self.i + 4)?).ok()?;
                            self.i += 4;
                            let c = char::from_u32(u32::from_str_radix(hex, 16).ok()?)
                                .unwrap_or(char::REPLACEMENT_CHARACTER);
                            let mut buf = [0; 4];
                            bytes.extend_from_slice(c.encode_utf8(&mut buf).as_bytes());
                        }
                        c => bytes.push(c),
                    },
                    c => bytes.push(c),
                }
            }
            String::from_utf8(bytes).ok()
        }
    }
}

/// Our side, run in a child process like truck's so that a crash or a hang in it is reported
/// in the table instead of ending or stalling the bench. Timing is the same as in-process.
mod ours_child {
    use std::panic::{AssertUnwindSafe, catch_unwind};
    use std::path::Path;
    use std::time::Instant;

    use patchwork::tessellate::{PatchMesh, tessellate_scene_tolerance};

    use super::json::Value;
    use super::{OUR_RUNS, OURS_SLOW_RUN, emit, median_ms};

    /// `spec` is `FILE|REL,REL,...`. Prints an `ours-load` line (read time, diagonal), then one
    /// `ours` line per relative tolerance; returns the exit code.
    pub fn run(spec: &str) -> i32 {
        let Some((file, rels)) = spec.rsplit_once('|') else {
            eprintln!(
                "{}: expected FILE|REL,..., got {spec:?}",
                super::OURS_CHILD_ENV
            );
            return 2;
        };
        let rels: Vec<f64> = rels
            .split(',')
            .filter_map(|r| r.trim().parse().ok())
            .collect();
        let base = |tool: &str| {
            vec![
                ("tool", Value::Str(tool.to_owned())),
                ("file", Value::Str(file.to_owned())),
            ]
        };
        let t = Instant::now();
        let loaded = catch_unwind(|| patchwork::prep::load(Path::new(file)));
        let read_ms = t.elapsed().as_secs_f64() * 1e3;
        let mut row = base("ours-load");
        row.push(("read_ms", Value::Num(read_ms)));
        let scene = match loaded {
            Ok(Ok(scene)) => scene,
            Ok(Err(e)) => {
                row.push(("error", Value::Str(format!("load failed: {e}"))));
                emit(&row);
                return 1;
            }
            Err(payload) => {
                row.push((
                    "error",
                    Value::Str(format!("load panicked: {}", message(&*payload))),
                ));
                emit(&row);
                return 1;
            }
        };
        let diag = scene.bbox_diagonal();
        row.extend([
            ("bbox_diag", Value::Num(diag)),
            ("patches", Value::Num(scene.patches.len() as f64)),
            ("skipped", Value::Num(scene.skipped.len() as f64)),
        ]);
        emit(&row);
        for rel in rels {
            let tol = rel * diag;
            let mut row = base("ours");
            row.extend([("rel", Value::Num(rel)), ("tol", Value::Num(tol))]);
            let mut times = Vec::with_capacity(OUR_RUNS);
            let mut meshes: Vec<PatchMesh> = Vec::new();
            let mut panicked = None;
            while times.len() < OUR_RUNS {
                let t = Instant::now();
                match catch_unwind(AssertUnwindSafe(|| tessellate_scene_tolerance(&scene, tol))) {
                    Ok(m) => meshes = m,
                    Err(payload) => {
                        panicked = Some(message(&*payload));
                        break;
                    }
                }
                let elapsed = t.elapsed();
                times.push(elapsed.as_secs_f64() * 1e3);
                if elapsed > OURS_SLOW_RUN {
                    break;
                }
            }
            if let Some(why) = panicked {
                row.push(("error", Value::Str(format!("panicked: {why}"))));
                emit(&row);
                continue;
            }
            let failures: Vec<&String> = meshes.iter().filter_map(|m| m.failure.as_ref()).collect();
            let first_failure = scene
                .skipped
                .first()
                .map(|s| format!("skipped by the reader: #{}: {}", s.face, s.reason))
                .or_else(|| failures.first().map(|s| (*s).clone()));
            let max_error = meshes.iter().map(|m| m.error).fold(0.0, f64::max);
            // A patch whose own target is not `tol` would make the ratio misleading.
            let off_target = meshes
                .iter()
                .filter(|m| (m.eps_target - tol).abs() > 1e-9 * tol.max(1.0))
                .count();
            row.extend([
                ("read_ms", Value::Num(read_ms)),
                ("runs", Value::Num(times.len() as f64)),
                ("mesh_ms", Value::Num(median_ms(&mut times))),
                (
                    "triangles",
                    Value::Num(meshes.iter().map(|m| m.triangles.len()).sum::<usize>() as f64),
                ),
                (
                    "faces",
                    Value::Num((scene.patches.len() + scene.skipped.len()) as f64),
                ),
                (
                    "faces_meshed",
                    Value::Num(meshes.iter().filter(|m| !m.triangles.is_empty()).count() as f64),
                ),
                ("max_error", Value::Num(max_error)),
                ("error_ratio", Value::Num(max_error / tol)),
                (
                    "trim_error",
                    Value::Num(meshes.iter().map(|m| m.trim_error).fold(0.0, f64::max)),
                ),
                (
                    "face_failures",
                    Value::Num((failures.len() + scene.skipped.len()) as f64),
                ),
                ("off_target", Value::Num(off_target as f64)),
                ("bbox_diag", Value::Num(diag)),
            ]);
            if let Some(f) = first_failure {
                row.push(("first_face_failure", Value::Str(f)));
            }
            emit(&row);
        }
        0
    }

    fn message(payload: &(dyn std::any::Any + Send)) -> String {
        payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default()
    }
}

/// Prints one JSON line on stdout and flushes it (a child may die right after).
fn emit(fields: &[(&str, json::Value)]) {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    // Nothing useful can be done if the parent closed the pipe.
    let _ = writeln!(out, "{}", json::write(fields));
    let _ = out.flush();
}

/// The truck-meshalgo side, run in a child process.
mod truck_child {
    use std::time::Instant;

    use truck_meshalgo::prelude::*;
    use truck_stepio::r#in::Table;
    use truck_stepio::r#in::alias::{Curve3D, Surface};
    use truck_topology::Shell;
    use truck_topology::compress::CompressedShell;

    use super::json::Value;
    use super::{MAX_SAMPLES, PROJECTION_TRIALS, REPEAT_BELOW, TRUCK_RUNS, emit, median_ms};

    type StepShell = Shell<Point3, Curve3D, Surface>;
    type StepCShell = CompressedShell<Point3, Curve3D, Surface>;
    type MeshedShell = Shell<Point3, PolylineCurve<Point3>, Option<PolygonMesh>>;
    type MeshedCShell = CompressedShell<Point3, PolylineCurve<Point3>, Option<PolygonMesh>>;

    /// A shell ready for truck's mesher: extracted into topology (`Shell::extract`), or, where
    /// that fails, still compressed — truck meshes both (its own `step-to-mesh` example meshes
    /// the compressed one).
    enum Prepared {
        Topology(StepShell),
        Compressed(StepCShell),
    }

    enum Meshed {
        Topology(MeshedShell),
        Compressed(MeshedCShell),
    }

    impl Prepared {
        fn robust(&self, tol: f64) -> Meshed {
            match self {
                Prepared::Topology(s) => Meshed::Topology(s.robust_triangulation(tol)),
                Prepared::Compressed(s) => Meshed::Compressed(s.robust_triangulation(tol)),
            }
        }

        fn plain(&self, tol: f64) -> Meshed {
            match self {
                Prepared::Topology(s) => Meshed::Topology(s.triangulation(tol)),
                Prepared::Compressed(s) => Meshed::Compressed(s.triangulation(tol)),
            }
        }

        fn face_count(&self) -> usize {
            match self {
                Prepared::Topology(s) => s.face_iter().count(),
                Prepared::Compressed(s) => s.faces.len(),
            }
        }

        /// Each face's surface (the one the mesher evaluated: the mesh's UVs are its
        /// parameters) with its mesh, in face order.
        fn pair(&self, meshed: &Meshed) -> Vec<(Surface, Option<PolygonMesh>)> {
            match (self, meshed) {
                (Prepared::Topology(s), Meshed::Topology(m)) => s
                    .face_iter()
                    .zip(m.face_iter())
                    .map(|(f, mf)| (f.surface(), mf.surface()))
                    .collect(),
                (Prepared::Compressed(s), Meshed::Compressed(m)) => s
                    .faces
                    .iter()
                    .zip(&m.faces)
                    .map(|(f, mf)| (f.surface.clone(), mf.surface.clone()))
                    .collect(),
                _ => Vec::new(),
            }
        }
    }

    /// `spec` is `FILE|TOL_ABS`. Prints one JSON line for `robust_triangulation`, then one for
    /// `triangulation`; returns the exit code.
    pub fn run(spec: &str) -> i32 {
        let Some((file, tol)) = spec.rsplit_once('|') else {
            eprintln!("{}: expected FILE|TOL_ABS, got {spec:?}", super::CHILD_ENV);
            return 2;
        };
        let tol = match tol.trim().parse::<f64>() {
            Ok(t) if t > 0.0 && t.is_finite() => t,
            _ => {
                eprintln!("bad tolerance {tol:?} in {spec:?}");
                return 2;
            }
        };
        let base = |tool: &str| {
            vec![
                ("tool", Value::Str(tool.to_owned())),
                ("file", Value::Str(file.to_owned())),
                ("tol", Value::Num(tol)),
            ]
        };
        let t0 = Instant::now();
        let (shells, shell_errors) = match read(file) {
            Ok(r) => r,
            Err(e) => {
                let mut row = base("truck");
                row.push(("error", Value::Str(e)));
                emit(&row);
                return 1;
            }
        };
        let read_ms = t0.elapsed().as_secs_f64() * 1e3;
        let compressed = shells
            .iter()
            .filter(|s| matches!(s, Prepared::Compressed(_)))
            .count();
        let mut common = vec![
            ("read_ms", Value::Num(read_ms)),
            ("shells", Value::Num(shells.len() as f64)),
            ("shells_compressed", Value::Num(compressed as f64)),
            ("shell_errors", Value::Num(shell_errors.len() as f64)),
        ];
        if let Some(first) = shell_errors.first() {
            common.push(("shell_error", Value::Str(first.clone())));
        }

        let (ms, runs, meshed) = timed(|| shells.iter().map(|s| s.robust(tol)).collect::<Vec<_>>());
        let mut row = base("truck");
        row.extend(common.iter().cloned());
        row.extend(report(&shells, &meshed, tol, ms, runs));
        emit(&row);

        let (ms, runs, meshed) = timed(|| shells.iter().map(|s| s.plain(tol)).collect::<Vec<_>>());
        let mut row = base("truck-plain");
        row.extend(common);
        row.extend(report(&shells, &meshed, tol, ms, runs));
        emit(&row);
        0
    }

    /// Every shell of the file (sorted by entity id), and why some were meshed compressed or
    /// could not be converted at all.
    fn read(file: &str) -> Result<(Vec<Prepared>, Vec<String>), String> {
        let text = std::fs::read_to_string(file).map_err(|e| format!("cannot read: {e}"))?;
        let table = Table::from_step(&text).ok_or("Table::from_step failed to parse the file")?;
        let mut ids: Vec<u64> = table.shell.keys().copied().collect();
        ids.sort_unstable();
        let mut shells = Vec::new();
        let mut errors = Vec::new();
        for id in ids {
            let step_shell = &table.shell[&id];
            match table.to_compressed_shell(step_shell) {
                Ok(c) => match Shell::extract(c.clone()) {
                    Ok(shell) => shells.push(Prepared::Topology(shell)),
                    Err(e) => {
                        errors.push(format!(
                            "shell #{id}: Shell::extract: {e} (meshed compressed)"
                        ));
                        shells.push(Prepared::Compressed(c));
                    }
                },
                Err(e) => errors.push(format!("shell #{id}: to_compressed_shell: {e}")),
            }
        }
        Ok((shells, errors))
    }

    /// Runs `f` once, and up to `TRUCK_RUNS` times if it is quick; (median ms, runs, result).
    fn timed<T>(mut f: impl FnMut() -> T) -> (f64, usize, T) {
        let t = Instant::now();
        let mut result = f();
        let first = t.elapsed();
        let mut times = vec![first.as_secs_f64() * 1e3];
        if first < REPEAT_BELOW {
            for _ in 1..TRUCK_RUNS {
                let t = Instant::now();
                result = f();
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        let runs = times.len();
        (median_ms(&mut times), runs, result)
    }

    /// Sizes of the parameter grids that seed projections (per face, built when first needed)
    /// and that check the worst sample by brute force.
    const SEED_GRID: usize = 48;
    const CHECK_GRID: usize = 256;

    /// Points of one face's surface on an `(n + 1)²` grid. Per direction the grid spans one
    /// period of a periodic surface, else the surface's range if it is bounded, else the face's
    /// UV box (the mesh's UVs) widened by half its size each side. Empty if the mesh has no UVs.
    fn uv_grid(surface: &Surface, uvs: &[Vector2], n: usize) -> Vec<((f64, f64), Point3)> {
        let (mut lo, mut hi) = (
            Vector2::new(f64::INFINITY, f64::INFINITY),
            Vector2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for uv in uvs {
            lo = Vector2::new(lo.x.min(uv.x), lo.y.min(uv.y));
            hi = Vector2::new(hi.x.max(uv.x), hi.y.max(uv.y));
        }
        if !(lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite()) {
            return Vec::new();
        }
        let pad = (hi - lo) / 2.0;
        let (u_range, v_range) = surface.try_range_tuple();
        let span =
            |lo: f64, hi: f64, pad: f64, period: Option<f64>, range: Option<(f64, f64)>| match (
                period, range,
            ) {
                (Some(p), _) => (lo, lo + p),
                (None, Some(r)) => r,
                (None, None) => (lo - pad, hi + pad),
            };
        let (u0, u1) = span(lo.x, hi.x, pad.x, surface.u_period(), u_range);
        let (v0, v1) = span(lo.y, hi.y, pad.y, surface.v_period(), v_range);
        let mut out = Vec::with_capacity((n + 1) * (n + 1));
        for i in 0..=n {
            for j in 0..=n {
                let u = u0 + (u1 - u0) * i as f64 / n as f64;
                let v = v0 + (v1 - v0) * j as f64 / n as f64;
                out.push(((u, v), surface.subs(u, v)));
            }
        }
        out
    }

    /// Damped Gauss–Newton descent of |S(u, v) − p|² from `(u, v)`; the distance reached.
    fn descend(surface: &Surface, p: Point3, (mut u, mut v): (f64, f64)) -> Option<f64> {
        let mut r = surface.subs(u, v) - p;
        let mut f = r.magnitude2();
        for _ in 0..PROJECTION_TRIALS {
            let (su, sv) = (surface.uder(u, v), surface.vder(u, v));
            let (a, b, c) = (su.dot(su), su.dot(sv), sv.dot(sv));
            let (gu, gv) = (su.dot(r), sv.dot(r));
            let det = a * c - b * b;
            if det.is_nan() || det.abs() <= 1e-300 {
                break;
            }
            let (du, dv) = (-(c * gu - b * gv) / det, -(a * gv - b * gu) / det);
            let mut step = 1.0;
            let mut improved = false;
            while step > 1e-6 {
                let (nu, nv) = (u + step * du, v + step * dv);
                let nr = surface.subs(nu, nv) - p;
                let nf = nr.magnitude2();
                if nf < f {
                    (u, v, r) = (nu, nv, nr);
                    improved = f - nf > 1e-14 * f.max(1e-300);
                    f = nf;
                    break;
                }
                step *= 0.5;
            }
            if !improved {
                break;
            }
        }
        let d = f.sqrt();
        d.is_finite().then_some(d)
    }

    /// Brute-force checks of the largest distance estimates, at most, per report.
    const MAX_RECHECKS: usize = 400;

    /// A sample's distance estimate, ordered by distance.
    struct Estimate {
        d: f64,
        face: usize,
        point: Point3,
        /// Already checked by brute force.
        checked: bool,
    }

    impl PartialEq for Estimate {
        fn eq(&self, other: &Self) -> bool {
            self.d.total_cmp(&other.d).is_eq()
        }
    }
    impl Eq for Estimate {}
    impl PartialOrd for Estimate {
        fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Estimate {
        fn cmp(&self, other: &Self) -> std::cmp::Ordering {
            self.d.total_cmp(&other.d)
        }
    }

    /// Distance from points to one face's surface with truck's `search_nearest_parameter`.
    struct Projector<'a> {
        surface: &'a Surface,
        uvs: &'a [Vector2],
        seeds: Option<Vec<((f64, f64), Point3)>>,
    }

    impl<'a> Projector<'a> {
        fn new(surface: &'a Surface, uvs: &'a [Vector2]) -> Self {
            Projector {
                surface,
                uvs,
                seeds: None,
            }
        }

        fn search(&self, p: Point3, hint: impl Into<SPHint2D>) -> Option<f64> {
            self.surface
                .search_nearest_parameter(p, hint, PROJECTION_TRIALS)
                .map(|(u, v)| self.surface.subs(u, v).distance(p))
                .filter(|d| d.is_finite())
        }

        /// Local search from `(u, v)`: truck's `search_nearest_parameter`, and a damped
        /// Gauss–Newton descent of |S(u, v) − p|² (truck's Newton iteration can stop far from
        /// the minimum, e.g. on spindle tori); the smaller distance.
        fn local(&self, p: Point3, (u, v): (f64, f64)) -> Option<f64> {
            let descent = descend(self.surface, p, (u, v));
            match (self.search(p, (u, v)), descent) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            }
        }

        /// Distance from `p`, `None` if no search finds a parameter. A search from `hint`
        /// first: it finds a local minimum, never below the true distance. When that could
        /// raise the running maximum `floor` (or fails), searches without hint and from the
        /// nearest point of a parameter grid follow, and the smallest distance is kept.
        fn distance(&mut self, p: Point3, hint: Option<(f64, f64)>, floor: f64) -> Option<f64> {
            let local = hint.and_then(|h| self.local(p, h));
            if local.is_some_and(|d| d <= floor) {
                return local;
            }
            let unhinted = self.search(p, SPHint2D::None);
            let (surface, uvs) = (self.surface, self.uvs);
            let seeds = self
                .seeds
                .get_or_insert_with(|| uv_grid(surface, uvs, SEED_GRID));
            let seeded = seeds
                .iter()
                .map(|(uv, q)| (q.distance(p), *uv))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(d, uv)| self.local(p, uv).map_or(d, |r| r.min(d)));
            [local, unhinted, seeded]
                .into_iter()
                .flatten()
                .min_by(f64::total_cmp)
        }

        /// Brute force, to check the worst sample: the nearest point of a fine grid, refined.
        fn brute_force(&self, p: Point3) -> Option<f64> {
            let best = uv_grid(self.surface, self.uvs, CHECK_GRID)
                .into_iter()
                .map(|(uv, q)| (q.distance(p), uv))
                .min_by(|a, b| a.0.total_cmp(&b.0))?;
            Some(self.local(p, best.1).map_or(best.0, |r| r.min(best.0)))
        }
    }

    /// Counts and the measured error of `meshed` (zipped face by face with `shells`).
    fn report(
        shells: &[Prepared],
        meshed: &[Meshed],
        tol: f64,
        ms: f64,
        runs: usize,
    ) -> Vec<(&'static str, Value)> {
        let nonempty: Vec<(Surface, PolygonMesh)> = shells
            .iter()
            .zip(meshed)
            .flat_map(|(s, m)| s.pair(m))
            .filter_map(|(s, m)| Some((s, m?)))
            .filter(|(_, m)| m.faces().triangle_iter().len() > 0)
            .collect();
        let faces: usize = shells.iter().map(Prepared::face_count).sum();
        let triangles: usize = nonempty
            .iter()
            .map(|(_, m)| m.faces().triangle_iter().len())
            .sum();
        let stride = (triangles * 4).div_ceil(MAX_SAMPLES).max(1);

        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        let (mut max_error, mut samples, mut unprojected, mut used, mut counter) =
            (0.0_f64, 0_usize, 0_usize, 0_usize, 0_usize);
        let t = Instant::now();
        // Every sample's distance estimate (an upper bound: a found surface point), its face.
        let mut estimates: Vec<Estimate> = Vec::new();
        for (face, (surface, mesh)) in nonempty.iter().enumerate() {
            let positions = mesh.positions();
            let uvs = mesh.uv_coords();
            for p in positions {
                lo = Point3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
                hi = Point3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
            }
            let mut projector = Projector::new(surface, uvs);
            for tri in mesh.faces().triangle_iter() {
                counter += 1;
                if (counter - 1) % stride != 0 {
                    continue;
                }
                used += 1;
                let [a, b, c] = tri.map(|v| positions[v.pos]);
                let uv = tri.map(|v| v.uv.filter(|&i| i < uvs.len()).map(|i| uvs[i]));
                let points = [
                    Point3::from_vec((a.to_vec() + b.to_vec() + c.to_vec()) / 3.0),
                    a.midpoint(b),
                    b.midpoint(c),
                    c.midpoint(a),
                ];
                let hints: [Option<(f64, f64)>; 4] = match uv {
                    [Some(p), Some(q), Some(r)] => {
                        let mid = |x: Vector2| (x.x, x.y);
                        [
                            mid((p + q + r) / 3.0),
                            mid((p + q) / 2.0),
                            mid((q + r) / 2.0),
                            mid((r + p) / 2.0),
                        ]
                        .map(Some)
                    }
                    _ => [None; 4],
                };
                for (point, hint) in points.into_iter().zip(hints) {
                    samples += 1;
                    match projector.distance(point, hint, max_error) {
                        Some(d) => {
                            max_error = max_error.max(d);
                            estimates.push(Estimate {
                                d,
                                face,
                                point,
                                checked: false,
                            });
                        }
                        None => unprojected += 1,
                    }
                }
            }
        }
        // Projections can stop at a local minimum (folded surfaces such as spindle tori): check
        // the largest estimates by brute force until the largest one has been checked.
        let mut heap = std::collections::BinaryHeap::from(estimates);
        let mut rechecked = 0;
        let mut capped = false;
        while let Some(top) = heap.peek() {
            if top.checked {
                break;
            }
            if rechecked == MAX_RECHECKS {
                capped = true;
                break;
            }
            let Some(mut e) = heap.pop() else { break };
            let (surface, mesh) = &nonempty[e.face];
            if let Some(d) = Projector::new(surface, mesh.uv_coords()).brute_force(e.point) {
                e.d = e.d.min(d);
            }
            e.checked = true;
            rechecked += 1;
            heap.push(e);
        }
        let max_error = heap.peek().map_or(0.0, |e| e.d);
        let sample_ms = t.elapsed().as_secs_f64() * 1e3;
        let bbox_diag = if lo.x.is_finite() {
            lo.distance(hi)
        } else {
            0.0
        };
        vec![
            ("mesh_ms", Value::Num(ms)),
            ("runs", Value::Num(runs as f64)),
            ("triangles", Value::Num(triangles as f64)),
            ("faces", Value::Num(faces as f64)),
            ("faces_meshed", Value::Num(nonempty.len() as f64)),
            ("max_error", Value::Num(max_error)),
            ("error_ratio", Value::Num(max_error / tol)),
            ("rechecked", Value::Num(rechecked as f64)),
            ("recheck_capped", Value::Bool(capped)),
            ("samples", Value::Num(samples as f64)),
            ("unprojected", Value::Num(unprojected as f64)),
            (
                "sampled",
                Value::Num(if triangles > 0 {
                    used as f64 / triangles as f64
                } else {
                    1.0
                }),
            ),
            ("sample_ms", Value::Num(sample_ms)),
            ("bbox_diag", Value::Num(bbox_diag)),
        ]
    }
}

/// Median of `times` (sorted in place); 0 for none.
fn median_ms(times: &mut [f64]) -> f64 {
    times.sort_by(f64::total_cmp);
    match times.len() {
        0 => 0.0,
        n if n % 2 == 1 => times[n / 2],
        n => 0.5 * (times[n / 2 - 1] + times[n / 2]),
    }
}

/// A child process's output, or why it did not finish.
#[derive(Debug)]
struct ChildOutput {
    stdout: String,
    stderr: String,
    status: Option<ExitStatus>,
    timed_out: bool,
    elapsed: Duration,
}

/// Runs this executable in child mode (`env_key=spec`) under an address-space limit of
/// `memory_mb` MiB (`ulimit -v`: a runaway allocation then aborts the child before the OOM
/// killer acts on anything else).
fn run_self(
    exe: &Path,
    env_key: &str,
    spec: &str,
    timeout: Duration,
    memory_mb: Option<u64>,
) -> std::io::Result<ChildOutput> {
    let mut cmd = match memory_mb {
        Some(mb) if cfg!(unix) => {
            let mut c = Command::new("sh");
            c.arg("-c")
                .arg(format!("ulimit -v {} && exec \"$0\"", mb * 1024))
                .arg(exe);
            c
        }
        _ => Command::new(exe),
    };
    cmd.env(env_key, spec);
    run_with_timeout(cmd, timeout)
}

/// Runs `cmd` to completion or until `timeout` (then kills it), collecting its output.
fn run_with_timeout(mut cmd: Command, timeout: Duration) -> std::io::Result<ChildOutput> {
    let start = Instant::now();
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    // Drain both pipes on threads so that a chatty child cannot block on a full pipe.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_end(&mut bytes);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break Some(status);
        }
        if start.elapsed() > timeout {
            timed_out = true;
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let elapsed = start.elapsed();
    Ok(ChildOutput {
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
        status,
        timed_out,
        elapsed,
    })
}

impl ChildOutput {
    /// Why the child failed, in a few words; `None` if it exited with 0.
    fn failure(&self) -> Option<String> {
        if self.timed_out {
            return Some(format!("timeout ({:.0} s)", self.elapsed.as_secs_f64()));
        }
        let status = self.status?;
        if status.success() {
            return None;
        }
        let detail = self.stderr_reason();
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt as _;
            if let Some(sig) = status.signal() {
                let what = match sig {
                    6 => "aborted",
                    9 => "killed",
                    11 => "crashed",
                    _ => "terminated",
                };
                return Some(match detail {
                    Some(d) => format!("{what} (signal {sig}): {d}"),
                    None => format!("{what} (signal {sig})"),
                });
            }
        }
        Some(match (status.code(), detail) {
            (Some(101), Some(d)) => format!("panicked: {d}"),
            (Some(101), None) => "panicked".to_owned(),
            (code, Some(d)) => format!("exit {}: {d}", code.unwrap_or(-1)),
            (code, None) => format!("exit {}", code.unwrap_or(-1)),
        })
    }

    /// The telling line of stderr: a panic message, an allocation failure, else the last line.
    fn stderr_reason(&self) -> Option<String> {
        let lines: Vec<&str> = self.stderr.lines().map(str::trim).collect();
        if let Some(i) = lines.iter().position(|l| l.contains("panicked at")) {
            let place = lines[i]
                .split_once("panicked at ")
                .map_or("", |(_, at)| at.trim_end_matches(':'));
            let message = lines.get(i + 1).copied().unwrap_or("");
            return Some(format!("{message} (at {place})"));
        }
        if let Some(l) = lines.iter().find(|l| l.starts_with("memory allocation of")) {
            return Some((*l).to_owned());
        }
        lines
            .iter()
            .rev()
            .find(|l| !l.is_empty())
            .map(|l| (*l).to_owned())
    }
}

/// The comparison table.
mod table {
    use super::*;
    use json::{Object, Value};

    /// What one tool achieved on one file at one tolerance.
    #[derive(Clone, Debug, Default)]
    struct Cell {
        mesh_ms: Option<f64>,
        read_ms: Option<f64>,
        triangles: Option<usize>,
        faces: Option<usize>,
        faces_meshed: Option<usize>,
        max_error: Option<f64>,
        tol: f64,
        /// Samples whose projection failed (truck, occt).
        unprojected: usize,
        /// Fraction of triangles sampled, below 1 when subsampled.
        sampled: Option<f64>,
        bbox_diag: Option<f64>,
        /// OCCT: its diagonal in millimetres, the file's length unit, the output unit.
        bbox_diag_mm: Option<f64>,
        file_unit: Option<String>,
        units: Option<String>,
        /// Largest trim-curve error (ours).
        trim_error: Option<f64>,
        /// Faces that were tried but failed (ours: `PatchMesh::failure`), with a first reason.
        face_failures: usize,
        first_face_failure: Option<String>,
        /// Timed runs (the median is shown); shown when fewer than planned.
        runs: Option<usize>,
        /// The whole run failed (abort, panic, timeout, error).
        failure: Option<String>,
        note: Option<String>,
    }

    impl Cell {
        fn failed(why: impl Into<String>) -> Cell {
            Cell {
                failure: Some(why.into()),
                ..Cell::default()
            }
        }

        fn from_json(o: &Object) -> Cell {
            let num = |k: &str| match o.get(k) {
                Some(Value::Num(x)) => Some(*x),
                _ => None,
            };
            let text = |k: &str| match o.get(k) {
                Some(Value::Str(s)) => Some(s.clone()),
                _ => None,
            };
            let count = |k: &str| num(k).map(|x| x as usize);
            let mut note = None;
            if let (Some(n), Some(e)) = (num("shell_errors"), text("shell_error"))
                && n > 0.0
            {
                note = Some(format!("{n} shell(s) with conversion errors, first: {e}"));
            }
            if let Some(n) = num("off_target").filter(|n| *n > 0.0) {
                note = Some(format!("{n} patch(es) with eps_target ≠ tol"));
            }
            if o.get("recheck_capped") == Some(&Value::Bool(true)) {
                note =
                    Some("brute-force recheck capped: the max error is an upper bound".to_owned());
            }
            Cell {
                mesh_ms: num("mesh_ms"),
                read_ms: num("read_ms"),
                triangles: count("triangles"),
                faces: count("faces"),
                faces_meshed: count("faces_meshed"),
                max_error: num("max_error"),
                tol: num("tol").unwrap_or(0.0),
                unprojected: count("unprojected").unwrap_or(0),
                sampled: num("sampled"),
                bbox_diag: num("bbox_diag"),
                bbox_diag_mm: num("bbox_diag_mm"),
                file_unit: text("file_unit"),
                units: text("units"),
                trim_error: num("trim_error"),
                face_failures: count("face_failures").unwrap_or(0),
                first_face_failure: text("first_face_failure"),
                runs: count("runs"),
                failure: text("error"),
                note,
            }
        }

        /// The four table columns: ms, triangles, faces meshed/total, error (×tol).
        fn columns(&self, footnotes: &mut Vec<String>) -> [String; 4] {
            if let Some(why) = &self.failure {
                let k = footnote(footnotes, why.clone());
                let short: String = why
                    .split([':', '('])
                    .next()
                    .unwrap_or(why)
                    .trim()
                    .to_owned();
                return [
                    format!("**{short}** [{k}]"),
                    "—".into(),
                    "—".into(),
                    "—".into(),
                ];
            }
            let mut ms = self.mesh_ms.map_or("?".into(), |t| format!("{t:.1}"));
            if let Some(n) = self.runs.filter(|n| *n < OUR_RUNS) {
                let _ = write!(ms, " ({n} run{})", if n == 1 { "" } else { "s" });
            }
            let tris = self.triangles.map_or("?".into(), |t| t.to_string());
            let mut faces = match (self.faces_meshed, self.faces) {
                (Some(m), Some(t)) => format!("{m}/{t}"),
                _ => "?".into(),
            };
            if self.face_failures > 0 {
                let why = self.first_face_failure.clone().unwrap_or_default();
                let k = footnote(
                    footnotes,
                    format!("{} face(s) failed, first: {why}", self.face_failures),
                );
                let _ = write!(faces, " [{k}]");
            }
            let mut err = match self.max_error {
                Some(e) if self.tol > 0.0 => format!("{e:.3e} ({:.2}×)", e / self.tol),
                Some(e) => format!("{e:.3e}"),
                None => "?".into(),
            };
            if let Some(t) = self.trim_error.filter(|t| *t > 0.0) {
                let _ = write!(err, ", trim {:.2}×", t / self.tol);
            }
            if self.unprojected > 0 {
                let _ = write!(err, ", {} unprojected", self.unprojected);
            }
            if let Some(s) = self.sampled.filter(|s| *s < 1.0) {
                let _ = write!(err, ", sampled {:.0} %", s * 100.0);
            }
            if let Some(n) = &self.note {
                let k = footnote(footnotes, n.clone());
                let _ = write!(err, " [{k}]");
            }
            [ms, tris, faces, err]
        }
    }

    /// The 1-based number of footnote `text`, added if it is new.
    fn footnote(footnotes: &mut Vec<String>, text: String) -> usize {
        match footnotes.iter().position(|f| *f == text) {
            Some(i) => i + 1,
            None => {
                footnotes.push(text);
                footnotes.len()
            }
        }
    }

    /// One row: a file at one tolerance.
    struct Row {
        file: String,
        rel: f64,
        tol: Option<f64>,
        ours: Cell,
        truck: Cell,
        truck_plain: Option<Cell>,
        occt: Cell,
    }

    /// Per file: read times and diagonals, to check units.
    #[derive(Default)]
    struct FileInfo {
        file: String,
        ours_read_ms: Option<f64>,
        ours_diag: Option<f64>,
        ours_error: Option<String>,
        truck_read_ms: Option<f64>,
        truck_diag: Option<f64>,
        occt_read_ms: Option<f64>,
        occt_diag: Option<f64>,
        occt_diag_mm: Option<f64>,
        occt_unit: Option<String>,
        occt_units: Option<String>,
        diag_source: &'static str,
    }

    /// Builds, prints and writes the table; returns the files our tessellator handled (no
    /// crash, no timeout) at every tolerance.
    pub fn run(files: &[PathBuf]) -> Vec<PathBuf> {
        let start = Instant::now();
        let mut ok_files = Vec::new();
        let ours_timeout = std::env::var(OURS_TIMEOUT_ENV)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|s| *s > 0.0)
            .map_or(DEFAULT_OURS_TIMEOUT, Duration::from_secs_f64);
        let occt = occt_available();
        let timeout = std::env::var(TRUCK_TIMEOUT_ENV)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|s| *s > 0.0)
            .map_or(DEFAULT_TRUCK_TIMEOUT, Duration::from_secs_f64);
        let memory_mb = truck_memory_limit_mb();
        let exe = std::env::current_exe();
        println!(
            "\nstep_compare: {} file(s), tolerances {REL_TOLERANCES:?} × bbox diagonal; child \
             timeouts: ours {:.0} s per file, truck {:.0} s per tolerance; memory limit {}",
            files.len(),
            ours_timeout.as_secs_f64(),
            timeout.as_secs_f64(),
            memory_mb.map_or("none".into(), |m| format!("{m} MiB"))
        );
        if let Err(why) = &occt {
            println!(
                "step_compare: OCCT not available ({why}); install it with \
                 `pip install cadquery-ocp` to compare with Open CASCADE"
            );
        }
        let mut rows = Vec::new();
        let mut infos = Vec::new();
        for path in files {
            let label = file_label(path);
            println!("step_compare: {label}");
            let mut info = FileInfo {
                file: label.clone(),
                ..FileInfo::default()
            };
            let ours_cells = match &exe {
                Ok(exe) => run_ours(exe, path, ours_timeout, memory_mb, &mut info),
                Err(e) => {
                    info.ours_error = Some(format!("current_exe: {e}"));
                    Vec::new()
                }
            };
            if ours_cells.len() == REL_TOLERANCES.len()
                && ours_cells.iter().all(|c| c.failure.is_none())
            {
                ok_files.push(path.clone());
            }
            // Absolute tolerances from our diagonal, or OCCT's if we cannot read the file.
            let mut occt_rows: Vec<Cell> = Vec::new();
            let mut diag = info.ours_diag.filter(|d| *d > 0.0 && d.is_finite());
            info.diag_source = "ours";
            if occt.is_ok() {
                let tols: Option<Vec<f64>> = diag.map(|d| REL_TOLERANCES.map(|r| r * d).to_vec());
                let (cells, occt_diag) = run_occt(path, tols.as_deref(), diag);
                occt_rows = cells;
                if diag.is_none() {
                    diag = occt_diag;
                    info.diag_source = "occt";
                }
            }
            if let Some(first) = occt_rows.first() {
                info.occt_read_ms = first.read_ms;
                info.occt_diag = first.bbox_diag;
                info.occt_diag_mm = first.bbox_diag_mm;
                info.occt_unit = first.file_unit.clone();
                info.occt_units = first.units.clone();
            }
            for (k, rel) in REL_TOLERANCES.iter().copied().enumerate() {
                let tol = diag.map(|d| rel * d);
                let ours = ours_cells.get(k).cloned().unwrap_or_else(|| {
                    Cell::failed(
                        info.ours_error
                            .clone()
                            .unwrap_or_else(|| "empty bounding box".into()),
                    )
                });
                let (truck, truck_plain) = match (tol, &exe) {
                    (Some(tol), Ok(exe)) => run_truck(exe, path, tol, timeout, memory_mb),
                    (None, _) => (Cell::failed("no bounding box to scale the tolerance"), None),
                    (_, Err(e)) => (Cell::failed(format!("current_exe: {e}")), None),
                };
                if info.truck_read_ms.is_none() {
                    info.truck_read_ms = truck.read_ms;
                    info.truck_diag = truck.bbox_diag.filter(|d| *d > 0.0);
                }
                let occt_cell = match &occt {
                    Err(_) => Cell::failed("not installed"),
                    Ok(()) => occt_rows.get(k).cloned().unwrap_or_else(|| {
                        occt_rows
                            .first()
                            .and_then(|c| c.failure.clone())
                            .map_or_else(|| Cell::failed("no output"), Cell::failed)
                    }),
                };
                rows.push(Row {
                    file: label.clone(),
                    rel,
                    tol,
                    ours,
                    truck,
                    truck_plain,
                    occt: occt_cell,
                });
            }
            infos.push(info);
        }
        let markdown = render(&rows, &infos, start.elapsed());
        println!("\n{markdown}");
        let target = std::env::var_os("CARGO_TARGET_DIR")
            .map_or_else(|| manifest_dir().join("target"), PathBuf::from);
        let out = target.join("step_compare.md");
        match std::fs::create_dir_all(&target).and_then(|()| std::fs::write(&out, &markdown)) {
            Ok(()) => println!("step_compare: table written to {}\n", out.display()),
            Err(e) => eprintln!("step_compare: cannot write {}: {e}", out.display()),
        }
        ok_files
    }

    /// Runs our child on `path` at every relative tolerance; fills the read time, diagonal or
    /// load error of `info` and returns one cell per tolerance (fewer if the child died: the
    /// first missing one then carries the reason).
    fn run_ours(
        exe: &Path,
        path: &Path,
        timeout: Duration,
        memory_mb: Option<u64>,
        info: &mut FileInfo,
    ) -> Vec<Cell> {
        let rels: Vec<String> = REL_TOLERANCES.iter().map(f64::to_string).collect();
        let spec = format!("{}|{}", path.display(), rels.join(","));
        let out = match run_self(exe, OURS_CHILD_ENV, &spec, timeout, memory_mb) {
            Ok(out) => out,
            Err(e) => {
                info.ours_error = Some(format!("cannot run the child: {e}"));
                return Vec::new();
            }
        };
        let mut cells = Vec::new();
        for o in out.stdout.lines().filter_map(json::parse) {
            match o.get("tool") {
                Some(Value::Str(t)) if t == "ours-load" => {
                    let cell = Cell::from_json(&o);
                    info.ours_read_ms = cell.read_ms;
                    info.ours_diag = cell.bbox_diag;
                    info.ours_error = cell.failure;
                }
                Some(Value::Str(t)) if t == "ours" => cells.push(Cell::from_json(&o)),
                _ => {}
            }
        }
        if let Some(why) = out.failure() {
            if info.ours_diag.is_none() && info.ours_error.is_none() {
                info.ours_error = Some(format!("load: {why}"));
            } else if cells.len() < REL_TOLERANCES.len() && info.ours_error.is_none() {
                cells.push(Cell::failed(why));
            }
        }
        cells
    }

    fn run_truck(
        exe: &Path,
        path: &Path,
        tol: f64,
        timeout: Duration,
        memory_mb: Option<u64>,
    ) -> (Cell, Option<Cell>) {
        let spec = format!("{}|{tol}", path.display());
        let out = match run_self(exe, CHILD_ENV, &spec, timeout, memory_mb) {
            Ok(out) => out,
            Err(e) => return (Cell::failed(format!("cannot run the child: {e}")), None),
        };
        let mut robust = None;
        let mut plain = None;
        for o in out.stdout.lines().filter_map(json::parse) {
            match o.get("tool") {
                Some(Value::Str(t)) if t == "truck" => robust = Some(Cell::from_json(&o)),
                Some(Value::Str(t)) if t == "truck-plain" => plain = Some(Cell::from_json(&o)),
                _ => {}
            }
        }
        let failure = out.failure();
        let robust = match (robust, &failure) {
            (Some(cell), _) => cell,
            (None, Some(why)) => Cell::failed(why.clone()),
            (None, None) => Cell::failed("child printed no result"),
        };
        // The plain mesher runs after the robust one: a failure after a robust result is its.
        let plain = match (plain, &failure) {
            (Some(cell), _) => Some(cell),
            (None, Some(why)) if robust.failure.is_none() => Some(Cell::failed(why.clone())),
            _ => None,
        };
        (robust, plain)
    }

    /// `Ok` if `python3 -c "import OCP"` works.
    fn occt_available() -> Result<(), String> {
        let out = Command::new("python3")
            .args(["-c", "import OCP"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .map_err(|e| format!("cannot run python3: {e}"))?;
        if out.status.success() {
            Ok(())
        } else {
            let err = String::from_utf8_lossy(&out.stderr);
            Err(err
                .lines()
                .last()
                .unwrap_or("import OCP failed")
                .trim()
                .to_owned())
        }
    }

    /// Runs the OCCT script at `tols` (absolute, in our units: the script picks millimetres or
    /// the file's unit, whichever matches `our_diag`), or at [`REL_TOLERANCES`] of OCCT's own
    /// diagonal in file units when we have none; the cells in tolerance order, OCCT's diagonal.
    fn run_occt(
        path: &Path,
        tols: Option<&[f64]>,
        our_diag: Option<f64>,
    ) -> (Vec<Cell>, Option<f64>) {
        let mut cmd = Command::new("python3");
        cmd.arg(manifest_dir().join("benches/occt_mesh.py"))
            .arg(path);
        match (tols, our_diag) {
            (Some(t), Some(d)) => cmd
                .args(t.iter().map(f64::to_string))
                .args(["--units", "auto", "--match-diag"])
                .arg(d.to_string()),
            _ => cmd
                .args(["--units", "file", "--rel"])
                .args(REL_TOLERANCES.iter().map(f64::to_string)),
        };
        let out = match run_with_timeout(cmd, OCCT_TIMEOUT) {
            Ok(out) => out,
            Err(e) => return (vec![Cell::failed(format!("cannot run python3: {e}"))], None),
        };
        let objects: Vec<Object> = out.stdout.lines().filter_map(json::parse).collect();
        let diag = objects.iter().find_map(|o| match o.get("bbox_diag") {
            Some(Value::Num(d)) => Some(*d),
            _ => None,
        });
        let mut cells: Vec<Cell> = objects.iter().map(Cell::from_json).collect();
        if cells.len() < REL_TOLERANCES.len()
            && let Some(why) = out.failure()
        {
            cells.push(Cell::failed(why));
        }
        (cells, diag)
    }

    fn render(rows: &[Row], infos: &[FileInfo], elapsed: Duration) -> String {
        let mut footnotes: Vec<String> = Vec::new();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "## STEP tessellation: patchwork vs truck-meshalgo vs Open CASCADE\n\n\
             Per tool: tessellation time in ms (ours: median of {OUR_RUNS} runs; truck: median \
             of up to {TRUCK_RUNS}; OCCT: one run), triangles, faces meshed / faces total, and \
             the measured max distance to the true surface (× the tolerance).\n"
        );
        let _ = writeln!(
            s,
            "| file | tol (rel) | tol (abs) | ours ms | ours tris | ours faces | ours max err \
             | truck ms | truck tris | truck faces | truck max err | occt ms | occt tris \
             | occt faces | occt max err |"
        );
        let _ = writeln!(s, "|{}", "---|".repeat(15));
        for r in rows {
            let tol = r.tol.map_or("?".into(), |t| format!("{t:.3e}"));
            let _ = write!(s, "| {} | {:.0e} | {tol} |", r.file, r.rel);
            for cell in [&r.ours, &r.truck, &r.occt] {
                for col in cell.columns(&mut footnotes) {
                    let _ = write!(s, " {col} |");
                }
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "\nFaces: ours counts one face per placed instance (a part used twice in an assembly \
             counts twice) plus the faces the reader skipped; truck counts the faces of every \
             shell once, without assembly placement; OCCT's `TopExp_Explorer` visits each \
             occurrence of an instanced face. Faces meshed = faces with at least one triangle. \
             Errors: ours is the largest `PatchMesh::error` (each patch's own measurement, trim \
             error shown when > 0); truck and OCCT are measured at the centroid and edge \
             midpoints of every triangle against the face's untrimmed surface (samples whose \
             projection failed are listed as unprojected); a mesh that covers parts of the \
             surface outside the face is not penalised by this (compare the diagonals below). \
             OCCT meshes with angular deflection {OCCT_ANGULAR_DEFLECTION} rad (set in \
             `occt_mesh.py`), which often makes its mesh finer \
             than the linear tolerance asks. Lengths are in our reader's unit; OCCT is run in \
             the same unit (millimetres or the file's, whichever diagonal matches ours).\n"
        );

        let _ = writeln!(
            s,
            "### Reading and units\n\n\
             | file | ours read ms | ours diag | truck read ms | truck diag (unplaced mesh) \
             | occt read ms | occt diag | occt diag (mm) | file unit | occt output unit \
             | tolerance from |\n\
             |---|---|---|---|---|---|---|---|---|---|---|"
        );
        let opt = |x: Option<f64>, prec: usize| x.map_or("—".into(), |v| format!("{v:.prec$}"));
        for i in infos {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                i.file,
                opt(i.ours_read_ms, 1),
                i.ours_error
                    .as_ref()
                    .map_or_else(|| opt(i.ours_diag, 4), |e| format!("error: {e}")),
                opt(i.truck_read_ms, 1),
                opt(i.truck_diag, 4),
                opt(i.occt_read_ms, 1),
                opt(i.occt_diag, 4),
                opt(i.occt_diag_mm, 4),
                i.occt_unit.as_deref().unwrap_or("—"),
                i.occt_units.as_deref().unwrap_or("—"),
                i.diag_source,
            );
        }
        let mismatches: Vec<String> = infos
            .iter()
            .filter_map(|i| {
                let (a, b) = (i.ours_diag?, i.occt_diag?);
                ((a - b).abs() > 1e-3 * a.max(b))
                    .then(|| format!("{}: ours {a:.4} vs OCCT {b:.4} ({:.4}×)", i.file, a / b))
            })
            .collect();
        let compared = infos
            .iter()
            .filter(|i| i.ours_diag.is_some() && i.occt_diag.is_some())
            .count();
        if compared == 0 {
            let _ = writeln!(
                s,
                "\nDiagonals not compared: no file has both ours and OCCT's."
            );
        } else if mismatches.is_empty() {
            let _ = writeln!(
                s,
                "\nOur diagonals and OCCT's (tight box of the faces, in the unit matching ours) \
                 agree within 0.1 % where both exist."
            );
        } else {
            let _ = writeln!(
                s,
                "\n**Diagonals disagree** (ours vs OCCT's tight box of the faces, in the unit \
                 matching ours; the tolerances of every tool are scaled from ours): {}",
                mismatches.join("; ")
            );
        }

        let plain: Vec<&Row> = rows.iter().filter(|r| r.truck_plain.is_some()).collect();
        if !plain.is_empty() {
            let _ = writeln!(
                s,
                "\n### truck `triangulation` (non-robust), same child\n\n\
                 | file | tol (rel) | ms | tris | faces | max err |\n|---|---|---|---|---|---|"
            );
            for r in plain {
                if let Some(c) = &r.truck_plain {
                    let [a, b, cc, d] = c.columns(&mut footnotes);
                    let _ = writeln!(s, "| {} | {:.0e} | {a} | {b} | {cc} | {d} |", r.file, r.rel);
                }
            }
        }
        if !footnotes.is_empty() {
            let _ = writeln!(s, "\n### Notes\n");
            for (i, f) in footnotes.iter().enumerate() {
                let _ = writeln!(s, "{}. {}", i + 1, f.replace('\n', " "));
            }
        }
        let _ = writeln!(s, "\nTable built in {:.1} s.", elapsed.as_secs_f64());
        s
    }

    /// Address-space limit for truck children, MiB.
    fn truck_memory_limit_mb() -> Option<u64> {
        if let Ok(v) = std::env::var(TRUCK_MEMORY_ENV) {
            return v.trim().parse::<u64>().ok().filter(|m| *m > 0);
        }
        let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
        let kb: u64 = meminfo
            .lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))?
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some((kb / 1024 / 2).min(4 * 1024))
    }
}
