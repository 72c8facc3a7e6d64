//! Module cycles, computed from the code: data flows one way (scene → model → problem → operators
//! → time loop → outputs), so no module may use a sibling that uses it back.
//!
//! Every `crate::…`, `super::…` and `self::…` path of a crate's files (comments and string literals
//! removed; `use` groups `{a, b::c}` expanded) is resolved to the deepest module it names. A
//! reference from a file of module F to module T gives, at their nearest common ancestor L, an edge
//! between the two children of L that contain F and T ("siblings"); a module using its parent's
//! or its own children's items gives none (that is how a module is built from its files). A cycle
//! is a strongly connected set of two or more siblings; each is reported with one reference per
//! edge (file and line), so the fix is findable.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::source::{code_only, ident};

/// A module path from the crate root (`[]` is the root, `["step", "delassus"]` is step::delassus).
type ModPath = Vec<String>;

/// The modules of one crate: each file's module path (a `mod.rs` names its folder).
struct Crate {
    name: String,
    files: BTreeMap<ModPath, PathBuf>,
}

fn crate_modules(name: &str, src: &Path, root_file: &str) -> Crate {
    let mut files = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().is_none_or(|x| x != "rs") {
                continue;
            }
            let Ok(rel) = p.strip_prefix(src) else { continue };
            let mut segs: Vec<String> = rel.iter().map(|s| s.to_string_lossy().to_string()).collect();
            let last = segs.pop().unwrap_or_default();
            if last == root_file && segs.is_empty() {
                files.insert(Vec::new(), p);
                continue;
            }
            if (last == "main.rs" || last == "lib.rs") && segs.is_empty() {
                continue; // another crate root in the same folder (a binary beside the library)
            }
            let stem = last.trim_end_matches(".rs").to_string();
            if stem != "mod" {
                segs.push(stem);
            }
            files.insert(segs, p);
        }
    }
    Crate { name: name.to_string(), files }
}

/// Every path starting with `crate::`, `super::` or `self::` in the code, with its line: a path is
/// its segments up to the first that is not an identifier; `{…}` groups expand into one path per
/// leaf.
fn paths(code: &str) -> Vec<(usize, Vec<String>)> {
    let b: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < b.len() {
        if b[i] == '\n' {
            line += 1;
        }
        let at_start = i == 0 || !(ident(b[i - 1]) || b[i - 1] == ':');
        if at_start {
            for head in ["crate", "super", "self"] {
                let h: Vec<char> = head.chars().collect();
                if b[i..].starts_with(&h) && b.get(i + h.len()) == Some(&':') && b.get(i + h.len() + 1) == Some(&':') {
                    let mut j = i;
                    let mut leaves = Vec::new();
                    parse_path(&b, &mut j, Vec::new(), &mut leaves);
                    out.extend(leaves.into_iter().map(|p| (line, p)));
                }
            }
        }
        i += 1;
    }
    out
}

/// Parse `seg::seg::…` (or a `{…}` group) at `*j`, appending every complete path to `leaves`.
fn parse_path(b: &[char], j: &mut usize, mut prefix: Vec<String>, leaves: &mut Vec<Vec<String>>) {
    loop {
        while *j < b.len() && b[*j].is_whitespace() {
            *j += 1;
        }
        if b.get(*j) == Some(&'{') {
            *j += 1;
            loop {
                parse_path(b, j, prefix.clone(), leaves);
                while *j < b.len() && b[*j].is_whitespace() {
                    *j += 1;
                }
                match b.get(*j) {
                    Some(',') => *j += 1,
                    Some('}') => {
                        *j += 1;
                        return;
                    }
                    _ => return,
                }
                while *j < b.len() && b[*j].is_whitespace() {
                    *j += 1;
                }
                if b.get(*j) == Some(&'}') {
                    *j += 1;
                    return;
                }
            }
        }
        let start = *j;
        while *j < b.len() && ident(b[*j]) {
            *j += 1;
        }
        if *j == start {
            if !prefix.is_empty() {
                leaves.push(prefix);
            }
            return;
        }
        prefix.push(b[start..*j].iter().collect());
        if b.get(*j) == Some(&':') && b.get(*j + 1) == Some(&':') {
            *j += 2;
        } else {
            leaves.push(prefix);
            return;
        }
    }
}

