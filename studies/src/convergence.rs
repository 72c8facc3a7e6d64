//! Convergence of the academic scene under joint refinement of h and k against a finer
//! reference (no exact solution exists): the trajectory a run leaves (contact forces per step,
//! displacements at probe nodes), the error measures between trajectories (force per step,
//! impulse over windows, displacement), and the study itself. The benchmark (`bench`) measures
//! its work–precision chart with the same runs and measures.

use std::path::Path;
use std::time::Instant;

use dyncontact::error::{Error, Result};
use dyncontact::model::kinds::SchemeKind;
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;

/// Material points (x, y) where displacements are compared: nodes of every nested rectangle mesh
/// (right corners, bottom and top midpoints, centre; the left corners are clamped).
pub const PROBES: [[f64; 2]; 5] = [[2.0, 0.0], [1.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 0.5]];

/// One level of joint refinement: the mesh and the time step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Level {
    pub cells: [i64; 2],
    pub k: f64,
}

/// The four joint levels [8,4]/2e-3 … [64,32]/2.5e-4, truncated to `n`.
pub(super) fn joint_levels(n: usize) -> Vec<Level> {
    (0..n).map(|l| Level { cells: [8 << l, 4 << l], k: 2e-3 / f64::from(1u32 << l) }).collect()
}

/// What one run leaves for the error measures: per step the contact forces (F_ν, F_τ) and the
/// probe displacements at t_{n+1} ([ux, uy] per probe, flattened).
#[derive(Debug, Clone, Default)]
pub(super) struct Trajectory {
    pub k: f64,
    pub forces: Vec<[f64; 2]>,
    pub probes: Vec<Vec<f64>>,
}

/// Work and solver facts of one run.
#[derive(Debug, Clone, Default)]
pub(super) struct RunStats {
    pub steps: usize,
    /// Simulation::new (assembly, factorization, Delassus) plus the time loop
    pub wall_time_s: f64,
    /// the time loop alone
    pub step_time_s: f64,
    /// Σ of the contact solve time (F.1 included) over the steps
    pub contact_time_s: f64,
    pub setup_delassus_s: f64,
    pub newton_iterations: usize,
    pub fixed_point_iterations: usize,
    pub unfrozen: usize,
    pub fallbacks: usize,
    /// two A_k solves (free + recovery) with this run's factor
    pub floor_s: f64,
    /// Newton-matrix factorizations computed and reused (the reduced system's cache)
    pub factorizations: usize,
    pub factor_reuses: usize,
}

/// The free-DOF indices of [ux, uy] at each probe point (None where clamped).
pub(super) fn probe_dofs(p: &Problem) -> Result<Vec<[Option<usize>; 2]>> {
    let tol = 1e-9 * p.mesh.bbox_diameter();
    PROBES
        .iter()
        .map(|x| {
            let node = (0..p.mesh.n_nodes())
                .map(|i| p.mesh.point(i))
                .position(|y| (y[0] - x[0]).abs() <= tol && (y[1] - x[1]).abs() <= tol && y[2] == 0.0);
            let node = node.ok_or_else(|| {
                Error::Study(format!("bench: the probe point ({}, {}) is not a mesh node", x[0], x[1]))
            })?;
            Ok([p.dofs.map[2 * node], p.dofs.map[2 * node + 1]])
        })
        .collect()
}

/// The floor of one step: two sparse triangular-solve pairs (free solve + recovery) with the
/// run's own factor of A_k; the best of 5 batches of the mean time per solve (robust to other
/// processes on the machine).
pub(super) fn floor_time(sim: &Simulation) -> f64 {
    let base: Vec<f64> = (0..sim.state.u.len()).map(|i| 1.0 + (i % 7) as f64).collect();
    let mut x = base.clone();
    let clock = Instant::now();
    sim.stepper.solve_in_place(&mut x);
    let once = clock.elapsed().as_secs_f64().max(1e-7);
    let reps = ((0.01 / once) as usize).clamp(3, 5000);
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let clock = Instant::now();
        for _ in 0..reps {
            x.copy_from_slice(&base);
            sim.stepper.solve_in_place(&mut x);
        }
        best = best.min(clock.elapsed().as_secs_f64() / reps as f64);
    }
    2.0 * best
}

