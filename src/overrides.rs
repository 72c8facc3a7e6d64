//! `--set KEY=VALUE` overrides (SCENES.md, "Overrides and sweeps") and the settings of a sweep's
//! points: a dotted key path into the scene's TOML table and a TOML value, applied to the table
//! of the scene text *before* the text is read as a scene. The overridden table goes through the
//! same reading and validation as a file, so an unknown key or a wrong type gets the same
//! key-path error (`contact.penaltyy: unknown field …`, `domain.cells: invalid type …`).
//!
//! Key paths: keys separated by dots, an array entry by `[N]` after its key
//! (`contact.friction.law`, `domain.cells[1]`, `loads.traction[0].value`); a key that holds a dot
//! is quoted (`"a.b".c`). Values are TOML (`1e-5`, `[64, 32]`, `"penalty"`, `true`,
//! `{ theta = 2.0, zeta = 1.5 }`); a value that is not TOML is taken as a string, so
//! `--set contact.enforcement=penalty` works as the README writes it.
//!
//! A table value given whole *replaces* the table at its key: `--set
//! 'contact.friction={law="constant", coefficient=0.3}'` switches the friction law, the old law's
//! keys (`static`, `kinetic`, `decay`) gone — a merge could never remove a key, so a law could
//! never be switched. A dotted key is a leaf override and changes that one key only
//! (`--set solver.relaxation=0.5` keeps the scene's other solver keys). In a sweep's `[set]` and
//! `sets` the same holds as written in the sweep file: an inline table (`"contact.friction" = {
//! law = "constant", coefficient = 0.3 }`) replaces, a dotted key (`solver.relaxation = 0.5`,
//! which TOML reads as a table too) is a leaf — [`dotted_to_paths`] tells them apart by the source.

use crate::error::{Error, Result};

/// One step of a key path.
#[derive(Debug, Clone, PartialEq)]
pub enum Segment {
    Key(String),
    Index(usize),
}

/// A key path and the value to put there.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// the key path as written (messages name it)
    pub key: String,
    pub path: Vec<Segment>,
    pub value: toml::Value,
}

impl Override {
    /// `KEY=VALUE` as given to `--set`.
    pub fn parse(arg: &str) -> Result<Override> {
        let Some((key, value)) = arg.split_once('=') else {
            return Err(Error::scene("--set", format!("`{arg}` is not KEY=VALUE (e.g. --set contact.penalty=1e-5)")));
        };
        if value.contains(['\n', '\r']) {
            // TOML would read the first line as the value and the rest as other keys, dropped here
            return Err(Error::scene(key.trim(), "the --set value holds a line break: give it on one line"));
        }
        Override::new(key.trim(), parse_value(value.trim()))
    }

    /// An override of `key` (a key path) with `value`.
    pub fn new(key: &str, value: toml::Value) -> Result<Override> {
        Ok(Override { key: key.to_string(), path: parse_path(key)?, value })
    }

    /// Put the value at the key path in `table`, creating the tables on the way; an array
    /// index must name an existing entry.
    pub fn apply(&self, table: &mut toml::Table) -> Result<()> {
        let Some((last, parents)) = self.path.split_last() else {
            return Err(Error::scene(&self.key, "is an empty key path"));
        };
        let mut root = toml::Value::Table(std::mem::take(table));
        let result = set_at(&mut root, parents, last, &self.value);
        if let toml::Value::Table(t) = root {
            *table = t;
        }
        result.map_err(|m| Error::scene(&self.key, m))
    }
}

/// Set `value` at `parents` + `last` below `root`.
fn set_at(
    root: &mut toml::Value,
    parents: &[Segment],
    last: &Segment,
    value: &toml::Value,
) -> std::result::Result<(), String> {
    let mut here = root;
    let mut at = String::new();
    for seg in parents {
        here = step(here, seg, &at, true)?;
        at = join(&at, seg);
    }
    match (last, here) {
        (Segment::Key(k), toml::Value::Table(t)) => {
            // any value, a table too, replaces what was there (a table given whole is the table)
            t.insert(k.clone(), value.clone());
            Ok(())
        }
        (Segment::Index(i), toml::Value::Array(a)) => {
            let n = a.len();
            let slot =
                a.get_mut(*i).ok_or_else(|| format!("index {i} is out of range: {} has {n} entries", shown(&at)))?;
            *slot = value.clone();
            Ok(())
        }
        (Segment::Key(_), other) => Err(format!("{} is a {}, not a table", shown(&at), other.type_str())),
        (Segment::Index(_), other) => Err(format!("{} is a {}, not an array", shown(&at), other.type_str())),
    }
}

/// Apply every override in order to the table of a scene text.
pub fn apply_all(table: &mut toml::Table, overrides: &[Override]) -> Result<()> {
    for o in overrides {
        o.apply(table)?;
    }
    Ok(())
}