/// The module a path names from file module `from`: `crate`/`super`/`self` resolved, then the
/// longest prefix that is a module of the crate.
fn resolve(from: &ModPath, path: &[String], modules: &BTreeSet<ModPath>) -> Option<ModPath> {
    let mut abs: ModPath = Vec::new();
    let mut rest = path;
    match path.first().map(String::as_str) {
        Some("crate") => rest = &path[1..],
        Some("self") => {
            abs = from.clone();
            rest = &path[1..];
        }
        Some("super") => {
            abs = from.clone();
            while rest.first().is_some_and(|s| s == "super") {
                abs.pop()?;
                rest = &rest[1..];
            }
        }
        _ => return None,
    }
    let mut best = abs.clone();
    for s in rest {
        abs.push(s.clone());
        if modules.contains(&abs) {
            best = abs.clone();
        } else {
            break;
        }
    }
    Some(best)
}

/// An edge between two siblings under `parent`, with the reference that made it.
type Edges = BTreeMap<ModPath, BTreeMap<(String, String), String>>;

fn sibling_edges(c: &Crate, root: &Path) -> Edges {
    let modules: BTreeSet<ModPath> = c.files.keys().cloned().collect();
    let mut edges = Edges::new();
    for (from, file) in &c.files {
        let Ok(text) = std::fs::read_to_string(file) else { continue };
        for (line, p) in paths(&code_only(&text)) {
            let Some(to) = resolve(from, &p, &modules) else { continue };
            let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common == from.len() || common == to.len() {
                continue; // a parent and its descendant
            }
            let parent = from[..common].to_vec();
            let rel = file.strip_prefix(root).unwrap_or(file).display().to_string();
            edges
                .entry(parent)
                .or_default()
                .entry((from[common].clone(), to[common].clone()))
                .or_insert_with(|| format!("{rel}:{line} uses {}", p.join("::")));
        }
    }
    edges
}

/// Strongly connected components of two or more nodes (Tarjan).
fn cycles(nodes: &BTreeSet<String>, adj: &BTreeMap<String, Vec<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        adj: &'a BTreeMap<String, Vec<String>>,
        index: BTreeMap<String, usize>,
        low: BTreeMap<String, usize>,
        stack: Vec<String>,
        on: BTreeSet<String>,
        next: usize,
        out: Vec<Vec<String>>,
    }
    fn visit(s: &mut State, v: &str) {
        s.index.insert(v.to_string(), s.next);
        s.low.insert(v.to_string(), s.next);
        s.next += 1;
        s.stack.push(v.to_string());
        s.on.insert(v.to_string());
        for w in s.adj.get(v).cloned().unwrap_or_default() {
            if !s.index.contains_key(&w) {
                visit(s, &w);
                let lw = s.low[&w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.on.contains(&w) {
                let iw = s.index[&w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(&w);
                let done = w == v;
                comp.push(w);
                if done {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        adj,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in nodes {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The module cycles of the workspace's crates: one message per cycle, naming its modules and
/// one reference for each edge inside it. Empty when there is none.
pub fn check(root: &Path) -> Vec<String> {
    let crates = [
        crate_modules("dyncontact", &root.join("src"), "lib.rs"),
        crate_modules("dyncontact-studies", &root.join("studies/src"), "lib.rs"),
        crate_modules("xtask", &root.join("xtask/src"), "main.rs"),
    ];
    let mut failures = Vec::new();
    for c in &crates {
        for (parent, es) in sibling_edges(c, root) {
            let nodes: BTreeSet<String> = es.keys().flat_map(|(a, b)| [a.clone(), b.clone()]).collect();
            let mut adj: BTreeMap<String, Vec<String>> = BTreeMap::new();
            for (a, b) in es.keys() {
                adj.entry(a.clone()).or_default().push(b.clone());
            }
            for comp in cycles(&nodes, &adj) {
                let inside: Vec<&String> =
                    es.iter().filter(|((a, b), _)| comp.contains(a) && comp.contains(b)).map(|(_, r)| r).collect();
                let scope =
                    if parent.is_empty() { c.name.clone() } else { format!("{}::{}", c.name, parent.join("::")) };
                failures.push(format!(
                    "module cycle in {scope}: {} use each other ({})",
                    comp.join(", "),
                    inside.iter().map(|r| r.as_str()).collect::<Vec<_>>().join("; ")
                ));
            }
        }
    }
    failures
}
