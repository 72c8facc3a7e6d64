//! Outputs in the run folder (SCENES.md): history.csv (every step), contact.csv and VTU
//! frames (every `output.every` steps), series.pvd, summary.json and plots/*.svg.
//!
//! Files are written so that a run stopped at any point leaves valid files: CSV rows are
//! flushed whole after each step, and the PVD, the summary and the charts are written to a
//! temporary name and renamed.

pub mod contact_charts;
pub mod export;
pub mod plots;
pub mod resume;
pub mod summary;
pub mod vtu;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::simulation::{Simulation, StepRecord};

pub use summary::{ModelInfo, Summary};

/// The required history.csv columns (SCENES.md), then our additions.
pub const HISTORY_COLUMNS: &str = "step,t,kinetic,elastic,compliance,external_work,viscous_dissipation,friction_dissipation,\
constraint_dissipation,energy_residual,normal_force,tangential_force,max_penetration,contact_nodes,slip_nodes,\
stick_nodes,newton_iterations,fixed_point_iterations,energy_scale,fixed_point_converged,inner_residual,\
persistency_dissipation,chatter,trapped_kinetic";

/// The contact.csv columns (SCENES.md), then our additions.
pub const CONTACT_COLUMNS: &str = "step,t,node,x,y,u_n,u_t,v_t,p,lambda,friction,status,friction_bound";

/// Write `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("")));
    std::fs::write(&tmp, bytes).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// A light copy of a history row for the charts.
#[derive(Debug, Clone, Copy)]
pub struct ChartRow {
    pub t: f64,
    pub kinetic: f64,
    pub elastic: f64,
    pub compliance: f64,
    pub work: f64,
    pub viscous: f64,
    pub friction: f64,
    pub constraint: f64,
    pub residual: f64,
    pub normal_force: f64,
    pub tangential_force: f64,
}

/// The writer of one run folder.
pub struct Writer {
    dir: PathBuf,
    history: BufWriter<File>,
    contact: Option<BufWriter<File>>,
    frames: Vec<(f64, String)>,
    every: usize,
    pub rows: Vec<ChartRow>,
    /// the contact nodes of every frame: (step, t, records), for the contact charts
    pub contact_frames: Vec<(usize, f64, Vec<crate::simulation::NodeRecord>)>,
}

fn csv_io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