/// Run a problem to its end, recording the trajectory at `probes` and the work done; the
/// recording is outside the timed parts.
pub(super) fn simulate(p: &Problem, probes: &[[Option<usize>; 2]]) -> Result<(Trajectory, RunStats)> {
    let clock = Instant::now();
    let mut sim = Simulation::new(p)?;
    let setup = clock.elapsed().as_secs_f64();
    let mut traj = Trajectory { k: p.k, forces: Vec::with_capacity(p.steps), probes: Vec::with_capacity(p.steps) };
    let mut st = RunStats { steps: p.steps, setup_delassus_s: sim.setup_timing.delassus, ..RunStats::default() };
    let mut steps = sim.steps();
    loop {
        let clock = Instant::now();
        let Some(rec) = steps.next() else { break };
        let rec = rec?;
        st.step_time_s += clock.elapsed().as_secs_f64();
        st.contact_time_s += rec.timing.contact_solve;
        st.newton_iterations += rec.report.inner_iterations;
        st.fixed_point_iterations += rec.report.fixed_point_iterations;
        st.unfrozen += usize::from(rec.report.unfrozen);
        st.fallbacks += usize::from(rec.report.fallback.is_some());
        traj.forces.push([rec.normal_force, rec.tangential_force]);
        let u = &steps.simulation().state.u;
        traj.probes.push(probes.iter().flat_map(|d| d.map(|i| i.map_or(0.0, |i| u[i]))).collect());
    }
    st.wall_time_s = setup + st.step_time_s;
    st.floor_s = floor_time(&sim);
    (st.factorizations, st.factor_reuses) = sim.delassus_factors.counts();
    Ok((traj, st))
}

/// How many steps of length `k` make the span `span` (an integer for nested levels).
pub(super) fn steps_in(span: f64, k: f64) -> Result<usize> {
    let r = span / k;
    let n = r.round() as usize;
    (n >= 1 && (r - n as f64).abs() <= 1e-9 * r)
        .then_some(n)
        .ok_or_else(|| Error::Study(format!("bench: {span} is not a whole number of steps k = {k}")))
}

/// How many reference steps make one step of `run`, checking the reference covers the run.
pub(super) fn step_ratio(run: &Trajectory, reference: &Trajectory) -> Result<usize> {
    let n = steps_in(run.k, reference.k)?;
    (run.forces.len() * n <= reference.forces.len()).then_some(n).ok_or_else(|| {
        Error::Study(format!("bench: the reference (k = {}) is shorter than the run (k = {})", reference.k, run.k))
    })
}

/// Means of a force history over consecutive windows of `m` steps (a trailing partial window is dropped).
pub(super) fn window_means(forces: &[[f64; 2]], m: usize) -> Vec<[f64; 2]> {
    forces
        .chunks_exact(m.max(1))
        .map(|w| [0, 1].map(|c| w.iter().map(|f| f[c]).sum::<f64>() / w.len() as f64))
        .collect()
}

/// Relative L² distances of a force history from a reference one on the same time grid (the
/// common length): [vector (F_ν, F_τ), F_ν, F_τ].
pub(super) fn relative_l2(run: &[[f64; 2]], reference: &[[f64; 2]]) -> [f64; 3] {
    let (mut diff, mut norm) = ([0.0; 2], [0.0; 2]);
    for (f, g) in run.iter().zip(reference) {
        for c in 0..2 {
            diff[c] += (f[c] - g[c]).powi(2);
            norm[c] += g[c] * g[c];
        }
    }
    let rel = |d: f64, n: f64| if n > 0.0 { (d / n).sqrt() } else { f64::NAN };
    [rel(diff[0] + diff[1], norm[0] + norm[1]), rel(diff[0], norm[0]), rel(diff[1], norm[1])]
}

