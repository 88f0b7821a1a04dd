//! Where the command's output goes, set once from the global flags.
//!
//! - **Data** (what the command found or made: stats, check results, the summary of a written
//!   file) goes to stdout as text, or as one JSON object with `--json`.
//! - **Diagnostics** (the adapter chosen, warnings, progress bars) go to stderr.
//! - `-q/--quiet` silences both text data and diagnostics; errors (`error: …`, exit code 2) and
//!   `--json` output are always printed.

use std::sync::OnceLock;

#[derive(Clone, Copy, Debug, Default)]
pub struct Mode {
    pub quiet: bool,
    pub json: bool,
}

static MODE: OnceLock<Mode> = OnceLock::new();

/// Sets the mode (first call wins: `main` calls it once).
pub fn set(mode: Mode) {
    let _ = MODE.set(mode);
}

pub fn mode() -> Mode {
    MODE.get().copied().unwrap_or_default()
}

/// Whether text data is printed (neither quiet nor JSON).
pub fn text() -> bool {
    let m = mode();
    !m.quiet && !m.json
}

/// Whether diagnostics are printed.
pub fn diagnostics() -> bool {
    !mode().quiet
}

/// Whether the command prints a JSON object.
pub fn json() -> bool {
    mode().json
}

/// Prints `value` as one line of JSON on stdout (with `--json`).
pub fn emit(value: &serde_json::Value) {
    if json() {
        println!("{value}");
    }
}

/// A line of text data on stdout (not with `--quiet` or `--json`).
macro_rules! data {
    ($($t:tt)*) => {
        if $crate::out::text() {
            println!($($t)*);
        }
    };
}

/// A diagnostic line on stderr (not with `--quiet`).
macro_rules! note {
    ($($t:tt)*) => {
        if $crate::out::diagnostics() {
            eprintln!($($t)*);
        }
    };
}

pub(crate) use {data, note};
