//! Imports in `src/` run one way: the modules' use graph has no circle.
//!
//! Each file is a node (`src/a/mod.rs` is module `a`, `src/a/b.rs` is
//! `a::b`; `src/bin` is left out: binaries import the library, never the
//! reverse). A file has an edge to every module a path in it names: `use`
//! trees (braces expanded) and inline paths that start with `crate::`,
//! `super::`, `self::` or the name of a child module it declares. A path
//! counts for the longest module prefix it names, so `crate::a::b::Item`
//! is an edge to `a::b` when that file exists and to `a` otherwise. Declaring
//! a child (`mod b;`) is not an edge, nor is re-exporting its items (`pub use
//! b::Item`: a facade names them, it does not depend on them); but a parent
//! whose code uses a child while the child reaches back into the parent's
//! own items makes a circle, so items both need live in a leaf they import.
//! Inside an inline module (`mod tests { … }`) `super::` is the file
//! itself. Comments are skipped.
#![allow(clippy::unwrap_used, missing_docs)]

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

type Module = Vec<String>;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module a file under `src/` defines; `None` for binaries.
fn module_of(src: &Path, file: &Path) -> Option<Module> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut segs: Module = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    if segs.first().is_some_and(|s| s == "bin") {
        return None;
    }
    if segs
        .last()
        .is_some_and(|s| s == "mod" || s == "lib" || s == "main")
    {
        segs.pop();
    }
    Some(segs)
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Ident(String),
    Path, // `::`
    Punct(char),
}

