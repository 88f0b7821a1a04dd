//! patchwork — crack-free rendering of multi-patch surfaces with fat borders.
//!
//! Every patch is tessellated independently to an object-space error ε derived from a pixel
//! error for the current view (`view`); the gaps this leaves along shared borders are covered by
//! fat borders expanded in a WGSL vertex shader (`render`), after Balázs, Guthe and Klein,
//! "Fat Borders: Gap Filling for Efficient View-dependent LOD Rendering" (2004).
//!
//! Data flows one way: `io` → `model` → `tessellate` → `render`; `view` converts pixel errors
//! to object errors in one place; `check` measures rendered images (cracks, growth, goldens).

pub mod anim;
pub mod check;
pub mod drive;
pub mod embed;
pub mod export;
pub mod frame;
pub mod geom;
pub mod io;
pub mod isolate;
pub mod lod;
pub mod model;
pub mod mt;
pub mod prep;
pub mod render;
pub mod report;
pub mod strips;
pub mod tessellate;
pub mod util;
pub mod view;
#[cfg(feature = "viewer")]
pub mod viewer;
