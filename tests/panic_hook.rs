//! A panic that `isolate::isolated` catches must never reach the process's panic hook, on any
//! thread: libfuzzer's hook aborts the process, and the step fuzz target died on ruststep
//! panics caught on rayon workers (the parallel chunk parse ran under an isolation set on the
//! calling thread only). A hook that counts stands in for libfuzzer's; its own test binary, so
//! no other test's panics reach it.

mod common;

use std::sync::atomic::{AtomicUsize, Ordering};

static REACHED: AtomicUsize = AtomicUsize::new(0);

#[test]
fn caught_panics_never_reach_the_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        REACHED.fetch_add(1, Ordering::SeqCst);
        eprintln!("reached the hook: {info}");
    }));
    let dir = common::root().join("tests/data/fuzz/step");
    let mut read = 0;
    for entry in std::fs::read_dir(&dir).expect("regression inputs") {
        let path = entry.expect("entry").path();
        let bytes = std::fs::read(&path).expect("readable");
        let r = patchwork::io::step::read(&bytes, &path);
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with("ruststep_") {
            // A ruststep panic on a number (overflow): an error, quietly.
            assert!(r.is_err(), "{}: read", path.display());
            read += 1;
        }
    }
    assert!(read >= 2, "{read} inputs");
    assert_eq!(
        REACHED.load(Ordering::SeqCst),
        0,
        "a caught panic reached the hook"
    );
}
