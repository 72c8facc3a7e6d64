//! Reopening a run folder at a checkpoint: history.csv and contact.csv are cut back to the
//! rows of steps ≤ the checkpoint (a run stopped later may have written more), frames after
//! it are removed, series.pvd is rewritten, and the chart data are read back from the CSVs.

use std::fs::OpenOptions;
use std::io::BufWriter;
use std::path::Path;

use super::{write_atomic, ChartRow, Writer};
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::simulation::NodeRecord;
use crate::step::NodeStatus;

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

fn column(header: &str, name: &str) -> Result<usize> {
    header
        .split(',')
        .position(|c| c == name)
        .ok_or_else(|| Error::Output(format!("history.csv has no column {name}: not a run folder of this version")))
}

impl Writer {
    /// Reopen `dir` to continue after checkpoint step `step`.
    pub fn reopen(dir: &Path, problem: &Problem, step: usize) -> Result<Writer> {
        let hp = dir.join("history.csv");
        let header = std::fs::read_to_string(&hp).map_err(|e| Error::io(&hp, e))?.lines().next().unwrap_or("").to_string();
        let rows = cut_csv(&hp, step)?;
        let chart_rows = chart_rows(&header, &rows)?;
        let cp = dir.join("contact.csv");
        let contact_frames = contact_frames(&cut_csv(&cp, step)?, problem.mesh.dim());
        let frames = kept_frames(dir, problem, step);
        write_atomic(&dir.join("series.pvd"), super::vtu::pvd(&frames).as_bytes())?;
        let open = |p: &Path| OpenOptions::new().append(true).open(p).map(BufWriter::new).map_err(|e| Error::io(p, e));
        let contact = if problem.contact.is_some() { Some(open(&cp)?) } else { None };
        let mut w = Writer::new(dir, problem, open(&hp)?, contact, frames, chart_rows, contact_frames);
        if problem.model.output_trajectory {
            w.trajectory = Some(super::trajectory::TrajectoryWriter::reopen(&dir.join("trajectory.f64"), problem.dofs.n_free, step)?);
        }
        Ok(w)
    }
}

/// A number of a CSV row (NaN where missing or unreadable).
fn num(r: &[String], c: usize) -> f64 {
    r.get(c).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN)
}

/// The chart data of history.csv rows, found by column name.
fn chart_rows(header: &str, rows: &[Vec<String>]) -> Result<Vec<ChartRow>> {
    let col = |n: &str| column(header, n);
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
