//! The house rules of `docs/architecture.md`, checked on the source tree:
//! no import circle between files, and no file over ~800 lines unless its
//! opening comment says why it reads best whole.
//!
//! The import graph is read from the text: every `crate::a::b`,
//! `super::a`, `self::a` path (and the first segment of each item of a
//! `use crate::{…}` / `use super::{…}` group) outside comments and outside
//! the trailing `#[cfg(test)]` module, resolved to the longest module path
//! that is a file. Edges into a `mod.rs` / `lib.rs` (re-exports, module
//! declarations) are not followed: a folder's front door may name its rooms.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Module path of a file relative to `src/` (`rig/cycles/mod.rs` → `rig::cycles`).
fn module_of(rel: &Path) -> Vec<String> {
    let mut segs: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = segs.pop().unwrap();
    let stem = last.trim_end_matches(".rs").to_string();
    if !matches!(stem.as_str(), "mod" | "lib" | "main") {
        segs.push(stem);
    }
    segs
}

fn is_front_door(rel: &Path) -> bool {
    matches!(
        rel.file_name().and_then(|n| n.to_str()),
        Some("mod.rs" | "lib.rs" | "main.rs")
    )
}

/// The code of a file without comments and without its test module.
fn code_of(text: &str) -> String {
    let body = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    body.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Paths named in the code: (anchor, segments after it).
fn paths_in(code: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    let b = code.as_bytes();
    for anchor in ["crate", "super", "self"] {
        let pat = format!("{anchor}::");
        let mut from = 0;
        while let Some(i) = code[from..].find(&pat) {
            let at = from + i;
            from = at + pat.len();
            if at > 0 && is_ident(b[at - 1] as char) {
                continue;
            }
            let rest = &code[from..];
            if let Some(group) = rest.strip_prefix('{') {
                // `use crate::{a::b, c, d::{e, f}}`: first segments of each item.
                let mut depth = 0usize;
                let mut item = String::new();
                let mut items = Vec::new();
                for c in group.chars() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => items.push(std::mem::take(&mut item)),
                        _ if depth == 0 => item.push(c),
                        _ => {}
                    }
                }
                items.push(item);
                for it in items {
                    let segs: Vec<String> = it
                        .split("::")
                        .map(|s| s.trim().to_string())
                        .take_while(|s| !s.is_empty() && s.chars().all(is_ident))
                        .collect();
                    if !segs.is_empty() {
                        out.push((anchor.to_string(), segs));
                    }
                }
                continue;
            }
            let mut segs = Vec::new();
            let mut cur = String::new();
            let mut chars = rest.chars().peekable();
            loop {
                match chars.next() {
                    Some(c) if is_ident(c) => cur.push(c),
                    Some(':') if chars.peek() == Some(&':') => {
                        chars.next();
                        segs.push(std::mem::take(&mut cur));
                        if chars.peek().is_some_and(|c| !is_ident(*c)) {
                            break;
                        }
                    }
                    _ => break,
                }
            }
            if !cur.is_empty() {
                segs.push(cur);
            }
            if !segs.is_empty() {
                out.push((anchor.to_string(), segs));
            }
        }
    }
    out
}

struct Tree {
    /// Module path → file (relative to src/).
    modules: BTreeMap<Vec<String>, PathBuf>,
    /// File → files it imports.
    edges: BTreeMap<PathBuf, BTreeSet<PathBuf>>,
    lines: BTreeMap<PathBuf, (usize, String)>,
}

fn read_tree() -> Tree {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    let mut modules = BTreeMap::new();
    let mut texts = BTreeMap::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap().to_path_buf();
        modules.insert(module_of(&rel), rel.clone());
        texts.insert(rel, std::fs::read_to_string(f).unwrap());
    }
    let mut edges: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
    let mut lines = BTreeMap::new();
    for (rel, text) in &texts {
        let here = module_of(rel);
        let dir_module = is_front_door(rel);
        let code = code_of(text);
        let mut out = BTreeSet::new();
        for (anchor, segs) in paths_in(&code) {
            let mut base: Vec<String> = match anchor.as_str() {
                "crate" => Vec::new(),
                "self" => here.clone(),
                // `super` of a file `a/b.rs` (module a::b) is `a`; of `a/mod.rs`
                // (module a) it is the parent of `a`.
                _ => {
                    let mut b = here.clone();
                    b.pop();
                    b
                }
            };
            let _ = dir_module;
            base.extend(segs);
            for n in (1..=base.len()).rev() {
                if let Some(target) = modules.get(&base[..n]) {
                    if target != rel && !is_front_door(target) {
                        out.insert(target.clone());
                    }
                    break;
                }
            }
        }
        edges.insert(rel.clone(), out);
        let head: String = text
            .lines()
            .take_while(|l| l.starts_with("//!") || l.trim().is_empty())
            .collect::<Vec<_>>()
            .join("\n");
        lines.insert(rel.clone(), (text.lines().count(), head));
    }
    Tree {
        modules,
        edges,
        lines,
    }
}

