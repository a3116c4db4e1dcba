//! The rules the docs keep: the README and docs/ within their line budgets, and no issue number, running count of work periods or calendar date in the
//! docs, the code, the tests or the scripts (docs/results.md alone carries the date of its
//! run; history lives in CHANGELOG.md and git).

use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Lines of a file.
fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .count()
}

/// Every file under `dir` (depth first) whose extension is one of `exts`.
fn files(dir: &Path, exts: &[&str]) -> Vec<PathBuf> {
    let Ok(read) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for p in read.map(|e| e.unwrap().path()) {
        if p.is_dir() {
            out.extend(files(&p, exts));
        } else if p.extension().is_some_and(|e| exts.iter().any(|x| e == *x)) {
            out.push(p);
        }
    }
    out
}

#[test]
fn the_readme_and_the_docs_stay_within_their_budgets() {
    let docs = files(&Path::new(ROOT).join("docs"), &["md"]);
    let total: usize = docs.iter().map(|p| lines(p)).sum();
    assert!(docs.len() >= 8, "docs/ read: {docs:?}");
    assert!(total <= 3000, "docs/ holds {total} lines, more than 3,000");
    let collector = lines(&Path::new(ROOT).join("docs/collector.md"));
    assert!(collector <= 700, "docs/collector.md: {collector} lines");
    let readme = lines(&Path::new(ROOT).join("README.md"));
    assert!(readme <= 150, "README.md: {readme} lines");
}

/// Where `text` names an issue ("issue 30", "issues #4"), a work period ("session 12") or a
/// date (2026-12-07): the words found.
fn history_in(text: &str, dates_allowed: bool) -> Vec<String> {
    let lower = text.to_lowercase();
    let mut found = Vec::new();
    for word in ["issue", "issues", "session", "sessions"] {
        let mut from = 0;
        while let Some(at) = lower[from..].find(word) {
            let start = from + at;
            let rest = &lower[start + word.len()..];
            let before_ok = !lower[..start].ends_with(|c: char| c.is_alphanumeric());
            let number = rest.trim_start_matches([' ', '#']);
            let gap = rest.len() - number.len();
            let digits = number.bytes().take_while(u8::is_ascii_digit).count();
            if before_ok && gap > 0 && digits > 0 {
                found.push(lower[start..start + word.len() + gap + digits].to_string());
            }
            from = start + word.len();
        }
    }
    if !dates_allowed {
        let b = text.as_bytes();
        for i in 0..b.len().saturating_sub(9) {
            let d = |k: usize| b[i + k].is_ascii_digit();
            let edge = i == 0 || !b[i - 1].is_ascii_digit();
            let shape = d(0) && d(1) && d(2) && d(3) && b[i + 4] == b'-' && d(5) && d(6);
            if edge && shape && b[i + 7] == b'-' && d(8) && d(9) && &b[i..i + 2] == b"20" {
                found.push(String::from_utf8_lossy(&b[i..i + 10]).into_owned());
            }
        }
    }
    found
}

#[test]
fn no_page_or_source_carries_an_issue_number_a_work_period_or_a_date() {
    let root = Path::new(ROOT);
    let mut checked = vec![root.join("README.md")];
    checked.extend(files(&root.join("docs"), &["md"]));
    for dir in [
        "src",
        "runtime/src",
        "capi/src",
        "python/src",
        "wgsl/src",
        "refbench/src",
    ] {
        checked.extend(files(&root.join(dir), &["rs", "wgsl", "c", "h"]));
    }
    checked.extend(files(&root.join("tests"), &["rs"]));
    checked.extend(files(&root.join("scripts"), &["sh", "py"]));
    let me = root.join("tests/docs_rules.rs");
    let mut broken = Vec::new();
    for path in checked.iter().filter(|p| **p != me) {
        let text = std::fs::read_to_string(path).unwrap();
        let dates_allowed = path.ends_with("docs/results.md");
        for word in history_in(&text, dates_allowed) {
            broken.push(format!("{}: {word}", path.display()));
        }
    }
    assert!(checked.len() > 100, "{} files read", checked.len());
    assert!(broken.is_empty(), "{broken:#?}");
}

/// The reader finds what it must, and not what it must not.
#[test]
fn the_reader_finds_issue_numbers_periods_and_dates() {
    let found = history_in("see issue 30, Issues #4; session 12 on 2026-12-07", false);
    assert_eq!(found, ["issue 30", "issues #4", "session 12", "2026-12-07"]);
    assert!(history_in("the issue is 3D; tissue 4; 12026-12-07; sessions", false).is_empty());
    assert!(history_in("2026-12-07", true).is_empty());
}
