//! patchwork — crack-free rendering of multi-patch surfaces with fat borders.
//!
//! Every patch is tessellated independently to an object-space error ε derived from a pixel
//! error for the current view (`view`); the gaps this leaves along shared borders are covered by
//! fat borders expanded in a WGSL vertex shader (`render`), after Balázs, Guthe and Klein,
//! "Fat Borders: Gap Filling for Efficient View-dependent LOD Rendering" (2004).
//!
//! Data flows one way: `io` → `model` → `tessellate` → `render`; `view` converts pixel errors
//! to object errors in one place; `check` measures rendered images (cracks, growth, goldens).
//!
//! # Drawing patchwork inside your own wgpu renderer
//!
//! [`embed::Renderer`] is the entry point: it draws a scene ([`prep::load`]) into your device,
//! your render pass and your camera, with the LOD frame loop and fat borders.
//! `examples/embed.rs` is a whole program (its own headless device, targets and triangle,
//! drawn beside the teapot in one pass).
//!
//! ```no_run
//! # fn frame(
//! #     device: &wgpu::Device,
//! #     queue: &wgpu::Queue,
//! #     pass: &mut wgpu::RenderPass<'_>,
//! # ) -> Result<(), Box<dyn std::error::Error>> {
//! use patchwork::embed::glam::{Mat4, Vec3};
//! use patchwork::embed::{Camera, EmbedOptions, Renderer};
//!
//! let scene = patchwork::prep::load(std::path::Path::new("models/teapot.bpt"))?;
//! let mut teapot = Renderer::new(
//!     device,
//!     queue,
//!     wgpu::TextureFormat::Bgra8UnormSrgb, // your pass's colour target
//!     wgpu::TextureFormat::Depth32Float,   // and its depth target
//!     scene,
//!     EmbedOptions::default(),
//! )?;
//! let camera = Camera {
//!     view: Mat4::look_at_rh(Vec3::new(8.0, -8.0, 6.0), Vec3::ZERO, Vec3::Z),
//!     projection: Mat4::perspective_rh(0.8, 16.0 / 9.0, 0.1, 100.0),
//!     viewport: (1920, 1080),
//! };
//! // Each frame, before your pass: re-tessellation within the budget, uploads, the camera.
//! teapot.prepare(&camera, 0.5)?;
//! // Inside your pass, among your own draws:
//! teapot.draw(pass);
//! # Ok(())
//! # }
//! ```
//!
//! # What is public
//!
//! A caller needs [`embed`], [`prep`] (loading a file into a [`model::Scene`]) and [`model`].
//! The other modules are `pub` only because patchwork's own command-line tool, tests, benchmarks
//! and examples are separate crates that use them (offscreen rendering, crack checks, readers,
//! export); they are hidden from these docs and are not a stable API. Items that nothing outside
//! the library uses are `pub(crate)`.

#[doc(hidden)]
pub mod anim;
#[doc(hidden)]
pub mod check;
#[doc(hidden)]
pub mod drive;
pub mod embed;
#[doc(hidden)]
pub mod export;
#[doc(hidden)]
pub mod frame;
#[doc(hidden)]
pub mod geom;
#[doc(hidden)]
pub mod io;
#[doc(hidden)]
pub mod isolate;
#[doc(hidden)]
pub mod lod;
pub mod model;
#[doc(hidden)]
pub mod mt;
pub mod prep;
#[doc(hidden)]
pub mod render;
#[doc(hidden)]
pub mod report;
#[doc(hidden)]
pub mod strips;
#[doc(hidden)]
pub mod tessellate;
#[doc(hidden)]
pub mod util;
#[doc(hidden)]
pub mod view;
#[cfg(feature = "viewer")]
#[doc(hidden)]
pub mod viewer;
