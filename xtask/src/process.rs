//! Running programs and preparing folders for the checks: the helpers that `crosscheck.rs` and
//! `workflow.rs` share (each imports this module; neither imports the other).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Run to completion with captured output: Ok((exited with 0, stdout + stderr, or on failure the
/// command line and the end of its output)); Err only when the program could not start.
pub fn spawn(cmd: &mut Command) -> Result<(bool, String), String> {
    // the command line for messages, with paths shown relative to the working directory
    let cwd = cmd.get_current_dir().map(Path::to_path_buf);
    let short = |a: &std::ffi::OsStr| match &cwd {
        Some(d) => rel(d, Path::new(a)),
        None => a.to_string_lossy().into_owned(),
    };
    let shown =
        std::iter::once(short(cmd.get_program())).chain(cmd.get_args().map(short)).collect::<Vec<_>>().join(" ");
    let out = cmd.stdin(Stdio::null()).output().map_err(|e| format!("cannot start `{shown}`: {e}"))?;
    let mut text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.push_str(&String::from_utf8_lossy(&out.stderr));
    let ok = out.status.success();
    if !ok {
        // keep the end of a long log (pip, a Python traceback)
        let lines: Vec<&str> = text.lines().collect();
        let tail = lines[lines.len().saturating_sub(40)..].join("\n");
        let code = out.status.code().map_or_else(|| out.status.to_string(), |c| format!("code {c}"));
        text = format!("`{shown}` exited with {code}:\n{tail}");
    }
    Ok((ok, text))
}

/// Run to completion with captured output; Err (with the end of the output) unless it exits with 0.
pub fn exec(cmd: &mut Command) -> Result<(), String> {
    let (ok, text) = spawn(cmd)?;
    if ok { Ok(()) } else { Err(text) }
}

/// An empty directory (removed first if it exists: stale frames would spoil the frame count).
pub fn fresh_dir(dir: &Path) -> Result<PathBuf, String> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| format!("remove {}: {e}", dir.display()))?;
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("create {}: {e}", dir.display()))?;
    Ok(dir.to_path_buf())
}

/// `p` relative to `root` when it is under it (for messages).
pub fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).display().to_string()
}
