//! Reopening a run folder at a checkpoint. First [`check`] proves, reading only, that the
//! folder's files belong to the checkpoint: history.csv has every step from 0 on, one row each,
//! through the checkpoint's step, and that row holds the checkpoint's state (its time and every
//! energy term, bit for bit); contact.csv holds exactly the frames of the steps up to it; every
//! such frame is on disk. Anything else is refused, naming the file and the mismatch. Then
//! [`Writer::reopen`] cuts history.csv and contact.csv back to the rows of steps ≤ the
//! checkpoint (a run stopped later may have written more), removes later frames, rewrites
//! series.pvd and reads the chart data back from the CSVs.

use std::path::Path;

use super::{AppendFile, ChartRow, Writer, history_header, write_atomic};
use crate::checkpoint::Checkpoint;
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::simulation::NodeRecord;
use crate::step::NodeStatus;

/// The history.csv columns a checkpoint's state is compared with: (column, value in the state).
fn state_columns(cp: &Checkpoint, problem: &Problem) -> Vec<(&'static str, f64)> {
    let s = cp.state();
    let e = s.energy;
    vec![
        ("t", problem.time(cp.step)),
        ("kinetic", e.kinetic),
        ("elastic", e.elastic),
        ("compliance", e.compliance),
        ("external_work", e.external_work),
        ("viscous_dissipation", e.viscous_dissipation),
        ("friction_dissipation", e.friction_dissipation),
        ("constraint_dissipation", e.constraint_dissipation),
        ("persistency_dissipation", e.persistency_dissipation),
        ("energy_residual", e.residual),
        ("energy_scale", s.energy_scale),
    ]
}

/// The steps that have a frame, up to and including `step`: every `output.every`-th (the frame
/// of the last step of a scene is written only when the run completes).
fn frame_steps(problem: &Problem, step: usize) -> Vec<usize> {
    let every = problem.model.output_every;
    if every == 0 { Vec::new() } else { (0..=step).step_by(every).collect() }
}

