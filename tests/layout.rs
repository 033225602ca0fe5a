//! Imports in `src/` run one way: the modules' use graph has no circle.
//!
//! Each file is a node (`src/a/mod.rs` is module `a`, `src/a/b.rs` is
//! `a::b`; `src/bin` is left out: binaries import the library, never the
//! reverse). A file has an edge to every module a path in it names: `use`
//! trees (braces expanded) and inline paths that start with `crate::`,
//! `super::`, `self::` or the name of a child module it declares. A path
//! counts for the longest module prefix it names, so `crate::a::b::Item`
//! is an edge to `a::b` when that file exists and to `a` otherwise, unless
//! `a` re-exports `Item`: then the edge goes on to where the re-export leads
//! (a glob: every module it names), so importing through a facade is
//! importing from the module that defines the item. Declaring a child (`mod
//! b;`) is not an edge, nor is re-exporting its items (`pub use b::Item`: a
//! facade names them, it does not depend on them); but a parent whose code
//! uses a child while the child reaches back into the parent's own items
//! makes a circle, so items both need live in a leaf they import. A renamed
//! re-export (`pub use b::X as Y`) is known by its old name.
//! A name brought in by a `use` (`use crate::catalog;`) starts paths that
//! count as the full path (`catalog::Registry` is `crate::catalog::Registry`).
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
                path.push("*".into());
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

/// The paths a file names: what its code uses, and what it re-exports.
#[derive(Debug, Default)]
struct Named {
    /// `use` trees and inline `a::b::c` chains (a glob ends in `*`).
    uses: Vec<Vec<String>>,
    /// The trees of `pub use` and `pub(…) use`: the module's public face,
    /// which leads an importer on to where an item is defined.
    reexports: Vec<Vec<String>>,
}

