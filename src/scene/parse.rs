//! Reading a scene: TOML text (with `--set` overrides applied to its table) → [`Scene`], every
//! unknown key, missing key or wrong type named by its key path.
//!
//! A TOML error is one line (`file: TOML parse error at line 4, column 17: unclosed array …`,
//! or with the key path first) and keeps TOML's diagram — the source line with a caret under
//! the place — apart, for the command line to print as lines. With `--set`, a message never
//! points into the overridden text (which nobody wrote): an error at a key that an override set
//! says that the value came from `--set`; any other error is reported from the user's file, at
//! its line.

use super::{DEFAULT_SCENE, Scene};
use crate::error::{Error, Result};
use crate::overrides::{Override, Segment};

/// A TOML error of `file` as an [`Error::SceneSyntax`]: `path` (the key path serde reached,
/// empty for a syntax error) first, then TOML's headline (`TOML parse error at line L, column
/// C`) and what is wrong; the quoted source lines go to `diagram`.
pub fn syntax_error(file: &str, path: &str, e: &toml::de::Error) -> Error {
    let shown = e.to_string();
    let mut lines = shown.lines().map(str::trim_end).filter(|l| !l.trim().is_empty());
    let head = lines.next().unwrap_or("").to_string();
    let diagram: Vec<&str> = lines.filter(|l| l.contains('|')).collect();
    let what = one_paragraph(e.message());
    let inner = if head.starts_with("TOML parse error") && !what.is_empty() {
        format!("{head}: {what}")
    } else if what.is_empty() {
        one_paragraph(&shown)
    } else {
        what
    };
    let message = if path.is_empty() || path == "." { inner } else { format!("{path}: {inner}") };
    let path = if path == "." { String::new() } else { path.to_string() };
    Error::SceneSyntax { file: file.to_string(), message, diagram: diagram.join("\n"), path }
}

/// The scene text with `overrides` applied to its table (TOML again).
pub fn overridden_text(text: &str, file: &str, overrides: &[Override]) -> Result<String> {
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| syntax_error(file, "", &e))?;
    crate::overrides::apply_all(&mut table, overrides)?;
    toml::to_string(&table).map_err(|e| Error::SceneSyntax {
        file: file.to_string(),
        message: one_paragraph(&e.to_string()),
        diagram: String::new(),
        path: String::new(),
    })
}

/// The effective scene a run writes to its folder as scene.toml (and `--resume DIR` reads
/// back): the text with its overrides applied and a relative mesh file made absolute (against
/// `dir`, the scene's folder), so the text reads the same from the run folder. Without
/// overrides or a relative mesh path the text is the file's own, comments and all.
pub fn effective_text(text: &str, file: &str, overrides: &[Override], dir: &std::path::Path) -> Result<String> {
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| syntax_error(file, "", &e))?;
    let relative_mesh = |t: &toml::Table| match t.get("domain").and_then(|d| d.get("file")) {
        Some(toml::Value::String(f)) => std::path::Path::new(f).is_relative(),
        _ => false,
    };
    if overrides.is_empty() && !relative_mesh(&table) {
        return Ok(text.to_string());
    }
    crate::overrides::apply_all(&mut table, overrides)?;
    if relative_mesh(&table)
        && let Some(toml::Value::Table(d)) = table.get_mut("domain")
        && let Some(toml::Value::String(f)) = d.get("file")
    {
        let abs = dir.join(f);
        let abs = abs.canonicalize().unwrap_or(abs);
        d.insert("file".into(), toml::Value::String(abs.display().to_string()));
    }
    toml::to_string(&table).map_err(|e| Error::SceneSyntax {
        file: file.to_string(),
        message: one_paragraph(&e.to_string()),
        diagram: String::new(),
        path: String::new(),
    })
}

/// A scene as the command line reads it (`run`, `check`, and the Python package's `Scene`): the
/// text with its `--set` overrides read first as written (so its errors name the user's lines
/// and keys), then the effective text ([`effective_text`]: what a run keeps as scene.toml) read
/// as the scene. `file` names the source in messages, `dir` is the folder relative paths in it
/// are read from. Returns the scene and its effective text.
pub fn load(text: &str, file: &str, overrides: &[Override], dir: &std::path::Path) -> Result<(Scene, String)> {
    Scene::from_toml_with(text, file, overrides)?;
    let effective = effective_text(text, file, overrides, dir)?;
    let scene = Scene::from_toml(&effective, file)?;
    Ok((scene, effective))
}

/// Read TOML text as a scene; Err: the key path serde reached (empty for a syntax error) and
/// TOML's error.
fn read(text: &str) -> std::result::Result<Scene, (String, toml::de::Error)> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| (String::new(), e))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let mut path = e.path().to_string();
        let inner = e.into_inner();
        // serde reports a missing key at its parent table; name the key itself.
        if let Some(key) = inner.message().strip_prefix("missing field `").and_then(|r| r.split('`').next()) {
            path = if path.is_empty() || path == "." { key.to_string() } else { format!("{path}.{key}") };
        }
        (path, inner)
    })
}

