//! The trimmed-face tessellator on whatever faces the STEP and IGES readers accept. The first
//! byte picks the reader (its low bit) and the tolerance (10⁻⁴ … 10⁻¹ of the model's size);
//! the rest is the file. Every patch gives a bounded mesh with a finite error, or a failure
//! naming the face — never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use patchwork::tessellate::{PatchMesh, Tessellators};

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let model = if first & 1 == 0 {
        patchwork::io::step::read(rest, std::path::Path::new("fuzz.step"))
    } else {
        patchwork::io::iges::read(rest, std::path::Path::new("fuzz.iges"))
    };
    let Ok(model) = model else {
        return;
    };
    let Ok(scene) = patchwork::prep::step::assemble(model, &patchwork::util::NoProgress) else {
        return;
    };
    let relative = 10f64.powf(-f64::from((first >> 1) % 4) - 1.0);
    let eps = relative * scene.bounds.radius.max(1e-300);
    let mut t = Tessellators::new();
    let mut out = PatchMesh::default();
    for p in scene.patches.iter().take(8) {
        t.patch(p, eps, &mut out);
        if out.failure.is_none() {
            assert!(out.error.is_finite(), "face {}: error {}", p.id, out.error);
            let n = out.positions.len();
            assert!(out.triangles.iter().flatten().all(|&i| (i as usize) < n));
        }
    }
});
