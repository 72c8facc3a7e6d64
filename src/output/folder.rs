//! The run folder contract (README, "Outputs"): a run owns its folder.
//!
//! A run owns the files it writes ([`OWNED`], the frames in `frames/` and the charts in
//! `plots/`, and their temporaries). Besides those a run folder may hold only scene files
//! (`*.toml`, such as the scene a sweep or the user put there), `run.log` and the folder
//! `study/` (`dyncontact study penalty`'s files), which a run neither reads nor removes. A fresh run
//! 1. takes the folder's lock (`run.lock`: one process writes a folder at a time; the lock
//!    goes with the process, so a killed run leaves none behind);
//! 2. refuses a folder that holds anything else, naming it (so `--out ~` never deletes a file
//!    that a run did not write);
//! 3. checks that it can write there before it changes anything;
//! 4. writes summary.json with status `running`;
//! 5. removes the earlier run's files (all of them: history, frames, checkpoint, trajectory,
//!    charts), and only then writes its own.
//!
//! So a killed run never reads `completed`, and a failure before step 4 leaves the folder as it
//! was.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Files at the top of a run folder that a run writes.
pub const OWNED: [&str; 7] =
    ["summary.json", "history.csv", "contact.csv", "checkpoint.json", "trajectory.f64", "series.pvd", "run.lock"];
/// Subfolders whose files of the given extension a run writes.
const OWNED_IN: [(&str, &str); 2] = [("frames", "vtu"), ("plots", "svg")];
/// Whether a file at the top of a run folder is one the run keeps without owning it: a scene
/// (`*.toml`) or a log of the run (`run.log`).
fn kept(name: &str) -> bool {
    name == "run.log" || Path::new(name).extension().is_some_and(|x| x == "toml")
}
/// Subfolders a run keeps without owning them: `study/`, where `dyncontact study penalty` writes
/// by default (its OUT is the scene's run folder, out/<name>).
const KEPT_DIRS: [&str; 1] = ["study"];
/// The lock file.
const LOCK: &str = "run.lock";

/// Whether `name` (a file at the top of a run folder) is the run's: an owned file or the
/// temporary of one (`summary.json.tmp`, written by a rename-into-place).
fn owned_top(name: &str) -> bool {
    let base = name.strip_suffix(".tmp").unwrap_or(name);
    OWNED.contains(&base)
}

/// Whether `name` in the subfolder `sub` is the run's: `frame_00010.vtu`, `energy.svg`, or
/// their temporaries.
fn owned_in(sub: &str, name: &str) -> bool {
    let base = name.strip_suffix(".tmp").unwrap_or(name);
    OWNED_IN.iter().any(|(d, ext)| *d == sub && Path::new(base).extension().is_some_and(|x| x == *ext))
}

/// What `dir` holds that a run does not own (relative paths), at most `limit` of them.
pub fn foreign(dir: &Path, limit: usize) -> Result<Vec<String>> {
    let mut found = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return Ok(found) };
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let path = e.path();
        if let Some((sub, _)) = OWNED_IN.iter().find(|(d, _)| *d == name) {
            if !path.is_dir() {
                found.push(format!("{name} (not a folder)"));
            } else if let Ok(inner) = std::fs::read_dir(&path) {
                for f in inner.flatten() {
                    let fname = f.file_name().to_string_lossy().to_string();
                    if !(owned_in(sub, &fname) && f.path().is_file()) {
                        found.push(format!("{name}/{fname}"));
                    }
                }
            }
        } else if KEPT_DIRS.contains(&name.as_str()) && path.is_dir() {
            continue;
        } else if !((owned_top(&name) || kept(&name)) && path.is_file()) {
            found.push(name);
        }
        if found.len() >= limit {
            break;
        }
    }
    found.sort();
    Ok(found)
}

/// The lock of a folder, held while a run (or a sweep) writes it; released when dropped or
/// when the process ends, however it ends.
#[derive(Debug)]
pub struct Lock {
    file: File,
    /// the lock file and the folder, when this process created them (see [`Lock::discard`])
    created: (Option<PathBuf>, Option<PathBuf>),
}

impl Lock {
    /// Release the lock of a run that was refused before it wrote anything, removing the lock
    /// file (and the folder) when this process created them, so the folder is left as it was.
    /// The file is removed while still locked; a process that opened it meanwhile and locks it
    /// after this one lets go finds it is no longer the folder's lock file ([`lock`] checks) and
    /// locks the folder's new one instead.
    pub fn discard(self) {
        if let Some(file) = &self.created.0 {
            let _ = std::fs::remove_file(file);
        }
        if let Some(dir) = &self.created.1 {
            // only if empty: never a file of anyone else's
            let _ = std::fs::remove_dir(dir);
        }
    }
}

impl Drop for Lock {
    /// Unlock explicitly: closing this descriptor alone would leave the lock held by any copy of
    /// it — a child process that another thread is starting holds every descriptor of its
    /// parent between fork and exec (Python's `os.fork` until it exits) — and this process's
    /// next lock of the folder would be refused. (That refused a sweep's point at random: its
    /// folder was left with only run.lock and scene.toml.)
    fn drop(&mut self) {
        let _ = self.file.unlock();
    }
}