/// Relative L²(0, T) errors of the force history at the run's own resolution [vector, F_ν, F_τ]:
/// each step's force is its mean over the step, compared with the reference's mean over the
/// same step. Step-to-step chatter of the run counts in full (a strong measure).
pub(super) fn force_errors(run: &Trajectory, reference: &Trajectory) -> Result<[f64; 3]> {
    let r = step_ratio(run, reference)?;
    Ok(relative_l2(&run.forces, &window_means(&reference.forces, r)))
}

/// Relative L²(0, T) error of the contact impulses over fixed windows of length `window` (the
/// coarsest step): the force vector averaged over each window, for run and reference alike. A
/// weak measure: chatter within a window averages out, as a time-averaged reading of the force.
pub(super) fn impulse_error(run: &Trajectory, reference: &Trajectory, window: f64) -> Result<f64> {
    step_ratio(run, reference)?;
    let (a, b) = (
        window_means(&run.forces, steps_in(window, run.k)?),
        window_means(&reference.forces, steps_in(window, reference.k)?),
    );
    Ok(relative_l2(&a, &b)[0])
}

/// Relative L²(0, T) error of the displacement at the probe points, at the run's step times.
pub(super) fn displacement_error(run: &Trajectory, reference: &Trajectory) -> Result<f64> {
    let r = step_ratio(run, reference)?;
    let (mut diff, mut norm) = (0.0, 0.0);
    for (n, u) in run.probes.iter().enumerate() {
        let u_ref = &reference.probes[(n + 1) * r - 1];
        diff += u.iter().zip(u_ref).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        norm += u_ref.iter().map(|b| b * b).sum::<f64>();
    }
    Ok(if norm > 0.0 { (diff / norm).sqrt() } else { f64::NAN })
}

/// One level of the convergence study.
#[derive(Debug, Clone, Copy)]
pub struct ConvergenceRow {
    pub cells: [i64; 2],
    pub k: f64,
    /// relative L²(0, T) errors: force history per step, impulses over 2e-3 s windows,
    /// displacement at the probe nodes
    pub error_force: f64,
    pub error_impulse: f64,
    pub error_disp: f64,
}

/// The convergence study of the academic scene for one scheme (midpoint, newton, lumped by
/// default): `levels` joint levels from 8×4 / 2e-3 (h and k halved together) against a
/// reference one level finer, over (0, `t_end`).
pub fn convergence(scheme: SchemeKind, levels: usize, t_end: f64) -> Result<Vec<ConvergenceRow>> {
    let all = joint_levels(levels + 1);
    let (runs, reference) = all.split_at(levels);
    let build = |l: &Level| -> Result<(Problem, Vec<[Option<usize>; 2]>)> {
        let mut s = Scene::default_scene();
        s.domain.cells = Some(l.cells.to_vec());
        s.time.step = l.k;
        s.time.end = t_end;
        s.time.scheme = scheme;
        let p = Problem::from_scene(&s, Path::new("."))?;
        let probes = probe_dofs(&p)?;
        Ok((p, probes))
    };
    let (p_ref, probes_ref) = build(&reference[0])?;
    let (traj_ref, _) = simulate(&p_ref, &probes_ref)?;
    let window = joint_levels(1)[0].k;
    runs.iter()
        .map(|l| {
            let (p, probes) = build(l)?;
            let (traj, _) = simulate(&p, &probes)?;
            Ok(ConvergenceRow {
                cells: l.cells,
                k: l.k,
                error_force: force_errors(&traj, &traj_ref)?[0],
                error_impulse: impulse_error(&traj, &traj_ref, window)?,
                error_disp: displacement_error(&traj, &traj_ref)?,
            })
        })
        .collect()
}
