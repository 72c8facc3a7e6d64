//! What `dc.run(scene, out=None)` keeps in memory instead of writing a folder: history.csv's
//! columns (the values [`dyncontact::output::HISTORY`] gives the CSV writer, so the f64s the CLI
//! prints), contact.csv's columns and the stored frames, at the steps the writer stores them.

use dyncontact::output::vtu::{self, NodeContact};
use dyncontact::output::{HISTORY, contact_columns, csv};
use dyncontact::problem::Problem;
use dyncontact::simulation::{State, StepRecord};

/// A contact.csv value: a number or a status.
pub enum ContactColumn {
    Numbers(Vec<f64>),
    Statuses(Vec<String>),
}

/// One stored frame: the VTU frame's fields.
pub struct Frame {
    pub step: usize,
    pub t: f64,
    /// nodal displacement and velocity, 3 components (z = 0 in 2-D)
    pub u: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
    pub contact: Vec<NodeContact>,
    /// 6 values per cell (VTK's order)
    pub stress: Vec<f64>,
}

/// The run's tables and frames.
pub struct Collected {
    /// HISTORY's columns, in its order
    pub history: Vec<Vec<f64>>,
    /// contact.csv's columns, in its order
    pub contact: Vec<(String, ContactColumn)>,
    pub frames: Vec<Frame>,
}

impl Collected {
    pub fn new(problem: &Problem) -> Collected {
        let contact = contact_columns(problem.mesh.dim())
            .split(',')
            .map(|name| {
                let col = if name == "status" {
                    ContactColumn::Statuses(Vec::new())
                } else {
                    ContactColumn::Numbers(Vec::new())
                };
                (name.to_string(), col)
            })
            .collect();
        Collected { history: vec![Vec::new(); HISTORY.len()], contact, frames: Vec::new() }
    }

    /// Record a step as the run folder's writer does: a history row always; contact rows and a
    /// frame every `output.every` steps and at the last step (none when `every` is 0).
    pub fn record(&mut self, rec: &StepRecord, problem: &Problem, state: &State) {
        for (col, (_, value)) in self.history.iter_mut().zip(HISTORY.iter()) {
            col.push(value(rec).value());
        }
        let every = problem.model.output_every;
        if every == 0 || !(rec.step.is_multiple_of(every) || rec.step == problem.steps) {
            return;
        }
        let mut contact = vec![NodeContact::OFF; problem.mesh.n_nodes()];
        if let Some(c) = &problem.contact {
            for (i, nr) in rec.nodes.iter().enumerate() {
                let node = c.nodes[i];
                contact[node] = NodeContact::of(nr);
                let x = problem.mesh.point(node);
                for (name, col) in &mut self.contact {
                    match col {
                        ContactColumn::Statuses(s) => s.push(nr.status.as_str().to_string()),
                        // as contact.csv holds them: a zero without its sign
                        ContactColumn::Numbers(n) => n.push(csv::as_written(match name.as_str() {
                            "step" => rec.step as f64,
                            "t" => rec.t,
                            "node" => node as f64,
                            "x" => x[0],
                            "y" => x[1],
                            "z" => x[2],
                            "u_n" => nr.u_n,
                            "u_t" => nr.u_t,
                            "v_t" => nr.v_t,
                            "p" => nr.p,
                            "lambda" => nr.lambda,
                            "friction" => nr.friction,
                            "v_tx" => nr.v_t_vec[0],
                            "v_ty" => nr.v_t_vec[1],
                            "v_tz" => nr.v_t_vec[2],
                            "friction_x" => nr.friction_vec[0],
                            "friction_y" => nr.friction_vec[1],
                            "friction_z" => nr.friction_vec[2],
                            "friction_bound" => nr.bound,
                            other => unreachable!("contact.csv column {other} has no value here: add it"),
                        })),
                    }
                }
            }
        }
        let u = problem.dofs.expand_dim(&state.u);
        let v = problem.dofs.expand_dim(&state.v);
        let stress = vtu::stress(&vtu::Snapshot {
            mesh: &problem.mesh,
            material: &problem.material,
            u: &u,
            v: &v,
            contact: &contact,
            eps_zz: &state.eps_zz,
        });
        self.frames.push(Frame { step: rec.step, t: rec.t, u, v, contact, stress });
    }
}