impl Writer {
    /// Create the folder (and frames/, plots/), remove stale outputs of an earlier run, and
    /// open the CSV files with their headers.
    pub fn create(dir: &Path, sim: &Simulation) -> Result<Writer> {
        for sub in ["", "frames", "plots"] {
            let d = dir.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        }
        // stale frames from an earlier run would be listed by no PVD but confuse readers
        if let Ok(rd) = std::fs::read_dir(dir.join("frames")) {
            for e in rd.flatten() {
                if e.path().extension().is_some_and(|x| x == "vtu") {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
        let hp = dir.join("history.csv");
        let mut history = BufWriter::new(File::create(&hp).map_err(csv_io(&hp))?);
        writeln!(history, "{HISTORY_COLUMNS}").map_err(csv_io(&hp))?;
        let cp = dir.join("contact.csv");
        let contact = if sim.problem.contact.is_some() {
            let mut w = BufWriter::new(File::create(&cp).map_err(csv_io(&cp))?);
            writeln!(w, "{CONTACT_COLUMNS}").map_err(csv_io(&cp))?;
            Some(w)
        } else {
            // a scene without contact still gets the file, with its header only
            std::fs::write(&cp, format!("{CONTACT_COLUMNS}\n")).map_err(csv_io(&cp))?;
            None
        };
        Ok(Writer {
            dir: dir.to_path_buf(),
            history,
            contact,
            frames: Vec::new(),
            every: sim.problem.scene.output.every.max(1) as usize,
            rows: Vec::new(),
            contact_frames: Vec::new(),
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Record a step: a history row always; a frame and contact rows every `every` steps and
    /// when `last` is set.
    pub fn record(&mut self, rec: &StepRecord, sim: &Simulation, last: bool) -> Result<()> {
        let e = &rec.energy;
        let r = &rec.report;
        let hp = self.dir.join("history.csv");
        writeln!(
            self.history,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            rec.step,
            rec.t,
            e.kinetic,
            e.elastic,
            e.compliance,
            e.external_work,
            e.viscous_dissipation,
            e.friction_dissipation,
            e.constraint_dissipation,
            e.residual,
            rec.normal_force,
            rec.tangential_force,
            rec.max_penetration,
            rec.contact_nodes,
            rec.slip_nodes,
            rec.stick_nodes,
            r.inner_iterations,
            r.fixed_point_iterations,
            rec.energy_scale,
            r.fixed_point_converged as u8,
            r.inner_residual,
            e.persistency_dissipation,
            rec.chatter,
            rec.trapped_kinetic
        )
        .map_err(csv_io(&hp))?;
        self.history.flush().map_err(csv_io(&hp))?;
        self.rows.push(ChartRow {
            t: rec.t,
            kinetic: e.kinetic,
            elastic: e.elastic,
            compliance: e.compliance,
            work: e.external_work,
            viscous: e.viscous_dissipation,
            friction: e.friction_dissipation,
            constraint: e.constraint_dissipation,
            residual: e.residual,
            normal_force: rec.normal_force,
            tangential_force: rec.tangential_force,
        });
        if rec.step % self.every == 0 || last {
            self.frame(rec, sim)?;
        }
        Ok(())
    }

    fn frame(&mut self, rec: &StepRecord, sim: &Simulation) -> Result<()> {
        let p = sim.problem;
        let mut contact = vec![(0.0, 0.0, 0.0, 0.0, -1); p.mesh.nodes.len()];
        if let (Some(c), Some(w)) = (&p.contact, self.contact.as_mut()) {
            let cp = self.dir.join("contact.csv");
            for (i, nr) in rec.nodes.iter().enumerate() {
                let node = c.nodes[i];
                let x = p.mesh.nodes[node];
                contact[node] = (nr.p + nr.lambda, nr.p, nr.lambda, nr.friction, nr.status.code());
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    rec.step,
                    rec.t,
                    node,
                    x[0],
                    x[1],
                    nr.u_n,
                    nr.u_t,
                    nr.v_t,
                    nr.p,
                    nr.lambda,
                    nr.friction,
                    nr.status.as_str(),
                    nr.bound
                )
                .map_err(csv_io(&cp))?;
            }
            w.flush().map_err(csv_io(&cp))?;
        }
        if !rec.nodes.is_empty() {
            self.contact_frames.push((rec.step, rec.t, rec.nodes.clone()));
        }
        let u = p.dofs.expand(&sim.u);
        let v = p.dofs.expand(&sim.v);
        let frame = vtu::Frame { mesh: &p.mesh, material: &p.material, u: &u, v: &v, contact: &contact };
        let name = format!("frames/frame_{:05}.vtu", rec.step);
        write_atomic(&self.dir.join(&name), vtu::vtu(&frame).as_bytes())?;
        self.frames.push((rec.t, name));
        write_atomic(&self.dir.join("series.pvd"), vtu::pvd(&self.frames).as_bytes())
    }

    /// Write summary.json and the charts.
    pub fn finish(&mut self, summary: &Summary, sim: &Simulation) -> Result<()> {
        let json = serde_json::to_string_pretty(summary).map_err(|e| Error::Output(format!("summary.json: {e}")))?;
        write_atomic(&self.dir.join("summary.json"), json.as_bytes())?;
        self.charts(sim)
    }

    /// Write only the summary (used when a run fails).
    pub fn write_summary(&self, summary: &Summary) -> Result<()> {
        let json = serde_json::to_string_pretty(summary).map_err(|e| Error::Output(format!("summary.json: {e}")))?;
        write_atomic(&self.dir.join("summary.json"), json.as_bytes())
    }

    /// Write plots/: energy.svg and deformed.svg always; with contact, forces.svg,
    /// contact_status.svg and normal_stress.svg (stale ones of an earlier run are removed
    /// when the scene has no contact).
    fn charts(&self, sim: &Simulation) -> Result<()> {
        use plots::Series;
        let save = |name: &str, svg: std::result::Result<String, String>| -> Result<()> {
            let file = format!("plots/{name}");
            let svg = svg.map_err(|e| Error::Output(format!("{file}: {e}")))?;
            write_atomic(&self.dir.join(&file), svg.as_bytes())
        };
        let s = |name: &str, f: fn(&ChartRow) -> f64, secondary: bool| Series {
            name: name.into(),
            points: self.rows.iter().map(|r| (r.t, f(r))).collect(),
            secondary,
        };
        let energy = plots::line_chart(
            "Energy balance (E.1)",
            "t [s]",
            "energy [J/m]",
            Some("(E.1) residual per step [J/m]"),
            &[
                s("kinetic", |r| r.kinetic, false),
                s("elastic", |r| r.elastic, false),
                s("compliance", |r| r.compliance, false),
                s("external work", |r| r.work, false),
                s("viscous dissipation", |r| r.viscous, false),
                s("friction dissipation", |r| r.friction, false),
                s("constraint dissipation", |r| r.constraint, false),
                s("residual", |r| r.residual, true),
            ],
            &[],
        );
        save("energy.svg", energy)?;
        let p = sim.problem;
        save("deformed.svg", contact_charts::deformed(&p.mesh, &p.dofs.expand(&sim.u), p.time(sim.n)))?;
        let Some(c) = &p.contact else {
            for stale in ["forces.svg", "contact_status.svg", "normal_stress.svg"] {
                let _ = std::fs::remove_file(self.dir.join("plots").join(stale));
            }
            return Ok(());
        };
        let p_g = contact_charts::p_at_bound(c);
        let gamma3: f64 = c.omega.iter().sum();
        save("forces.svg", contact_charts::forces(&self.rows, p_g.map(|q| q * gamma3)))?;
        let along = contact_charts::Along::of(&p.mesh, c, &p.scene.boundary.contact);
        save("contact_status.svg", contact_charts::contact_status(&self.contact_frames, &along))?;
        save("normal_stress.svg", contact_charts::normal_stress(&self.contact_frames, &along, p_g))
    }
}