impl Scene {
    /// Parse TOML text. `file` names the source in error messages.
    pub fn from_toml(text: &str, file: &str) -> Result<Scene> {
        read(text).map_err(|(path, e)| syntax_error(file, &path, &e))
    }

    /// Read and parse a scene file.
    pub fn from_file(path: &std::path::Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        Scene::from_toml(&text, &path.display().to_string())
    }

    /// Parse TOML text with `--set` overrides applied to its table first (see
    /// [`crate::overrides`]): the result is read exactly as a file with those values would be,
    /// so an unknown key or a wrong type gets the same key-path error. An error at a key an
    /// override set says the value came from `--set KEY=VALUE`; any other is the user's file's
    /// own, reported at its line in that file.
    pub fn from_toml_with(text: &str, file: &str, overrides: &[Override]) -> Result<Scene> {
        if overrides.is_empty() {
            return Scene::from_toml(text, file);
        }
        let overridden = overridden_text(text, file, overrides)?;
        let (path, e) = match read(&overridden) {
            Ok(scene) => return Ok(scene),
            Err(pe) => pe,
        };
        let at = crate::overrides::parse_path(&path).unwrap_or_default();
        if let Some(o) = overrides.iter().rev().find(|o| !at.is_empty() && crate::overrides::overlap(&o.path, &at)) {
            let message = format!(
                "{path}: {}{} (the value came from --set {}={})",
                one_paragraph(e.message()),
                beyond_i64_hint(e.message(), &at, &o.path, &o.value),
                o.key,
                one_paragraph(&o.value.to_string())
            );
            return Err(Error::SceneSyntax { file: file.to_string(), message, diagram: String::new(), path });
        }
        // not a value an override set: the file's own error, at its line (when the file alone
        // shows it; otherwise the message without a diagram of a text nobody wrote)
        match read(text) {
            Err((p, own)) => Err(syntax_error(file, &p, &own)),
            Ok(_) => {
                let message = if path.is_empty() || path == "." {
                    one_paragraph(e.message())
                } else {
                    format!("{path}: {}", one_paragraph(e.message()))
                };
                let file = format!("{file} with --set");
                Err(Error::SceneSyntax { file, message, diagram: String::new(), path })
            }
        }
    }

    /// Read a scene file with `--set` overrides.
    pub fn from_file_with(path: &std::path::Path, overrides: &[Override]) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        Scene::from_toml_with(&text, &path.display().to_string(), overrides)
    }

    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        // The embedded text is checked by a test; a failure here is a build defect, not user input.
        Scene::from_toml(DEFAULT_SCENE, "<embedded academic scene>")
            .expect("the embedded default scene parses (tested)")
    }
}

/// A (TOML or serde) error message on one line: its non-blank lines, right-trimmed, joined by
/// ` | `.
pub fn one_paragraph(s: &str) -> String {
    // every line terminator (TOML errors quote the offending source line, which may hold a lone \r)
    s.split(['\n', '\r', '\u{b}', '\u{c}', '\u{85}', '\u{2028}', '\u{2029}'])
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
        .collect::<Vec<_>>()
        .join(" | ")
}

/// For a whole number beyond TOML's integers at a key that takes one: `--set output.every=1e20`
/// reads as a float, `100000000000000000000` as a string (TOML's integers are i64), and a Python
/// int beyond i64 arrives as a float; serde says "invalid type: floating point …, expected
/// i64", which names neither the range nor that the number was meant whole.
fn beyond_i64_hint(message: &str, at: &[Segment], set: &[Segment], value: &toml::Value) -> &'static str {
    const HINT: &str = "; this key takes a whole number, and TOML's whole numbers run from -9223372036854775808 to 9223372036854775807";
    let wants_integer = ["expected i64", "expected u64", "expected usize", "expected u32", "expected i32"]
        .iter()
        .any(|w| message.contains(w));
    // the value at the error's key: the override's own, or its element there (`domain.cells=[1e20, 4]`)
    let mut v = value;
    for seg in at.iter().skip(set.len()) {
        v = match (seg, v) {
            (Segment::Index(i), toml::Value::Array(a)) => match a.get(*i) {
                Some(x) => x,
                None => return "",
            },
            (Segment::Key(k), toml::Value::Table(t)) => match t.get(k) {
                Some(x) => x,
                None => return "",
            },
            _ => return "",
        };
    }
    // beyond i64: x ≥ 2⁶³ or x < −2⁶³ (−2⁶³ itself is i64::MIN); a string of digits that TOML
    // read as text only for its range (not `007` or `1__0`, which are in range)
    const TWO_63: f64 = 9_223_372_036_854_775_808.0;
    let whole_beyond = match v {
        toml::Value::Float(x) => x.fract() == 0.0 && (*x >= TWO_63 || *x < -TWO_63),
        toml::Value::String(s) => {
            let digits = s.replace('_', "");
            digits.parse::<i128>().is_ok_and(|n| i64::try_from(n).is_err())
                || (digits.trim_start_matches(['-', '+']).len() > 38
                    && digits.trim_start_matches(['-', '+']).chars().all(|c| c.is_ascii_digit()))
        }
        _ => false,
    };
    if wants_integer && whole_beyond { HINT } else { "" }
}