/// Identifiers, `::` and single punctuation, with comments, strings and
/// character literals left out.
fn tokens(text: &str) -> Vec<Token> {
    let b: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == '/' && b.get(i + 1) == Some(&'/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && b.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                i += if b[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c == 'r' && (b.get(i + 1) == Some(&'#') || b.get(i + 1) == Some(&'"')) {
            // A raw string: r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(Token::Ident("r".into()));
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == '"' && (0..hashes).all(|h| b.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
        } else if c == '\'' {
            // A character literal ('x', '\n') or a lifetime ('a).
            if b.get(i + 2) == Some(&'\'') {
                i += 3;
            } else if b.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < b.len() && b[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else {
                i += 1;
                while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(Token::Ident(b[start..i].iter().collect()));
        } else if c == ':' && b.get(i + 1) == Some(&':') {
            out.push(Token::Path);
            i += 2;
        } else if c.is_whitespace() {
            i += 1;
        } else {
            out.push(Token::Punct(c));
            i += 1;
        }
    }
    out
}

/// The paths of one `use` tree starting at `t[*i]`, braces expanded.
fn use_tree(t: &[Token], i: &mut usize, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    loop {
        match t.get(*i) {
            Some(Token::Ident(s)) if s != "as" => {
                path.push(s.clone());
                *i += 1;
            }
            Some(Token::Punct('{')) => {
                *i += 1;
                while !matches!(t.get(*i), Some(Token::Punct('}')) | None) {
                    use_tree(t, i, &path, out);
                    if matches!(t.get(*i), Some(Token::Punct(','))) {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            Some(Token::Punct('*')) => {
                *i += 1;
            }
            _ => {}
        }
        if matches!(t.get(*i), Some(Token::Path)) {
            *i += 1;
            continue;
        }
        if matches!(t.get(*i), Some(Token::Ident(s)) if s == "as") {
            *i += 2;
        }
        out.push(path);
        return;
    }
}

/// Every path the tokens name: `use` trees and inline `a::b::c` chains.
/// A re-export (`pub use`, `pub(crate) use`) is left out: it is the
/// module's public face, not something its code depends on.
fn paths(t: &[Token]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Token::Ident(s) if s == "use" => {
                let reexport = i >= 1 && t[i - 1] == Token::Ident("pub".into())
                    || i >= 4
                        && t[i - 1] == Token::Punct(')')
                        && t[i - 4] == Token::Ident("pub".into());
                i += 1;
                let mut tree = Vec::new();
                use_tree(t, &mut i, &[], &mut tree);
                if !reexport {
                    out.extend(tree);
                }
            }
            Token::Ident(s) if matches!(t.get(i + 1), Some(Token::Path)) => {
                // Only the start of a chain: `x::y` after `::` was taken with it.
                let mut path = vec![s.clone()];
                i += 1;
                while let (Some(Token::Path), Some(Token::Ident(n))) = (t.get(i), t.get(i + 1)) {
                    path.push(n.clone());
                    i += 2;
                }
                out.push(path);
            }
            _ => i += 1,
        }
    }
    out
}

/// Where the first inline module (`mod name {`) starts, if any.
fn inline_module_start(t: &[Token]) -> Option<usize> {
    (0..t.len().saturating_sub(2)).find(|&k| {
        t[k] == Token::Ident("mod".into())
            && matches!(t[k + 1], Token::Ident(_))
            && t[k + 2] == Token::Punct('{')
    })
}

/// The child modules a file declares (`mod name;`).
fn children(t: &[Token]) -> BTreeSet<String> {
    (0..t.len().saturating_sub(2))
        .filter(|&k| t[k] == Token::Ident("mod".into()) && t[k + 2] == Token::Punct(';'))
        .filter_map(|k| match &t[k + 1] {
            Token::Ident(n) => Some(n.clone()),
            _ => None,
        })
        .collect()
}

/// The module `path` names from `here`, by its longest module prefix.
fn resolve(
    modules: &BTreeSet<Module>,
    here: &Module,
    kids: &BTreeSet<String>,
    path: &[String],
) -> Option<Module> {
    let (mut base, mut rest): (Module, &[String]) = match path.first()?.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "self" => (here.clone(), &path[1..]),
        "super" => (here.clone(), path),
        child if kids.contains(child) => (here.clone(), path),
        _ => return None,
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    for seg in rest {
        base.push(seg.clone());
        if !modules.contains(&base) {
            base.pop();
            break;
        }
    }
    Some(base)
}

fn graph(src: &Path) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let parsed: Vec<(Module, Vec<Token>)> = files
        .iter()
        .filter_map(|f| Some((module_of(src, f)?, tokens(&fs::read_to_string(f).unwrap()))))
        .collect();
    let modules: BTreeSet<Module> = parsed.iter().map(|(m, _)| m.clone()).collect();
    let mut edges = BTreeMap::new();
    for (here, t) in &parsed {
        let kids = children(t);
        let split = inline_module_start(t).unwrap_or(t.len());
        let mut to = BTreeSet::new();
        let file_level = paths(&t[..split]);
        // Inside an inline module `super` is this file: read it as `self`.
        let inner = paths(&t[split..]).into_iter().map(|mut p| {
            if p.first().is_some_and(|s| s == "super") {
                p[0] = "self".into();
            }
            p
        });
        for p in file_level.into_iter().chain(inner) {
            if let Some(m) = resolve(&modules, here, &kids, &p)
                && m != *here
            {
                to.insert(m);
            }
        }
        edges.insert(here.clone(), to);
    }
    edges
}

/// A circle through the graph, if there is one, as the modules along it.
fn find_circle(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Option<Vec<Module>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        m: &Module,
        edges: &BTreeMap<Module, BTreeSet<Module>>,
        marks: &mut BTreeMap<Module, Mark>,
        stack: &mut Vec<Module>,
    ) -> Option<Vec<Module>> {
        match marks.get(m) {
            Some(Mark::Done) => return None,
            Some(Mark::Open) => {
                let at = stack.iter().position(|s| s == m).unwrap();
                let mut circle = stack[at..].to_vec();
                circle.push(m.clone());
                return Some(circle);
            }
            None => {}
        }
        marks.insert(m.clone(), Mark::Open);
        stack.push(m.clone());
        for next in edges.get(m).into_iter().flatten() {
            if let Some(c) = visit(next, edges, marks, stack) {
                return Some(c);
            }
        }
        stack.pop();
        marks.insert(m.clone(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    edges
        .keys()
        .find_map(|m| visit(m, edges, &mut marks, &mut Vec::new()))
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

#[test]
fn src_has_no_circle_of_imports() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = graph(&src);
    assert!(edges.len() > 30, "read {} modules", edges.len());
    if let Some(circle) = find_circle(&edges) {
        let shown: Vec<String> = circle.iter().map(name).collect();
        panic!("a circle of imports: {}", shown.join(" -> "));
    }
}

/// The reader sees the edges the check relies on, so a change that blinds
/// it (every file read as having no imports) fails here.
#[test]
fn the_graph_sees_known_imports() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = graph(&src);
    let m = |s: &str| s.split("::").map(String::from).collect::<Module>();
    assert!(edges[&m("stats")].contains(&m("scenario")));
    assert!(edges[&m("stats")].contains(&m("geometry")));
    assert!(edges[&m("planner::input")].contains(&m("limits")));
    assert!(edges[&m("estimator::exact")].contains(&m("estimator::exact::windows")));
}

#[test]
fn a_circle_is_found_and_a_tree_is_not() {
    let m = |s: &str| vec![s.to_string()];
    let mut edges = BTreeMap::new();
    edges.insert(m("a"), BTreeSet::from([m("b")]));
    edges.insert(m("b"), BTreeSet::from([m("c")]));
    edges.insert(m("c"), BTreeSet::new());
    assert_eq!(find_circle(&edges), None);
    edges.get_mut(&m("c")).unwrap().insert(m("a"));
    assert_eq!(
        find_circle(&edges),
        Some(vec![m("a"), m("b"), m("c"), m("a")])
    );
}

#[test]
fn use_trees_expand_and_inline_modules_read_super_as_self() {
    let t = tokens("use crate::{a::{B, c::D as E}, f}; use super::g::*; x::y::z(); // crate::no\n");
    let p = paths(&t);
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert!(p.contains(&s(&["crate", "a", "B"])));
    assert!(p.contains(&s(&["crate", "a", "c", "D"])));
    assert!(p.contains(&s(&["crate", "f"])));
    assert!(p.contains(&s(&["super", "g"])));
    assert!(p.contains(&s(&["x", "y", "z"])));
    assert!(!p.iter().any(|q| q.contains(&"no".to_string())));
    let t = tokens("pub use a::B; pub(crate) use c::D; use e::F;");
    assert_eq!(paths(&t), vec![s(&["e", "F"])]);
    let t = tokens("mod inner { use super::Thing; }");
    assert_eq!(inline_module_start(&t), Some(0));
}
