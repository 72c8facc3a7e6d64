//! Outputs in the run folder (the README): history.csv (every step), contact.csv and VTU
//! frames (every `output.every` steps), series.pvd, summary.json and plots/*.svg.
//!
//! Files are written so that a run stopped at any point leaves valid files: CSV rows reach the
//! disk whole after each step (a row that a full disk cut short is removed again), and the PVD,
//! the summary and the charts are written to a temporary name and renamed.
//!
//! A VTU frame is encoded and written on a background thread while the time loop goes on (one
//! frame in flight at most: the next frame, the summary and the end of the run wait for it and
//! report its error), so a frame costs the loop only the copy of u and v.

pub mod contact_charts;
pub mod csv;
pub mod export;
pub mod folder;
pub mod loglog;
pub mod plots;
pub mod resume;
pub mod style;
pub mod summary;
pub mod trajectory;
pub mod units;
pub mod vtu;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;

use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::simulation::{NodeRecord, State, StepRecord};

pub use crate::files::{AppendFile, write_atomic, write_files};
pub use summary::{ModelInfo, Summary};

/// A history.csv value: a real (written by [`csv::real`]: shortest round-trip, exponent outside
/// 1e-5 ≤ |x| < 1e16) or a count.
#[derive(Debug, Clone, Copy)]
pub enum Cell {
    Real(f64),
    Count(usize),
}

impl Cell {
    /// The value as history.csv holds it ([`csv::as_written`]: a zero without its sign).
    pub fn value(self) -> f64 {
        match self {
            Cell::Real(x) => csv::as_written(x),
            Cell::Count(n) => n as f64,
        }
    }
}

impl std::fmt::Display for Cell {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Cell::Real(x) => f.write_str(&csv::real(*x)),
            Cell::Count(n) => write!(f, "{n}"),
        }
    }
}