/// Strongly connected components with more than one file (Tarjan).
fn circles(edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    struct St<'a> {
        edges: &'a BTreeMap<PathBuf, BTreeSet<PathBuf>>,
        index: BTreeMap<&'a PathBuf, usize>,
        low: BTreeMap<&'a PathBuf, usize>,
        stack: Vec<&'a PathBuf>,
        on: BTreeSet<&'a PathBuf>,
        next: usize,
        out: Vec<Vec<PathBuf>>,
    }
    fn visit<'a>(s: &mut St<'a>, v: &'a PathBuf) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        let edges = s.edges;
        for w in &edges[v] {
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = St {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

#[test]
fn the_checker_sees_a_circle_and_a_one_way_import() {
    let mut e: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
    let (a, b, c) = (
        PathBuf::from("a.rs"),
        PathBuf::from("b.rs"),
        PathBuf::from("c.rs"),
    );
    e.insert(a.clone(), [b.clone()].into());
    e.insert(b.clone(), [a.clone(), c.clone()].into());
    e.insert(c.clone(), BTreeSet::new());
    assert_eq!(circles(&e), vec![vec![a, b]]);
    let p = paths_in("use super::{x::Y, z};\nlet q = crate::rig::cycles::analyse(&l);");
    assert!(p.contains(&("super".into(), vec!["x".into(), "Y".into()])));
    assert!(p.contains(&("super".into(), vec!["z".into()])));
    assert!(p.contains(&(
        "crate".into(),
        vec!["rig".into(), "cycles".into(), "analyse".into()]
    )));
}

#[test]
fn no_import_circle_between_files() {
    let tree = read_tree();
    assert!(
        tree.modules.len() > 50,
        "the source tree was not found ({} files)",
        tree.modules.len()
    );
    assert!(
        tree.edges[Path::new("engine/vision.rs")].contains(Path::new("engine/entries.rs")),
        "the import reader missed a known import"
    );
    let found = circles(&tree.edges);
    assert!(
        found.is_empty(),
        "files that import each other (give the shared types a home below both): {found:#?}"
    );
}

/// Files over ~800 lines when the rule was written, each with its size then:
/// the splits along their jobs are open work (docs/architecture.md lists
/// them). The list may only shrink: a listed file may not grow past its
/// size, and no other file may pass 800 lines without saying in its opening
/// comment why it reads best whole.
const NOT_YET_SPLIT: &[(&str, usize)] = &[];

#[test]
fn no_file_over_800_lines_without_its_reason() {
    let tree = read_tree();
    let mut bad = Vec::new();
    for (p, (n, head)) in &tree.lines {
        let name = p.display().to_string();
        let allowed = NOT_YET_SPLIT
            .iter()
            .find(|(f, _)| *f == name)
            .map(|(_, max)| *max);
        let over = match allowed {
            Some(max) => *n > max,
            None => *n > 800 && !head.contains("reads best whole"),
        };
        if over {
            bad.push(format!(
                "{name} ({n} lines, allowed {})",
                allowed.unwrap_or(800)
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "split these along their jobs, or say in the opening comment why each \
         reads best whole: {bad:#?}"
    );
    // The list only shrinks: a listed file that is now short is struck off.
    let done: Vec<&str> = NOT_YET_SPLIT
        .iter()
        .filter(|(f, _)| tree.lines.get(Path::new(f)).is_none_or(|(n, _)| *n <= 800))
        .map(|(f, _)| *f)
        .collect();
    assert!(
        done.is_empty(),
        "these files are split now: strike them off NOT_YET_SPLIT: {done:?}"
    );
}

/// Each folder under `tests/` other than `common/` and `python/` is one test
/// binary (`main.rs`); a file beside it that `main.rs` does not declare
/// would never be compiled, so its tests would silently not run.
#[test]
fn every_test_file_in_a_test_binary_folder_is_declared() {
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let mut undeclared = Vec::new();
    let mut folders = 0;
    for e in std::fs::read_dir(&tests).unwrap().flatten() {
        let dir = e.path();
        let main = dir.join("main.rs");
        if !dir.is_dir() || !main.is_file() {
            continue;
        }
        folders += 1;
        let declared = code_of(&std::fs::read_to_string(&main).unwrap());
        for f in std::fs::read_dir(&dir).unwrap().flatten() {
            let p = f.path();
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            if p.extension().is_some_and(|x| x == "rs")
                && stem != "main"
                && !declared.contains(&format!("mod {stem};"))
            {
                undeclared.push(p);
            }
        }
    }
    assert!(folders >= 5, "found only {folders} test-binary folders");
    assert!(
        undeclared.is_empty(),
        "not declared in main.rs: {undeclared:?}"
    );
}
