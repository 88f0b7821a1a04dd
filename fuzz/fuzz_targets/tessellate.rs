//! The Bézier tessellator on whatever patches the `.bpt` reader accepts, at a tolerance taken
//! from the first byte (10⁻⁸ … 10 of the patch's size): bounded output, finite error, no panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use patchwork::tessellate::PatchMesh;
use patchwork::tessellate::bezier::{BezierTessellator, MAX_SEGMENTS};

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let Ok(patches) = patchwork::io::bpt::parse(rest, std::path::Path::new("fuzz.bpt")) else {
        return;
    };
    let relative = 10f64.powf(f64::from(first % 10) - 8.0);
    let mut t = BezierTessellator::new();
    let mut out = PatchMesh::default();
    for p in patches.iter().take(8) {
        let eps = relative * p.bounding_sphere().radius.max(1e-300);
        t.tessellate(p, eps, &mut out);
        let max = 2 * (MAX_SEGMENTS as usize).pow(2);
        assert!(out.triangles.len() <= max, "{} triangles", out.triangles.len());
    }
});