/// Prove, reading only, that the files in `dir` belong to the checkpoint `cp` (see the module
/// documentation); Err names the file and the mismatch.
pub fn check(dir: &Path, problem: &Problem, cp: &Checkpoint) -> Result<()> {
    let refuse = |file: &str, m: String| {
        Error::folder(
            dir.join(file),
            format!(
                "{m}; the checkpoint (step {}) and this file do not belong together, so the run is not resumed",
                cp.step
            ),
        )
    };
    let read =
        |file: &str| std::fs::read_to_string(dir.join(file)).map_err(|e| refuse(file, format!("cannot be read ({e})")));
    // history.csv: rows 0, 1, …, at least through the checkpoint's step, whole
    let text = read("history.csv")?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("");
    if header != history_header() {
        return Err(refuse("history.csv", "its header is not this version's history.csv header".into()));
    }
    let columns: Vec<&str> = header.split(',').collect();
    let mut at_step: Option<Vec<&str>> = None;
    let mut rows = 0usize;
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != columns.len() {
            // a last row cut short by a kill after the checkpoint's step is cut off on resume
            if i > cp.step {
                break;
            }
            return Err(refuse(
                "history.csv",
                format!("row {} (step {i}) has {} fields, not {}", i + 2, fields.len(), columns.len()),
            ));
        }
        match fields[0].parse::<usize>() {
            Ok(s) if s == i => {}
            Ok(s) => {
                return Err(refuse(
                    "history.csv",
                    format!(
                        "row {} is step {s} where step {i} belongs: the rows of steps {i}..{} are missing",
                        i + 2,
                        s.saturating_sub(1)
                    ),
                ));
            }
            Err(_) => return Err(refuse("history.csv", format!("row {} does not start with a step number", i + 2))),
        }
        if i == cp.step {
            at_step = Some(fields);
        }
        rows += 1;
    }
    let Some(row) = at_step else {
        return Err(refuse("history.csv", format!("has the steps 0..{} only", rows.saturating_sub(1))));
    };
    for (name, want) in state_columns(cp, problem) {
        let Some(c) = columns.iter().position(|c| *c == name) else { continue };
        // equal as f64: bit for bit but for a zero's sign, which history.csv does not write
        let got = row[c].parse::<f64>().ok();
        if got != Some(want) {
            return Err(refuse(
                "history.csv",
                format!(
                    "the row of step {} does not hold the checkpoint's state ({name} = {} there, {want} in checkpoint.json)",
                    cp.step, row[c]
                ),
            ));
        }
    }
    // contact.csv and frames/: exactly the frames of the steps up to the checkpoint's
    let expected = frame_steps(problem, cp.step);
    if problem.contact.is_some() {
        let text = read("contact.csv")?;
        let mut steps: Vec<usize> = Vec::new();
        for line in text.lines().skip(1) {
            let Some(s) = line.split(',').next().and_then(|f| f.parse::<usize>().ok()) else { continue };
            if s <= cp.step && steps.last() != Some(&s) {
                steps.push(s);
            }
        }
        // the frame of the checkpoint's own step, off the output grid, is that of a completed
        // run's last step (a run extended by a later time.end goes on from it)
        if steps.last() == Some(&cp.step) && expected.last() != Some(&cp.step) {
            steps.pop();
        }
        if steps != expected {
            let missing: Vec<usize> = expected.iter().copied().filter(|s| !steps.contains(s)).take(5).collect();
            let extra: Vec<usize> = steps.iter().copied().filter(|s| !expected.contains(s)).take(5).collect();
            return Err(refuse(
                "contact.csv",
                format!(
                    "holds the frames of steps that are not this run's (missing: {missing:?}, unexpected: {extra:?})"
                ),
            ));
        }
    }
    for s in expected {
        let name = format!("frames/frame_{s:05}.vtu");
        if !dir.join(&name).is_file() {
            return Err(refuse(&name, "is missing".into()));
        }
    }
    Ok(())
}

/// Keep the header and the rows whose first field (the step) is ≤ `step`; returns the rows.
fn cut_csv(path: &Path, step: usize) -> Result<Vec<Vec<String>>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("").to_string();
    let mut kept = vec![header.clone()];
    let mut rows = Vec::new();
    for l in lines {
        let fields: Vec<String> = l.split(',').map(str::to_string).collect();
        // a half-written last line (the run was killed mid-write) has too few fields: drop it
        if fields.len() != header.split(',').count() {
            continue;
        }
        match fields[0].parse::<usize>() {
            Ok(s) if s <= step => {
                kept.push(l.to_string());
                rows.push(fields);
            }
            _ => {}
        }
    }
    write_atomic(path, format!("{}\n", kept.join("\n")).as_bytes())?;
    Ok(rows)
}

/// The index of column `name` of the header of `path` (history.csv).
fn column(path: &Path, header: &str, name: &str) -> Result<usize> {
    header
        .split(',')
        .position(|c| c == name)
        .ok_or_else(|| Error::folder(path, format!("it has no column {name}: not a run folder of this version")))
}

impl Writer {
    /// Reopen `dir` to continue after checkpoint step `step` ([`check`] has accepted it).
    pub fn reopen(dir: &Path, problem: &Problem, step: usize) -> Result<Writer> {
        let hp = dir.join("history.csv");
        let header =
            std::fs::read_to_string(&hp).map_err(|e| Error::io(&hp, e))?.lines().next().unwrap_or("").to_string();
        let rows = cut_csv(&hp, step)?;
        let chart_rows = chart_rows(&hp, &header, &rows)?;
        let cp = dir.join("contact.csv");
        let contact_frames = contact_frames(&cut_csv(&cp, step)?, problem.mesh.dim());
        let frames = kept_frames(dir, problem, step);
        write_atomic(&dir.join("series.pvd"), super::vtu::pvd(&frames).as_bytes())?;
        let contact = if problem.contact.is_some() { Some(AppendFile::open(&cp)?) } else { None };
        let mut w = Writer::new(dir, problem, AppendFile::open(&hp)?, contact, frames, chart_rows, contact_frames);
        if problem.model.output_trajectory {
            w.trajectory = Some(super::trajectory::TrajectoryWriter::reopen(
                &dir.join("trajectory.f64"),
                problem.dofs.n_free,
                step,
            )?);
        }
        Ok(w)
    }
}