/// Every path the tokens name.
fn paths(t: &[Token]) -> Named {
    let mut out = Named::default();
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
                if reexport {
                    out.reexports.extend(tree);
                } else {
                    out.uses.extend(tree);
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
                out.uses.push(path);
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

/// What the files declare, module by module.
struct Crate {
    modules: BTreeSet<Module>,
    /// Per module: the children it declares (`mod name;`).
    kids: BTreeMap<Module, BTreeSet<String>>,
    /// Per module: its re-exports' paths (the last segment is the name, or
    /// `*` for a glob).
    reexports: BTreeMap<Module, Vec<Vec<String>>>,
}

/// The modules `path` names from `here`: its longest module prefix, and
/// where a re-export there leads (a glob: every module it re-exports).
/// Paths that start elsewhere (an outside crate, a local name) name none.
fn resolve(c: &Crate, here: &Module, path: &[String], depth: usize) -> Vec<Module> {
    let Some(first) = path.first() else {
        return Vec::new();
    };
    let (mut base, mut rest): (Module, &[String]) = match first.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "self" => (here.clone(), &path[1..]),
        "super" => (here.clone(), path),
        child if c.kids.get(here).is_some_and(|k| k.contains(child)) => (here.clone(), path),
        _ => return Vec::new(),
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    while let Some((seg, tail)) = rest.split_first() {
        let mut next = base.clone();
        next.push(seg.clone());
        if c.modules.contains(&next) {
            (base, rest) = (next, tail);
            continue;
        }
        // An item of `base`: if `base` re-exports it, the importer depends
        // on where it is defined.
        let reexports = c.reexports.get(&base).map_or(&[][..], Vec::as_slice);
        let named: Vec<&Vec<String>> = reexports.iter().filter(|p| p.last() == Some(seg)).collect();
        let via: Vec<&[String]> = if named.is_empty() {
            reexports
                .iter()
                .filter(|p| p.last().is_some_and(|l| l == "*"))
                .map(|p| &p[..p.len() - 1])
                .collect()
        } else {
            named.iter().map(|p| p.as_slice()).collect()
        };
        if depth < 8 && !via.is_empty() {
            return via
                .iter()
                .flat_map(|p| resolve(c, &base, p, depth + 1))
                .collect();
        }
        break;
    }
    vec![base]
}

fn graph(src: &Path) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let parsed: Vec<(Module, Vec<Token>)> = files
        .iter()
        .filter_map(|f| Some((module_of(src, f)?, tokens(&fs::read_to_string(f).unwrap()))))
        .collect();
    let split = |t: &[Token]| inline_module_start(t).unwrap_or(t.len());
    let c = Crate {
        modules: parsed.iter().map(|(m, _)| m.clone()).collect(),
        kids: parsed
            .iter()
            .map(|(m, t)| (m.clone(), children(t)))
            .collect(),
        reexports: parsed
            .iter()
            .map(|(m, t)| (m.clone(), paths(&t[..split(t)]).reexports))
            .collect(),
    };
    let mut edges = BTreeMap::new();
    for (here, t) in &parsed {
        let at = split(t);
        let mut to = BTreeSet::new();
        let file_level = paths(&t[..at]).uses;
        // Inside an inline module `super` is this file: read it as `self`.
        let inner = paths(&t[at..]).uses.into_iter().map(|mut p| {
            if p.first().is_some_and(|s| s == "super") {
                p[0] = "self".into();
            }
            p
        });
        // A name a `use` brought in (`use crate::catalog;`) starts paths
        // of its own (`catalog::Registry`): read them as the full path.
        let aliases: BTreeMap<String, Vec<String>> = file_level
            .iter()
            .filter(|p| p.len() > 1 && p.last().is_some_and(|l| l != "*"))
            .filter_map(|p| Some((p.last()?.clone(), p.clone())))
            .collect();
        for p in file_level.iter().cloned().chain(inner) {
            let p = match p.first().and_then(|f| aliases.get(f)) {
                Some(full) if p.len() > 1 && !c.kids[here].contains(&p[0]) => {
                    [full.as_slice(), &p[1..]].concat()
                }
                _ => p,
            };
            to.extend(resolve(&c, here, &p, 0).into_iter().filter(|m| m != here));
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
    let p = paths(&t).uses;
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert!(p.contains(&s(&["crate", "a", "B"])));
    assert!(p.contains(&s(&["crate", "a", "c", "D"])));
    assert!(p.contains(&s(&["crate", "f"])));
    assert!(p.contains(&s(&["super", "g", "*"])));
    assert!(p.contains(&s(&["x", "y", "z"])));
    assert!(!p.iter().any(|q| q.contains(&"no".to_string())));
    let t = tokens("pub use a::B; pub(crate) use c::*; use e::F;");
    let named = paths(&t);
    assert_eq!(named.uses, vec![s(&["e", "F"])]);
    assert_eq!(named.reexports, vec![s(&["a", "B"]), s(&["c", "*"])]);
    let t = tokens("mod inner { use super::Thing; }");
    assert_eq!(inline_module_start(&t), Some(0));
}

/// An import through a facade's re-export depends on the module that
/// defines the item, so a circle through a facade is still found.
#[test]
fn re_exports_lead_to_where_an_item_is_defined() {
    let m = |s: &str| -> Module {
        if s.is_empty() {
            Vec::new()
        } else {
            s.split("::").map(String::from).collect()
        }
    };
    let p = |s: &str| -> Vec<String> { s.split("::").map(String::from).collect() };
    let c = Crate {
        modules: ["", "a", "a::b", "a::g", "c"].into_iter().map(m).collect(),
        kids: [
            (m(""), BTreeSet::from(["a".to_string(), "c".to_string()])),
            (m("a"), BTreeSet::from(["b".to_string(), "g".to_string()])),
        ]
        .into_iter()
        .collect(),
        reexports: [(m("a"), vec![p("b::Item"), p("g::*")])]
            .into_iter()
            .collect(),
    };
    assert_eq!(
        resolve(&c, &m("c"), &p("crate::a::Item"), 0),
        vec![m("a::b")]
    );
    assert_eq!(
        resolve(&c, &m("c"), &p("crate::a::Other"), 0),
        vec![m("a::g")]
    );
    assert_eq!(
        resolve(&c, &m("c"), &p("crate::a::b::Item"), 0),
        vec![m("a::b")]
    );
    assert_eq!(
        resolve(&c, &m("c"), &p("std::fmt"), 0),
        Vec::<Module>::new()
    );
}
