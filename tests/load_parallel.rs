//! STEP files load the same on one thread as on several: faces are converted, truck's entity
//! instances parsed and faces probed in parallel, and the scene keeps file order — the same
//! patches with the same bounds and placements, the same skipped faces and the same warnings,
//! in the same order.

mod common;

use patchwork::model::{PatchSurface, Scene};

fn load_on(threads: usize, name: &str) -> Scene {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| common::load(name))
}

/// Everything a patch is, as comparable data: id, STEP face, bounds, placement, part,
/// instance, colour.
fn patches(scene: &Scene) -> Vec<String> {
    scene
        .patches
        .iter()
        .map(|p| {
            let face = match &p.surface {
                PatchSurface::Trimmed(f) => f.id,
                _ => u64::MAX,
            };
            format!(
                "{} #{face} {:?} {:?} {} {} {:?}",
                p.id, p.bounds, p.transform, p.part, p.instance, p.color
            )
        })
        .collect()
}

#[test]
fn parallel_step_loads_give_the_sequential_scene() {
    // Two files whose loose-edge warning lists edges (its order is the conversion order), and
    // a KiCad board of 12 062 patches.
    for name in [
        "corpus/L_Wurth_WE-HCFT-3521.step.gz",
        "corpus/SampleCrankshaft4A.stp.gz",
        "corpus/kicad-demo-tinytapeout.step.gz",
    ] {
        let one = load_on(1, name);
        let many = load_on(4, name);
        assert!(!one.patches.is_empty(), "{name}");
        assert_eq!(one.patches.len(), many.patches.len(), "{name}");
        let (a, b) = (patches(&one), patches(&many));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert_eq!(x, y, "{name}: patch {k}");
        }
        assert_eq!(one.skipped, many.skipped, "{name}");
        assert_eq!(one.warnings, many.warnings, "{name}");
        assert_eq!(one.instances, many.instances, "{name}");
        assert_eq!(one.bbox, many.bbox, "{name}");
    }
    // The warning the order matters for is there.
    let wurth = load_on(4, "corpus/L_Wurth_WE-HCFT-3521.step.gz");
    assert!(
        wurth
            .warnings
            .iter()
            .any(|w| w.starts_with("12 edges have vertices off their curve")),
        "{:?}",
        wurth.warnings
    );
}
