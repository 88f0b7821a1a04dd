//! Every WGSL file in `shaders/` is used by a composed module, and every module validates
//! with naga.

use std::collections::BTreeSet;

use patchwork::render::shaders::{MODULES, validate};

#[test]
fn every_shader_module_validates_with_naga() {
    for (name, source, _) in MODULES {
        if let Err(e) = validate(name, source) {
            panic!("{e}");
        }
    }
}

#[test]
fn every_wgsl_file_is_part_of_a_validated_module() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let on_disk: BTreeSet<String> = std::fs::read_dir(&dir)
        .expect("shaders/ exists")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    let used: BTreeSet<String> = MODULES
        .iter()
        .flat_map(|(_, _, files)| files.iter().map(|f| f.to_string()))
        .collect();
    assert_eq!(
        on_disk, used,
        "shaders/ and render::shaders::MODULES disagree"
    );
    // The composed sources really contain the files they name.
    for (name, source, files) in MODULES {
        for f in *files {
            let text = std::fs::read_to_string(dir.join(f)).expect("readable");
            assert!(source.contains(text.trim()), "{name} does not include {f}");
        }
    }
}

#[test]
fn validation_reports_line_and_column() {
    let err = validate("broken", "fn f() -> f32 {\n  return oops;\n}\n").expect_err("invalid");
    assert!(err.contains("broken"), "{err}");
    assert!(err.contains(":2:") || err.contains("2:"), "{err}");
}