/// A number of a CSV row (NaN where missing or unreadable).
fn num(r: &[String], c: usize) -> f64 {
    r.get(c).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN)
}

/// The chart data of the rows of history.csv (`path`), found by column name.
fn chart_rows(path: &Path, header: &str, rows: &[Vec<String>]) -> Result<Vec<ChartRow>> {
    let col = |n: &str| column(path, header, n);
    let (ct, ck, ce, cc, cw, cv, cf, cx, cr, cn, ctg) = (
        col("t")?,
        col("kinetic")?,
        col("elastic")?,
        col("compliance")?,
        col("external_work")?,
        col("viscous_dissipation")?,
        col("friction_dissipation")?,
        col("constraint_dissipation")?,
        col("energy_residual")?,
        col("normal_force")?,
        col("tangential_force")?,
    );
    Ok(rows
        .iter()
        .map(|r| ChartRow {
            t: num(r, ct),
            kinetic: num(r, ck),
            elastic: num(r, ce),
            compliance: num(r, cc),
            work: num(r, cw),
            viscous: num(r, cv),
            friction: num(r, cf),
            constraint: num(r, cx),
            residual: num(r, cr),
            normal_force: num(r, cn),
            tangential_force: num(r, ctg),
        })
        .collect())
}

/// The contact frames of contact.csv rows: (step, t, records), grouped by frame.
fn contact_frames(crow: &[Vec<String>], dim: usize) -> Vec<(usize, f64, Vec<NodeRecord>)> {
    let mut contact_frames: Vec<(usize, f64, Vec<NodeRecord>)> = Vec::new();
    // 3-D rows carry z after y, and the global components before friction_bound
    let (o, bound) = if dim == 3 { (1, 19) } else { (0, 12) };
    for r in crow {
        let st: usize = r[0].parse().unwrap_or(0);
        let status = r.get(11 + o).and_then(|s| NodeStatus::from_name(s)).unwrap_or(NodeStatus::Separated);
        let vec3 = |c: usize| if dim == 3 { [num(r, c), num(r, c + 1), num(r, c + 2)] } else { [0.0; 3] };
        let rec = NodeRecord {
            u_n: num(r, 5 + o),
            u_t: num(r, 6 + o),
            v_t: num(r, 7 + o),
            p: num(r, 8 + o),
            lambda: num(r, 9 + o),
            friction: num(r, 10 + o),
            bound: num(r, bound),
            status,
            v_t_vec: vec3(13),
            friction_vec: vec3(16),
        };
        match contact_frames.last_mut() {
            Some(f) if f.0 == st => f.2.push(rec),
            _ => contact_frames.push((st, num(r, 1), vec![rec])),
        }
    }
    contact_frames
}

/// The frames of steps ≤ `step` that exist (as (t, path) for series.pvd); later ones are removed.
fn kept_frames(dir: &Path, problem: &Problem, step: usize) -> Vec<(f64, String)> {
    let mut frames = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir.join("frames")) {
        let mut names: Vec<(usize, String)> = rd
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().to_string();
                let n = name.strip_prefix("frame_")?.strip_suffix(".vtu")?.parse::<usize>().ok()?;
                Some((n, name))
            })
            .collect();
        names.sort();
        for (n, name) in names {
            if n <= step {
                frames.push((problem.time(n), format!("frames/{name}")));
            } else {
                let _ = std::fs::remove_file(dir.join("frames").join(&name));
            }
        }
    }
    frames
}
