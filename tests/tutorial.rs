//! docs/tutorial.md as a user follows it: every `sh` block, in order, in one empty folder, with
//! this build's `nephele` on PATH; each must exit 0, and the files the page promises must exist.

use std::path::Path;
use std::process::Command;

/// The page's `sh` blocks, in order.
fn shell_blocks(page: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in page.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```sh") => current = Some(String::new()),
            (Some(_), "```") => blocks.push(current.take().unwrap()),
            (Some(b), l) => {
                b.push_str(l);
                b.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

#[test]
fn every_shell_block_of_the_tutorial_runs() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = std::fs::read_to_string(repo.join("docs/tutorial.md")).unwrap();
    let blocks = shell_blocks(&page);
    assert_eq!(blocks.len(), 3, "the tutorial's three steps");
    let bin = Path::new(env!("CARGO_BIN_EXE_nephele")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let dir = tempfile::tempdir().unwrap();
    for (k, block) in blocks.iter().enumerate() {
        let o = Command::new("bash")
            .args(["-euo", "pipefail", "-c", block])
            .current_dir(dir.path())
            .env("PATH", &path)
            .env("REPO", repo)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "block {} failed:\n{block}\nstderr: {}",
            k + 1,
            String::from_utf8_lossy(&o.stderr)
        );
    }
    for file in [
        "tables20/transport.ntt",
        "tables20/manifest.json",
        "ref/render.json",
        "fast/render.json",
        "cmp/report.json",
        "cmp/panel.png",
    ] {
        assert!(dir.path().join(file).exists(), "{file} missing");
    }
    let manifest = std::fs::read_to_string(dir.path().join("tables20/manifest.json")).unwrap();
    assert!(
        manifest.contains("d = 20 um"),
        "the manifest does not name 20 µm"
    );
}
