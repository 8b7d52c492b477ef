//! Cross-crate integration tests live in tests/tests/: the ones that need more than one of
//! estimator-core, trainer and hil-sim (e.g. the trainer's vectors replayed by hil-sim on QEMU).

use std::path::PathBuf;

/// A fresh, empty scratch directory for one test: `<tmp>/scratch/<pid>/<tag>`, where `tmp` is
/// the test's `env!("CARGO_TARGET_TMPDIR")` (inside the user's own target directory). Test
/// binaries cannot clean up after their last test, so each one removes, on its first call, the
/// directories left by test processes that are no longer running: a run leaves at most its own
/// scratch behind, never that of every run before it.
pub fn scratch(tmp: &str, tag: &str) -> PathBuf {
    static SWEPT: std::sync::Once = std::sync::Once::new();
    let base = std::path::Path::new(tmp).join("scratch");
    SWEPT.call_once(|| sweep(&base));
    let d = base.join(std::process::id().to_string()).join(tag);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("creating {}: {e}", d.display()));
    d
}

/// Removes `base/<pid>` for every pid without a running process (where `/proc` tells; elsewhere
/// nothing is removed).
fn sweep(base: &std::path::Path) {
    if !std::path::Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(base) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name.to_str().and_then(|n| n.parse::<u32>().ok()) else {
            continue;
        };
        if !std::path::Path::new("/proc").join(pid.to_string()).exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}
