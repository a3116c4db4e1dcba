//! Running the `nephele` binary from integration tests.

use std::path::Path;
use std::process::{Command, Output};

/// `nephele ARGS`, its output captured.
pub fn nephele(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nephele"))
        .args(args)
        .output()
        .expect("run nephele")
}

/// The sorted file names in `dir` (none when it does not exist).
pub fn files_in(dir: &Path) -> Vec<String> {
    match std::fs::read_dir(dir) {
        Ok(rd) => {
            let mut names: Vec<String> = rd
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            names
        }
        Err(_) => vec![],
    }
}

/// Runs nephele and asserts that it succeeded.
pub fn succeeds(args: &[&str]) -> Output {
    let o = nephele(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Runs nephele and asserts the way a slip must end: a non-zero exit, stderr one line
/// `error: …` that contains `names_fix`, and nothing written in `out` (when given).
/// Returns that line.
pub fn refuses(args: &[&str], names_fix: &str, out: Option<&Path>) -> String {
    let o = nephele(args);
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert!(!o.status.success(), "{args:?} should fail; stderr: {err}");
    assert!(
        err.lines().count() == 1 && err.starts_with("error: "),
        "{args:?}: not one error line: {err}"
    );
    assert!(
        err.contains(names_fix),
        "{args:?}: {err:?} lacks {names_fix:?}"
    );
    if let Some(dir) = out {
        assert!(
            files_in(dir).is_empty(),
            "{args:?} left files: {:?}",
            files_in(dir)
        );
    }
    err
}
