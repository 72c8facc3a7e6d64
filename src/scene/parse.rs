//! Reading a scene: TOML text (with `--set` overrides applied to its table) → [`Scene`], every
//! unknown key, missing key or wrong type named by its key path.

use super::{DEFAULT_SCENE, Scene};
use crate::error::{Error, Result};

/// The scene text with `overrides` applied to its table (TOML again).
pub fn overridden_text(text: &str, file: &str, overrides: &[crate::overrides::Override]) -> Result<String> {
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| Error::SceneSyntax {
        file: file.to_string(),
        message: one_paragraph(&e.to_string()),
    })?;
    crate::overrides::apply_all(&mut table, overrides)?;
    toml::to_string(&table)
        .map_err(|e| Error::SceneSyntax { file: file.to_string(), message: one_paragraph(&e.to_string()) })
}

impl Scene {
    /// Parse TOML text. `file` names the source in error messages.
    pub fn from_toml(text: &str, file: &str) -> Result<Scene> {
        let de = toml::de::Deserializer::parse(text)
            .map_err(|e| Error::SceneSyntax { file: file.to_string(), message: one_paragraph(&e.to_string()) })?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            let mut path = e.path().to_string();
            let inner = e.into_inner();
            // serde reports a missing key at its parent table; name the key itself.
            if let Some(key) = inner.message().strip_prefix("missing field `").and_then(|r| r.split('`').next()) {
                path = if path.is_empty() || path == "." { key.to_string() } else { format!("{path}.{key}") };
            }
            let inner = one_paragraph(&inner.to_string());
            if path.is_empty() || path == "." {
                Error::SceneSyntax { file: file.to_string(), message: inner }
            } else {
                Error::SceneSyntax { file: file.to_string(), message: format!("{path}: {inner}") }
            }
        })?;
        Ok(scene)
    }

    /// Read and parse a scene file.
    pub fn from_file(path: &std::path::Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        Scene::from_toml(&text, &path.display().to_string())
    }

    /// Parse TOML text with `--set` overrides applied to its table first (see
    /// [`crate::overrides`]): the result is read exactly as a file with those values would be,
    /// so an unknown key or a wrong type gets the same key-path error.
    pub fn from_toml_with(text: &str, file: &str, overrides: &[crate::overrides::Override]) -> Result<Scene> {
        if overrides.is_empty() {
            return Scene::from_toml(text, file);
        }
        // positions in a message are those of the overridden text, so the source says so
        Scene::from_toml(&overridden_text(text, file, overrides)?, &format!("{file} with --set"))
    }

    /// Read a scene file with `--set` overrides.
    pub fn from_file_with(path: &std::path::Path, overrides: &[crate::overrides::Override]) -> Result<Scene> {
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
