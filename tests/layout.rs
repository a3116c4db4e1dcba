//! The rules the layout keeps (docs/architecture.md), checked over the source's paths: a
//! stage never imports a later one, the render floor knows no wing and the wings not each
//! other, clap stays in the command line, and the runtime's transport modules import each
//! other one way. Comments are not read (a doc link may name any module).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Every `.rs` file under `dir`, depth first, in name order.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut out = Vec::new();
    for p in entries {
        if p.is_dir() {
            out.extend(sources(&p));
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
    out
}

/// The file's code with its comments blanked (line comments; block comments are not used).
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .map(|line| match line.find("//") {
            Some(at) if !line[..at].contains('"') => &line[..at],
            _ => line,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The identifiers right after each `prefix`: `prefix::name` and each top-level name of
/// `prefix::{a, b::c, …}`.
fn names_after(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let pat = format!("{prefix}::");
    let mut rest = code;
    while let Some(at) = rest.find(&pat) {
        let before = rest[..at].chars().last();
        rest = &rest[at + pat.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1;
            let mut start = true;
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 1 => start = true,
                    c if start && depth == 1 && !c.is_whitespace() => {
                        names.insert(ident(&group[i..]));
                        start = false;
                    }
                    _ => {}
                }
                if depth == 0 {
                    break;
                }
            }
        } else {
            names.insert(ident(rest));
        }
    }
    names.remove("");
    names
}

fn relative(path: &Path) -> String {
    path.strip_prefix(ROOT)
        .unwrap()
        .to_string_lossy()
        .replace('\\', "/")
}

/// Data flows one way: mie → phase → fit / slab → compress → render, over io and stats.
#[test]
fn no_stage_imports_a_later_one() {
    let rank = |m: &str| match m {
        "io" | "stats" => Some(0),
        "mie" => Some(1),
        "phase" => Some(2),
        "fit" | "slab" => Some(3),
        "compress" => Some(4),
        "render" => Some(5),
        _ => None,
    };
    let src = Path::new(ROOT).join("src");
    let mut broken = Vec::new();
    for file in sources(&src) {
        let rel = relative(&file);
        let stage = rel
            .trim_start_matches("src/")
            .split(['/', '.'])
            .next()
            .unwrap();
        let Some(own) = rank(stage) else { continue };
        for used in names_after(&code(&file), "crate") {
            if let Some(r) = rank(&used) {
                if used != stage && r >= own {
                    broken.push(format!("{rel} imports crate::{used}"));
                }
            }
        }
    }
    assert!(broken.is_empty(), "{broken:#?}");
}

/// Within render/, the path tracer and the fast renderers never import each other, and the
/// floor (every file of render/ but mod.rs, which declares the wings) imports neither.
#[test]
fn the_render_floor_knows_no_wing() {
    let render = Path::new(ROOT).join("src/render");
    let mut broken = Vec::new();
    for file in sources(&render) {
        let rel = relative(&file);
        let inside = rel.trim_start_matches("src/render/");
        let forbidden: &[&str] = match inside.split('/').next().unwrap() {
            "path" => &["fast"],
            "fast" => &["path"],
            "mod.rs" => &[],
            _ => &["path", "fast"],
        };
        let text = code(&file);
        let mut used = names_after(&text, "super");
        used.extend(names_after(&text, "super::super"));
        used.extend(names_after(&text, "crate::render"));
        for wing in forbidden {
            if used.contains(*wing) {
                broken.push(format!("{rel} imports render::{wing}"));
            }
        }
    }
    assert!(broken.is_empty(), "{broken:#?}");
}

/// The command line is thin: clap is named only in src/cli/ and src/main.rs.
#[test]
fn clap_stays_in_the_command_line() {
    let src = Path::new(ROOT).join("src");
    let broken: Vec<String> = sources(&src)
        .iter()
        .map(|f| relative(f))
        .filter(|rel| !rel.starts_with("src/cli/") && rel != "src/main.rs")
        .filter(|rel| code(&Path::new(ROOT).join(rel)).contains("clap"))
        .collect();
    assert!(broken.is_empty(), "clap outside src/cli/: {broken:#?}");
}

/// The runtime's transport modules import each other one way: their graph (by `super::m` and
/// `crate::transport::m`) has no cycle.
#[test]
fn the_runtime_transport_modules_have_no_cycle() {
    let dir = Path::new(ROOT).join("runtime/src/transport");
    let files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    let module = |p: &Path| p.file_stem().unwrap().to_string_lossy().to_string();
    let modules: BTreeSet<String> = files.iter().map(|p| module(p)).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in &files {
        let me = module(file);
        if me == "mod" {
            continue;
        }
        let text = code(file);
        let mut used = names_after(&text, "super");
        used.extend(names_after(&text, "crate::transport"));
        let edges = used
            .into_iter()
            .filter(|m| modules.contains(m) && *m != me && m != "mod")
            .collect();
        graph.insert(me, edges);
    }
    // Depth-first search for a back edge, naming the cycle it closes.
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        stack: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = stack.iter().position(|s| s == m) {
            let mut cycle = stack[at..].to_vec();
            cycle.push(m.to_string());
            return Some(cycle);
        }
        if done.contains(m) {
            return None;
        }
        stack.push(m.to_string());
        for next in graph.get(m).into_iter().flatten() {
            if let Some(c) = visit(next, graph, stack, done) {
                return Some(c);
            }
        }
        stack.pop();
        done.insert(m.to_string());
        None
    }
    let (mut stack, mut done) = (Vec::new(), BTreeSet::new());
    for m in graph.keys() {
        let cycle = visit(m, &graph, &mut stack, &mut done);
        assert!(cycle.is_none(), "a cycle: {}", cycle.unwrap().join(" → "));
    }
    // The check reads what it should: the search imports the shared types below it.
    assert!(graph["search"].contains("surface"), "{graph:#?}");
}

/// The readers see what they must: a `crate::{…}` group and a path are both read.
#[test]
fn the_reader_finds_grouped_and_plain_paths() {
    let text = "use crate::{io::npy, phase};\nuse crate::slab::Grid;\nlet x = my_crate::fit;";
    let got = names_after(text, "crate");
    let want: BTreeSet<String> = ["io", "phase", "slab"].map(String::from).into();
    assert_eq!(got, want);
}