/// A value as TOML (`x = VALUE`), or the text itself as a string when that is not TOML.
pub fn parse_value(text: &str) -> toml::Value {
    format!("x = {text}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("x"))
        .unwrap_or_else(|| toml::Value::String(text.to_string()))
}

/// `a.b[2].c` → [Key a, Key b, Index 2, Key c]; `"a.b".c` keeps the quoted key whole.
pub fn parse_path(key: &str) -> Result<Vec<Segment>> {
    if key.is_empty() {
        return Err(Error::scene("--set", "the key is empty: give KEY=VALUE, e.g. --set contact.compliance=2000"));
    }
    let bad = |m: &str| Error::scene(key, format!("is not a key path: {m}"));
    let mut out = Vec::new();
    let mut chars = key.chars().peekable();
    loop {
        // a key: quoted, or bare up to '.', '[' or the end
        let mut name = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next() {
                    Some('"') => break,
                    Some(c) => name.push(c),
                    None => return Err(bad("an unclosed quote")),
                }
            }
        } else {
            while let Some(&c) = chars.peek() {
                if c == '.' || c == '[' {
                    break;
                }
                name.push(c);
                chars.next();
            }
            let name_ok = !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !name_ok {
                return Err(bad("keys are letters, digits, _ and - (quote any other)"));
            }
        }
        out.push(Segment::Key(name));
        // indices
        while chars.peek() == Some(&'[') {
            chars.next();
            let mut digits = String::new();
            loop {
                match chars.next() {
                    Some(']') => break,
                    Some(c) => digits.push(c),
                    None => return Err(bad("an unclosed [")),
                }
            }
            let i = digits.trim().parse::<usize>().map_err(|_| bad("an index is a whole number in [ ]"))?;
            out.push(Segment::Index(i));
        }
        match chars.next() {
            None => return Ok(out),
            Some('.') => {}
            Some(_) => return Err(bad("expected `.` or `[` after a key")),
        }
    }
}

/// One step down a key path (creating a missing table when `create`).
fn step<'v>(
    here: &'v mut toml::Value,
    seg: &Segment,
    at: &str,
    create: bool,
) -> std::result::Result<&'v mut toml::Value, String> {
    match (seg, here) {
        (Segment::Key(k), toml::Value::Table(t)) => {
            if create && !t.contains_key(k) {
                t.insert(k.clone(), toml::Value::Table(toml::Table::new()));
            }
            t.get_mut(k).ok_or_else(|| format!("{} has no key `{k}`", shown(at)))
        }
        (Segment::Index(i), toml::Value::Array(a)) => {
            let n = a.len();
            a.get_mut(*i).ok_or_else(|| format!("index {i} is out of range: {} has {n} entries", shown(at)))
        }
        (Segment::Key(_), other) => Err(format!("{} is a {}, not a table", shown(at), other.type_str())),
        (Segment::Index(_), other) => Err(format!("{} is a {}, not an array", shown(at), other.type_str())),
    }
}

fn join(at: &str, seg: &Segment) -> String {
    match seg {
        Segment::Key(k) if at.is_empty() => k.clone(),
        Segment::Key(k) => format!("{at}.{k}"),
        Segment::Index(i) => format!("{at}[{i}]"),
    }
}

fn shown(at: &str) -> String {
    if at.is_empty() { "the scene".into() } else { format!("`{at}`") }
}

/// The overrides of a table of overrides (a sweep's `[set]`, one value of a `sets` axis): one
/// per key, the key a key path (`"contact.penalty" = 1e-5`; a key that is not one is taken as
/// one quoted key), its value given whole — a table value replaces the scene's table. The sweep
/// file's dotted keys were made key paths first ([`dotted_to_paths`]), so
/// `solver.relaxation = 1` sets that one leaf.
pub fn leaves(table: &toml::Table) -> Result<Vec<Override>> {
    table
        .iter()
        .map(|(k, v)| {
            let key = if parse_path(k).is_ok() { k.clone() } else { format!("\"{k}\"") };
            Override::new(&key, v.clone())
        })
        .collect()
}

/// An override table as written in a sweep file (`source`, its parsed form with spans, and the
/// file's `text`) with its dotted keys made key paths: `solver.relaxation = 1` — which TOML
/// reads as the table `solver = { relaxation = 1 }` — becomes the entry
/// `"solver.relaxation" = 1` (a leaf override), while a table written inline
/// (`"contact.friction" = { law = "constant", coefficient = 0.3 }`) stays a table, given whole.
/// TOML's parsed tables do not say how they were written, the source does: an inline table's
/// value starts with `{`, a dotted key's implicit table with its key.
pub fn dotted_to_paths(table: &toml::Table, source: &toml::de::DeTable<'_>, text: &str) -> toml::Table {
    fn bare(k: &str) -> String {
        if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
            k.to_string()
        } else {
            format!("\"{k}\"")
        }
    }
    fn walk(
        table: &toml::Table,
        source: Option<&toml::de::DeTable<'_>>,
        text: &str,
        at: Option<&str>,
        out: &mut toml::Table,
    ) {
        for (k, v) in table {
            let key = match at {
                None => k.clone(),
                Some(a) => format!("{a}.{}", bare(k)),
            };
            let written =
                source.and_then(|s| s.iter().find(|(sk, _)| sk.get_ref().as_ref() == k.as_str()).map(|(_, w)| w));
            let dotted = written.is_some_and(|w| text.get(w.span()).is_some_and(|s| !s.starts_with('{')));
            match (v, written.map(|w| w.get_ref())) {
                (toml::Value::Table(sub), Some(toml::de::DeValue::Table(sub_source))) if dotted => {
                    walk(sub, Some(sub_source), text, Some(&key), out);
                }
                _ => {
                    out.insert(key, v.clone());
                }
            }
        }
    }
    let mut out = toml::Table::new();
    walk(table, Some(source), text, None, &mut out);
    out
}

/// Whether one key path is the other or lies below it (`contact.friction` and
/// `contact.friction.decay`): two overrides that touch the same value.
pub fn overlap(a: &[Segment], b: &[Segment]) -> bool {
    a.iter().zip(b).all(|(x, y)| x == y)
}