/// Lock `dir` for this process through `dir/<name>` (created with `dir` if missing). Refused
/// when another process holds it. On a file system without locks (some network file systems)
/// the run goes on unlocked: nothing else could be done there.
pub fn lock(dir: &Path, name: &str) -> Result<Lock> {
    let new_dir = (!dir.exists()).then(|| dir.to_path_buf());
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let p = dir.join(name);
    // a lock file removed by a refused run (Lock::discard) between this process's open and its
    // lock is opened again; a few rounds at most, however the processes interleave
    for _ in 0..16 {
        // `create_new` says whether this process created the file
        let (file, created) = match OpenOptions::new().write(true).create_new(true).open(&p) {
            Ok(f) => (f, true),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => match OpenOptions::new().write(true).open(&p) {
                Ok(f) => (f, false),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(Error::io(&p, e)),
            },
            Err(e) => return Err(Error::io(&p, e)),
        };
        let created = (created.then(|| p.clone()), new_dir.clone());
        match file.try_lock() {
            Ok(()) if is_the_file_at(&file, &p) => return Ok(Lock { file, created }),
            Ok(()) => {
                let _ = file.unlock();
            }
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(Error::folder(
                    dir,
                    format!(
                        "another dyncontact process is writing this folder (it holds {name}); wait for it to end or choose another folder"
                    ),
                ));
            }
            Err(std::fs::TryLockError::Error(_)) => return Ok(Lock { file, created }),
        }
    }
    Err(Error::folder(
        dir,
        format!("its lock file {name} keeps being removed and created: another process is at work here"),
    ))
}

/// Whether the open `file` is still the file at `path` (not one removed since it was opened).
#[cfg(unix)]
fn is_the_file_at(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn is_the_file_at(_: &File, path: &Path) -> bool {
    path.exists()
}

/// Lock a run folder ([`lock`] with `run.lock`).
pub fn lock_run(dir: &Path) -> Result<Lock> {
    lock(dir, LOCK)
}

/// Before a fresh run writes anything: refuse a folder holding files a run does not own, and
/// check that the folder (and its frames/ and plots/, where they exist) can be written.
/// Returns whether an earlier run's files are there (they are about to be replaced).
pub fn check_fresh(dir: &Path) -> Result<bool> {
    let foreign = foreign(dir, 6)?;
    if !foreign.is_empty() {
        let more = if foreign.len() > 5 { ", …" } else { "" };
        let shown = foreign.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
        return Err(Error::folder(
            dir,
            format!(
                "holds files that are not a dyncontact run's ({shown}{more}); a run replaces the whole folder, so give an empty or new folder with --out"
            ),
        ));
    }
    for sub in ["", "frames", "plots"] {
        let d = dir.join(sub);
        if d.is_dir() {
            probe(&d)?;
        }
    }
    Ok(OWNED.iter().any(|f| *f != LOCK && dir.join(f).exists()) || OWNED_IN.iter().any(|(d, _)| dir.join(d).is_dir()))
}

/// Before anything is validated or built: `dir` must be a folder, or be creatable as one — Err
/// (a folder error, naming the path) for a file or a device given as the folder, or a missing
/// folder below a file or in a place that cannot be written (`/proc/x`).
pub fn check_target(dir: &Path) -> Result<()> {
    if dir.exists() {
        return if dir.is_dir() {
            Ok(())
        } else {
            Err(Error::folder(
                dir,
                "is not a folder (a file or a device): the run folder must be a new folder or a run's",
            ))
        };
    }
    let mut at = dir;
    while let Some(parent) = at.parent().filter(|p| !p.as_os_str().is_empty()) {
        at = parent;
        if at.exists() {
            break;
        }
    }
    if at == dir || !at.exists() {
        return Ok(()); // relative to the working directory, which the run creates it in
    }
    if !at.is_dir() {
        return Err(Error::folder(at, format!("is a file: the folder {} cannot be created below it", dir.display())));
    }
    probe(at).map_err(|_| {
        Error::folder(at, format!("cannot be written: the folder {} cannot be created there", dir.display()))
    })
}

/// Create and remove a file in `dir`: Err (naming `dir`) when the folder cannot be written.
fn probe(dir: &Path) -> Result<()> {
    // one name per call: threads of one process (Python's) may probe the same folder at once
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let p: PathBuf = dir.join(format!(".dyncontact-probe-{}-{call}", std::process::id()));
    File::create(&p).map_err(|e| Error::io(dir, e))?;
    std::fs::remove_file(&p).map_err(|e| Error::io(dir, e))
}

/// Remove every file a run owns but summary.json and the lock (the new run's summary is already
/// there), and the frames/ and plots/ files.
pub fn clear(dir: &Path) -> Result<()> {
    let remove = |p: &Path| match std::fs::remove_file(p) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(p, e)),
    };
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            if owned_top(&name) && name != "summary.json" && name != LOCK {
                remove(&e.path())?;
            }
        }
    }
    for (sub, _) in OWNED_IN {
        if let Ok(rd) = std::fs::read_dir(dir.join(sub)) {
            for e in rd.flatten() {
                if owned_in(sub, &e.file_name().to_string_lossy()) {
                    remove(&e.path())?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (the run folder contract) A lock this process released is free at once although a copy
    /// of its descriptor stays open — as a child process between fork and exec holds it —
    /// and a lock that is held is refused, naming the lock file.
    #[test]
    fn a_released_lock_is_free_while_a_copy_of_its_descriptor_is_open() {
        let dir = std::env::temp_dir().join(format!("dyncontact-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let first = lock_run(&dir).expect("a fresh folder locks");
        // the descriptor a child would inherit: the same open file description as the lock's
        let inherited = first.file.try_clone().expect("the descriptor duplicates");
        let held = lock_run(&dir).expect_err("a held lock refuses");
        drop(first);
        let second = lock_run(&dir);
        drop(inherited);
        let _ = std::fs::remove_dir_all(&dir);
        assert!(held.to_string().contains("another dyncontact process") && held.to_string().contains(LOCK), "{held}");
        assert!(second.is_ok(), "the released lock stayed held by the open copy: {second:?}");
    }
}
