//! WGSL sources, composed from the files in `shaders/` (WGSL has no `#include`).

/// The fat-border expansion functions shared by the render shader and the compute twin.
pub(crate) const FAT_BORDER_LIB: &str = include_str!("../../shaders/fat_border_lib.wgsl");

/// Surfaces + fat borders (vertex) and colour / linear-depth (fragment) entry points.
pub(crate) const SCENE: &str = concat!(
    include_str!("../../shaders/fat_border_lib.wgsl"),
    "\n",
    include_str!("../../shaders/scene.wgsl")
);

/// Compute twin of the fat-border expansion, for tests.
pub const FAT_BORDER_TWIN: &str = concat!(
    include_str!("../../shaders/fat_border_lib.wgsl"),
    "\n",
    include_str!("../../shaders/fat_border_twin.wgsl")
);

/// Copies a read-back frame onto a window surface (the viewer).
pub(crate) const PRESENT: &str = include_str!("../../shaders/present.wgsl");

/// Every composed module with the `shaders/` files it is made of (validated by a test, which
/// also checks that every file in `shaders/` is used by some module).
pub const MODULES: &[(&str, &str, &[&str])] = &[
    ("fat_border_lib", FAT_BORDER_LIB, &["fat_border_lib.wgsl"]),
    ("scene", SCENE, &["fat_border_lib.wgsl", "scene.wgsl"]),
    (
        "fat_border_twin",
        FAT_BORDER_TWIN,
        &["fat_border_lib.wgsl", "fat_border_twin.wgsl"],
    ),
    ("present", PRESENT, &["present.wgsl"]),
];

/// Parses and validates a WGSL module with naga; the error names line and column.
pub fn validate(name: &str, source: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    Ok(())
}