/// A history.csv column: its name and how a record gives its value.
pub type Column = (&'static str, fn(&StepRecord) -> Cell);

/// history.csv, column by column: the required columns of the README's output contract, then
/// our additions. The header and every row are written from this one table.
pub const HISTORY: [Column; 27] = [
    ("step", |r| Cell::Count(r.step)),
    ("t", |r| Cell::Real(r.t)),
    ("kinetic", |r| Cell::Real(r.energy.kinetic)),
    ("elastic", |r| Cell::Real(r.energy.elastic)),
    ("compliance", |r| Cell::Real(r.energy.compliance)),
    ("external_work", |r| Cell::Real(r.energy.external_work)),
    ("viscous_dissipation", |r| Cell::Real(r.energy.viscous_dissipation)),
    ("friction_dissipation", |r| Cell::Real(r.energy.friction_dissipation)),
    ("constraint_dissipation", |r| Cell::Real(r.energy.constraint_dissipation)),
    ("energy_residual", |r| Cell::Real(r.energy.residual)),
    ("normal_force", |r| Cell::Real(r.normal_force)),
    ("tangential_force", |r| Cell::Real(r.tangential_force)),
    ("max_penetration", |r| Cell::Real(r.max_penetration)),
    ("contact_nodes", |r| Cell::Count(r.contact_nodes)),
    ("slip_nodes", |r| Cell::Count(r.slip_nodes)),
    ("stick_nodes", |r| Cell::Count(r.stick_nodes)),
    ("newton_iterations", |r| Cell::Count(r.report.inner_iterations)),
    ("fixed_point_iterations", |r| Cell::Count(r.report.fixed_point_iterations)),
    ("energy_scale", |r| Cell::Real(r.energy_scale)),
    ("fixed_point_converged", |r| Cell::Count(usize::from(r.report.fixed_point_converged()))),
    ("inner_residual", |r| Cell::Real(r.report.inner_residual)),
    ("persistency_dissipation", |r| Cell::Real(r.energy.persistency_dissipation)),
    ("chatter", |r| Cell::Real(r.chatter)),
    ("trapped_kinetic", |r| Cell::Real(r.trapped_kinetic)),
    ("friction_force_x", |r| Cell::Real(r.friction_force[0])),
    ("friction_force_y", |r| Cell::Real(r.friction_force[1])),
    ("friction_force_z", |r| Cell::Real(r.friction_force[2])),
];

/// The history.csv header line (without the newline).
pub fn history_header() -> String {
    HISTORY.iter().map(|(name, _)| *name).collect::<Vec<_>>().join(",")
}

/// The contact.csv columns (the README's output contract), then our additions.
pub const CONTACT_COLUMNS: &str = "step,t,node,x,y,u_n,u_t,v_t,p,lambda,friction,status,friction_bound";
/// The 3-D contact.csv columns (SCENES.md, "Three dimensions"): z after y, magnitudes in the
/// tangent plane, then the global components of v̄ and of the friction traction.
pub const CONTACT_COLUMNS_3D: &str = "step,t,node,x,y,z,u_n,u_t,v_t,p,lambda,friction,status,v_tx,v_ty,v_tz,friction_x,friction_y,friction_z,friction_bound";

/// The contact.csv header for a problem of dimension d.
pub fn contact_columns(dim: usize) -> &'static str {
    if dim == 3 { CONTACT_COLUMNS_3D } else { CONTACT_COLUMNS }
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

/// A contact record as contact.csv holds it: every real with a zero's sign dropped
/// ([`csv::as_written`]), as a resumed run reads it back.
fn as_written(nr: &NodeRecord) -> NodeRecord {
    let w = csv::as_written;
    NodeRecord {
        u_n: w(nr.u_n),
        u_t: w(nr.u_t),
        v_t: w(nr.v_t),
        p: w(nr.p),
        lambda: w(nr.lambda),
        friction: w(nr.friction),
        bound: w(nr.bound),
        status: nr.status,
        v_t_vec: nr.v_t_vec.map(w),
        friction_vec: nr.friction_vec.map(w),
    }
}

/// The writer of one run folder.
pub struct Writer {
    dir: PathBuf,
    history: AppendFile,
    contact: Option<AppendFile>,
    frames: Vec<(f64, String)>,
    every: usize,
    pub rows: Vec<ChartRow>,
    /// the contact nodes of every frame: (step, t, records), for the contact charts
    pub contact_frames: Vec<(usize, f64, Vec<NodeRecord>)>,
    /// the mesh, shared with the frame thread
    mesh: Arc<crate::mesh::Geometry>,
    /// the frame being written (VTU, then series.pvd)
    pending: Option<JoinHandle<Result<()>>>,
    /// trajectory.f64 (`output.trajectory`)
    trajectory: Option<trajectory::TrajectoryWriter>,
}

impl Drop for Writer {
    /// A frame in flight is finished before the writer goes (its error, if any, was not asked
    /// for: every path that reports errors calls [`Writer::wait`] first).
    fn drop(&mut self) {
        let _ = self.wait();
    }
}

impl Writer {
    /// Create frames/ and plots/ and open the CSV files with their headers, in a folder that
    /// holds no earlier run's files (output/folder.rs cleared them).
    pub fn create(dir: &Path, problem: &Problem) -> Result<Writer> {
        for sub in ["", "frames", "plots"] {
            let d = dir.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        }
        let mut history = AppendFile::create(&dir.join("history.csv"))?;
        history.append(format!("{}\n", history_header()).as_bytes())?;
        let mut contact = AppendFile::create(&dir.join("contact.csv"))?;
        contact.append(format!("{}\n", contact_columns(problem.mesh.dim())).as_bytes())?;
        // a scene without contact still gets the file, with its header only
        let contact = problem.contact.is_some().then_some(contact);
        let mut w = Writer::new(dir, problem, history, contact, Vec::new(), Vec::new(), Vec::new());
        if problem.model.output_trajectory {
            w.trajectory =
                Some(trajectory::TrajectoryWriter::create(&dir.join("trajectory.f64"), problem.dofs.n_free)?);
        }
        Ok(w)
    }

    pub(crate) fn new(
        dir: &Path,
        problem: &Problem,
        history: AppendFile,
        contact: Option<AppendFile>,
        frames: Vec<(f64, String)>,
        rows: Vec<ChartRow>,
        contact_frames: Vec<(usize, f64, Vec<NodeRecord>)>,
    ) -> Writer {
        Writer {
            dir: dir.to_path_buf(),
            history,
            contact,
            frames,
            every: problem.model.output_every,
            rows,
            contact_frames,
            mesh: Arc::new(problem.mesh.clone()),
            pending: None,
            trajectory: None,
        }
    }

    /// Wait for the frame in flight and return its result.
    pub fn wait(&mut self) -> Result<()> {
        match self.pending.take() {
            Some(h) => h.join().unwrap_or_else(|_| Err(Error::Internal("the frame writer thread panicked".into()))),
            None => Ok(()),
        }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Record a step: a history row always; a frame and contact rows every `every` steps and
    /// when `last` is set, none when `every` is 0 (`output.every = 0`: no frames). `state` is the simulation's state after the step (for the frame).
    pub fn record(&mut self, rec: &StepRecord, problem: &Problem, state: &State, last: bool) -> Result<()> {
        let mut row = String::with_capacity(512);
        for (j, (_, value)) in HISTORY.iter().enumerate() {
            let sep = if j + 1 == HISTORY.len() { "\n" } else { "," };
            let _ = write!(row, "{}{sep}", value(rec));
        }
        self.history.append(row.as_bytes())?;
        // the charts' values as history.csv holds them (a zero without its sign), which a
        // resumed run reads back: its charts equal an uninterrupted run's
        let (e, w) = (&rec.energy, csv::as_written);
        self.rows.push(ChartRow {
            t: w(rec.t),
            kinetic: w(e.kinetic),
            elastic: w(e.elastic),
            compliance: w(e.compliance),
            work: w(e.external_work),
            viscous: w(e.viscous_dissipation),
            friction: w(e.friction_dissipation),
            constraint: w(e.constraint_dissipation),
            residual: w(e.residual),
            normal_force: w(rec.normal_force),
            tangential_force: w(rec.tangential_force),
        });
        if let Some(tw) = self.trajectory.as_mut() {
            tw.record(rec.step, rec.t, &state.u, &state.v)?;
        }
        if self.every > 0 && (rec.step.is_multiple_of(self.every) || last) {
            self.frame(rec, problem, state)?;
        }
        Ok(())
    }

    fn frame(&mut self, rec: &StepRecord, p: &Problem, state: &State) -> Result<()> {
        let mut contact = vec![vtu::NodeContact::OFF; p.mesh.n_nodes()];
        if let (Some(c), Some(w)) = (&p.contact, self.contact.as_mut()) {
            let mut rows = String::with_capacity(160 * rec.nodes.len());
            for (i, nr) in rec.nodes.iter().enumerate() {
                let node = c.nodes[i];
                let x = p.mesh.point(node);
                contact[node] = vtu::NodeContact::of(nr);
                // the columns of contact_columns(d): z after y in 3-D, the global components
                // of v̄ and of the friction before friction_bound
                let dim = c.dim;
                let mut row: Vec<String> = vec![rec.step.to_string(), csv::real(rec.t), node.to_string()];
                row.extend(x[..dim].iter().map(|&v| csv::real(v)));
                row.extend([nr.u_n, nr.u_t, nr.v_t, nr.p, nr.lambda, nr.friction].map(csv::real));
                row.push(nr.status.as_str().to_string());
                if dim == 3 {
                    row.extend(nr.v_t_vec.iter().chain(&nr.friction_vec).map(|&v| csv::real(v)));
                }
                row.push(csv::real(nr.bound));
                rows.push_str(&row.join(","));
                rows.push('\n');
            }
            // the frame's rows whole, or none of them
            w.append(rows.as_bytes())?;
        }
        if !rec.nodes.is_empty() {
            // as contact.csv holds them, which a resumed run reads back
            self.contact_frames.push((rec.step, rec.t, rec.nodes.iter().map(as_written).collect()));
        }
        let u = p.dofs.expand_dim(&state.u);
        let v = p.dofs.expand_dim(&state.v);
        let eps_zz = state.eps_zz.clone();
        self.wait()?;
        let name = format!("frames/frame_{:05}.vtu", rec.step);
        self.frames.push((rec.t, name.clone()));
        let (dir, mesh, material, frames) = (self.dir.clone(), Arc::clone(&self.mesh), p.material, self.frames.clone());
        self.pending = Some(std::thread::spawn(move || {
            let frame =
                vtu::Snapshot { mesh: &mesh, material: &material, u: &u, v: &v, contact: &contact, eps_zz: &eps_zz };
            write_atomic(&dir.join(&name), vtu::vtu(&frame).as_bytes())?;
            write_atomic(&dir.join("series.pvd"), vtu::pvd(&frames).as_bytes())
        }));
        Ok(())
    }

    /// Write the charts, then summary.json: a summary that says `completed` follows every
    /// output (a run killed or a disk full while the charts are written leaves `running`, and
    /// the caller writes `failed`).
    pub fn finish(&mut self, summary: &Summary, problem: &Problem, state: &State) -> Result<()> {
        self.wait()?;
        self.charts(problem, state)?;
        self.write_summary(summary)
    }

    /// Write only the summary (used when a run fails), after the frame in flight.
    pub fn write_summary(&mut self, summary: &Summary) -> Result<()> {
        let waited = self.wait();
        write_atomic(&self.dir.join("summary.json"), summary.to_json()?.as_bytes())?;
        waited
    }

    /// The last resort when summary.json cannot be replaced through a temporary file (a full
    /// disk has no room for a second copy): overwrite it where it is. Best effort: a run whose
    /// summary cannot be written at all still returns its error.
    pub fn write_summary_in_place(&mut self, summary: &Summary) {
        if let Ok(json) = summary.to_json() {
            let _ = std::fs::write(self.dir.join("summary.json"), json.as_bytes());
        }
    }

    /// Write plots/: energy.svg (the terms of (E.1) over its residual) and deformed.svg always; with contact, forces.svg,
    /// contact_status.svg and normal_stress.svg (stale ones of an earlier run are removed
    /// when the scene has no contact).
    fn charts(&self, p: &Problem, state: &State) -> Result<()> {
        use plots::Series;
        let save = |name: &str, svg: std::result::Result<String, String>| -> Result<()> {
            let file = format!("plots/{name}");
            let svg = svg.map_err(|e| Error::Output(format!("{file}: {e}")))?;
            write_atomic(&self.dir.join(&file), svg.as_bytes())
        };
        let s = |name: &str, f: fn(&ChartRow) -> f64| Series {
            name: name.into(),
            points: self.rows.iter().map(|r| (r.t, f(r))).collect(),
        };
        let terms = [
            s("kinetic", |r| r.kinetic),
            s("elastic", |r| r.elastic),
            s("compliance", |r| r.compliance),
            s("external work", |r| r.work),
            s("viscous dissipation", |r| r.viscous),
            s("friction dissipation", |r| r.friction),
            s("constraint dissipation", |r| r.constraint),
        ];
        let residual = [s("(E.1) residual", |r| r.residual)];
        let dim = p.mesh.dim();
        let (energy_axis, residual_axis) =
            (format!("energy [{}]", units::energy(dim)), format!("residual [{}]", units::energy(dim)));
        let energy = plots::stacked_chart(
            &[
                (
                    plots::Panel {
                        title: "Energy balance (E.1)",
                        x_desc: "t [s]",
                        y_desc: &energy_axis,
                        series: &terms,
                        hlines: &[],
                        log: (false, false),
                    },
                    2.0,
                ),
                (
                    plots::Panel {
                        title: "(E.1) residual per step",
                        x_desc: "t [s]",
                        y_desc: &residual_axis,
                        series: &residual,
                        hlines: &[],
                        log: (false, false),
                    },
                    1.0,
                ),
            ],
            // room above the data for the legend (it covered the first 0.12 s of the residual)
            &plots::Options { headroom: 0.4, ..plots::Options::default() },
        );
        save("energy.svg", energy)?;
        // the charts of the mesh and of Γ3 along its arc are 2-D (in 3-D, Γ3 is drawn as maps in its plane)
        if let Some(mesh) = p.mesh.plane() {
            let u: Vec<[f64; 2]> = p.dofs.expand_dim(&state.u).iter().map(|u| [u[0], u[1]]).collect();
            let foundation = p.contact.as_ref().map(|c| {
                let along = contact_charts::Along::of(mesh, c, &p.model.contact_sides);
                contact_charts::Foundation::of(mesh, c, &along)
            });
            save("deformed.svg", contact_charts::deformed(mesh, &u, p.time(state.n), foundation.as_ref()))?;
        }
        let Some(c) = &p.contact else {
            for stale in ["forces.svg", "contact_status.svg", "normal_stress.svg", "status_fractions.svg"] {
                let _ = std::fs::remove_file(self.dir.join("plots").join(stale));
            }
            return Ok(());
        };
        let p_g = contact_charts::p_at_bound(c);
        let gamma3: f64 = c.omega.iter().sum();
        // a friction law gives stick, slip and a tangential force; without one there are none
        let friction = c.friction.is_some();
        save("forces.svg", contact_charts::forces(&self.rows, p_g.map(|q| q * gamma3), dim, friction))?;
        save("status_fractions.svg", contact_charts::status_fractions(&self.contact_frames, friction))?;
        let Some(mesh) = p.mesh.plane() else {
            // 3-D: maps of Γ3 laid flat, each node's share of Γ3's faces coloured
            let Some(solid) = p.mesh.solid() else { return Ok(()) };
            let surface = contact_charts::FlatSurface::of(solid, c, &p.model.contact_sides);
            return save("contact_status.svg", contact_charts::status_maps(&self.contact_frames, &surface, friction));
        };
        let along = contact_charts::Along::of(mesh, c, &p.model.contact_sides);
        save("contact_status.svg", contact_charts::contact_status(&self.contact_frames, &along, friction))?;
        save("normal_stress.svg", contact_charts::normal_stress(&self.contact_frames, &along, p_g))
    }
}
