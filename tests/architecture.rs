//! The shape ARCHITECTURE.md promises, checked on the source: data flows one way through the
//! stages (no module imports from a later stage), the scene holds no interior mutability, and
//! no source file grows past 800 lines without saying why at its top.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The library's top-level modules in stage order: a module may use modules of its own or an
/// earlier stage only. Keep in step with ARCHITECTURE.md.
const STAGES: &[&[&str]] = &[
    &["geom", "isolate", "util"],
    &["mt"],
    &["model"],
    &["view"],
    &["io"],
    &["tessellate"],
    &["prep"],
    &["strips"],
    &["lod"],
    &["render"],
    &["check"],
    &["anim"],
    &["frame"],
    &["embed"],
    &["drive"],
    &["export"],
    &["report"],
    &["viewer"],
];

/// Longest source file without a reason.
const MAX_LINES: usize = 800;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The library's top-level modules (`mod x;` / `pub mod x;` in lib.rs) with their source text, tests
/// (from `#[cfg(test)]` on) and comments left out.
fn modules() -> BTreeMap<String, String> {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).expect("src/lib.rs");
    let mut out = BTreeMap::new();
    for line in lib.lines() {
        let line = line.trim();
        let Some(name) = line
            .strip_prefix("pub ")
            .unwrap_or(line)
            .strip_prefix("mod ")
            .and_then(|r| r.strip_suffix(';'))
        else {
            continue;
        };
        let mut files = Vec::new();
        let single = root().join(format!("src/{name}.rs"));
        if single.exists() {
            files.push(single);
        }
        rust_files(&root().join(format!("src/{name}")), &mut files);
        assert!(!files.is_empty(), "module {name}: no source file");
        let mut text = String::new();
        for f in files {
            let src = std::fs::read_to_string(&f).expect("source");
            for l in src.lines() {
                if l.trim_start().starts_with("#[cfg(test)]") {
                    break;
                }
                if !l.trim_start().starts_with("//") {
                    text.push_str(l);
                    text.push('\n');
                }
            }
        }
        out.insert(name.to_owned(), text);
    }
    out
}

/// The top-level modules `src` refers to through `crate::…` (also `use crate::{a, b::c}`).
fn uses(src: &str) -> Vec<String> {
    let mut found = Vec::new();
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut rest = src;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                found.push(ident(item));
            }
        } else {
            found.push(ident(rest));
        }
    }
    found.retain(|m| !m.is_empty());
    found
}

/// Every import that runs back up the stages: (module, what it uses, why that is wrong).
fn violations(modules: &BTreeMap<String, String>) -> Vec<String> {
    let stage_of = |m: &str| STAGES.iter().position(|s| s.contains(&m));
    let mut bad = Vec::new();
    for (name, src) in modules {
        let Some(own) = stage_of(name) else {
            bad.push(format!(
                "{name}: not in STAGES (give the new module its stage)"
            ));
            continue;
        };
        let mut seen: Vec<String> = uses(src);
        seen.sort();
        seen.dedup();
        for dep in seen {
            if dep == *name || !modules.contains_key(&dep) {
                continue;
            }
            match stage_of(&dep) {
                Some(s) if s <= own => {}
                _ => bad.push(format!(
                    "{name} (stage {own}) uses {dep} (stage {:?}), a later stage",
                    stage_of(&dep)
                )),
            }
        }
    }
    bad
}

#[test]
fn no_module_imports_from_a_later_stage() {
    let modules = modules();
    let bad = violations(&modules);
    assert!(
        bad.is_empty(),
        "imports against the stages:\n{}",
        bad.join("\n")
    );
}

/// The check sees a backward import (here: the model reaching up into the renderer) and a
/// module left out of the stage list; a grouped `use crate::{…}` counts too.
#[test]
fn the_stage_check_fails_on_a_backward_import() {
    let mut modules = modules();
    let model = modules.get_mut("model").expect("model");
    model.push_str("use crate::{geom, render::Frame};\n");
    let bad = violations(&modules);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(bad[0].starts_with("model (stage 2) uses render"), "{bad:?}");
    let mut modules = self::modules();
    modules.insert("newcomer".into(), String::new());
    assert!(violations(&modules)[0].starts_with("newcomer: not in STAGES"));
}

/// Interior mutability found in the scene's modules (`model`, and `mt`, whose hierarchies
/// the scene holds).
fn interior_mutability(modules: &BTreeMap<String, String>) -> Vec<String> {
    let mut found = Vec::new();
    for name in ["model", "mt"] {
        let src = &modules[name];
        for needle in [
            "Mutex", "RwLock", "RefCell", "Cell<", "OnceCell", "OnceLock", "Atomic",
        ] {
            if src.contains(needle) {
                found.push(format!("{name} holds {needle}"));
            }
        }
    }
    found
}

/// The scene is immutable after load: per-view state cannot hide in it.
#[test]
fn the_scene_holds_no_interior_mutability() {
    let found = interior_mutability(&modules());
    assert!(
        found.is_empty(),
        "{}: per-view state belongs to the frame loop or the renderer",
        found.join(", ")
    );
}

/// The check sees a cache put back into a mesh patch.
#[test]
fn the_mutability_check_fails_on_a_cache_in_the_model() {
    let mut modules = modules();
    let model = modules.get_mut("model").expect("model");
    model.push_str("pub struct CutCache(pub std::sync::Mutex<Option<u32>>);\n");
    assert_eq!(interior_mutability(&modules), ["model holds Mutex"]);
}

#[test]
fn no_source_file_is_longer_than_800_lines_without_a_reason() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    let mut long = Vec::new();
    for f in files {
        let src = std::fs::read_to_string(&f).expect("source");
        let n = src.lines().count();
        let reason = src
            .lines()
            .take(40)
            .any(|l| l.contains(&format!("longer than {MAX_LINES} lines")));
        if n > MAX_LINES && !reason {
            long.push(format!("{} ({n} lines)", f.display()));
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines without \"longer than {MAX_LINES} lines\" and a reason at \
         their top:\n{}",
        long.join("\n")
    );
}

/// Library modules that print (`println!` / `eprintln!` / `print!` / `eprint!`): only the
/// binary prints; the library returns data, errors and progress through `prep::Progress`.
fn printing(modules: &BTreeMap<String, String>) -> Vec<String> {
    modules
        .iter()
        .filter(|(_, src)| src.contains("print!(") || src.contains("println!("))
        .map(|(name, _)| name.clone())
        .collect()
}

#[test]
fn the_library_prints_nothing() {
    let mut modules = modules();
    assert_eq!(printing(&modules), Vec::<String>::new());
    // The check sees a warning printed by a reader.
    modules
        .get_mut("io")
        .expect("io")
        .push_str("eprintln!(\"warning: {w}\");\n");
    assert_eq!(printing(&modules), ["io"]);
}
