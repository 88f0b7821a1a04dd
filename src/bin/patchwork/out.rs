//! Where the command's output goes, set once from the global flags.
//!
//! - **Data** (what the command found or made: stats, check results, the summary of a written
//!   file) goes to stdout as text, or as one JSON object with `--json`.
//! - **Diagnostics** (the adapter chosen, warnings, progress bars) go to stderr.
//! - `-q/--quiet` silences both text data and diagnostics; errors (`error: …`, exit code 2) and
//!   `--json` output are always printed.

use std::io::Write as _;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

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

/// Set once stdout is closed (`patchwork stats … | head`): the command goes on without
/// printing (its work, files and exit code stand) instead of panicking in `println!`.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes `text` to stdout; a closed pipe stops further output, nothing else.
pub fn write(text: std::fmt::Arguments<'_>) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if out.write_fmt(text).and_then(|()| out.flush()).is_err() {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}

/// A line on stdout through [`write`] (`println!` panics on a closed pipe).
macro_rules! outln {
    () => {
        $crate::out::write(format_args!("\n"))
    };
    ($($t:tt)*) => {
        $crate::out::write(format_args!("{}\n", format_args!($($t)*)))
    };
}

/// Prints `value` as one line of JSON on stdout (with `--json`).
pub fn emit(value: &serde_json::Value) {
    if json() {
        outln!("{value}");
    }
}

/// A line of text data on stdout (not with `--quiet` or `--json`).
macro_rules! data {
    ($($t:tt)*) => {
        if $crate::out::text() {
            $crate::out::outln!($($t)*);
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

pub(crate) use {data, note, outln};
