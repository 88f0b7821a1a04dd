//! Running code that may panic (truck's geometry code has hard `assert!`s) so that one bad face
//! cannot abort a whole file: the panic becomes an error message, and is not printed.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<u32> = const { Cell::new(0) };
}

static HOOK: Once = Once::new();

/// Installs (once) a panic hook that stays silent inside [`isolated`] and defers to the
/// previous hook everywhere else.
fn install_hook() {
    HOOK.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) == 0 {
                previous(info);
            }
        }));
    });
}

/// Runs `f`, turning a panic into `Err(message)`.
///
/// This catches unwinding panics only; an abort (e.g. out of memory, a stack overflow) still
/// ends the process, which is why the benchmark runs truck's own mesher in a child process
/// and the STEP reader refuses reference cycles before truck follows them.
///
/// Quiet only on the calling thread: a panic on a rayon worker that `f` waits for is carried
/// back and caught here, but the panic hook has already run on the worker (libFuzzer's hook
/// aborts there). Code that may panic inside a parallel loop is isolated per item on its
/// worker (the STEP chunk parse, face conversion and probing, trimmed tessellation); the one
/// isolated call with parallel work inside, `drive::scale`'s frames, wants the message.
pub fn isolated<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install_hook();
    QUIET.with(|q| q.set(q.get() + 1));
    let result = panic::catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(q.get().saturating_sub(1)));
    result.map_err(|payload| {
        if let Some(s) = payload.downcast_ref::<&str>() {
            format!("panicked: {s}")
        } else if let Some(s) = payload.downcast_ref::<String>() {
            format!("panicked: {s}")
        } else {
            "panicked".to_owned()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_and_values_pass_through() {
        assert_eq!(isolated(|| 7), Ok(7));
        match isolated(|| -> u32 { panic!("bad face") }) {
            Err(e) => assert!(e.contains("bad face"), "{e}"),
            Ok(v) => panic!("expected an error, got {v}"),
        }
    }
}
