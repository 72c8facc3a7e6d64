//! Criterion benches of the hot kernels of dyncontact (`cargo bench -p xtask --bench kernels`):
//! the assembly of M, K, C at two mesh sizes, one time step of the academic scene and the
//! contact solve of one step (the frozen-S Newton of N.1–N.3 on the condensed contact DOFs).
//! Steps are measured from a state in the stick–slip phase (t = 0.25 s), where the contact
//! solve has work to do.

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use dyncontact::fem::Operators;
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;
use dyncontact::simulation::State;
use dyncontact::step::delassus::DelassusFactors;
use dyncontact::step::fixed_point::Inner;
use dyncontact::step::newton::{self, NewtonSettings};

/// The academic scene on `cells`, built into a problem.
fn academic(cells: [i64; 2]) -> Problem {
    let mut s = Scene::default_scene();
    s.domain.cells = Some(cells.to_vec());
    s.validate().expect("valid scene");
    Problem::from_scene(&s, Path::new(".")).expect("problem")
}

/// Assembly of the operators M, K, C on the free DOFs (`Operators::new`): the setup cost that
/// grows with the mesh.
fn assembly(c: &mut Criterion) {
    let mut g = c.benchmark_group("assembly");
    for cells in [[32, 16], [128, 64]] {
        let p = academic(cells);
        let nodes: Vec<usize> = p.contact.as_ref().map(|c| c.nodes.clone()).unwrap_or_default();
        g.bench_function(format!("operators {}x{}", cells[0], cells[1]), |b| {
            b.iter(|| {
                Operators::new(&p.mesh, &p.material, p.model.solver.mass, &p.dofs, black_box(&nodes)).expect("assembly")
            })
        });
    }
    g.finish();
}

/// A simulation of the academic scene (32×16, k = 5e-4) advanced to t = 0.25 s.
fn advanced(p: &Problem) -> Simulation<'_> {
    let mut sim = Simulation::new(p).expect("setup");
    for rec in sim.steps().take(500) {
        rec.expect("step");
    }
    sim
}

/// One time step of the academic scene (free solve, F.1 with Newton, recovery, energy), always
/// from the same state: a copy of it is made outside the timing and moved in.
fn time_step(c: &mut Criterion) {
    let p = academic([32, 16]);
    let base = advanced(&p);
    let mut sim = Simulation::new(&p).expect("setup");
    c.bench_function("time step academic 32x16", |b| {
        b.iter_batched(
            || base.state.clone(),
            |state: State| {
                sim.restore(state).expect("restore");
                sim.step().expect("step")
            },
            BatchSize::SmallInput,
        )
    });
}

/// The contact solve of one step: one frozen-S Newton solve (`newton::solve`) on the step's
/// condensed data, with S the bound F.1 converged to (the last convex problem of the step).
fn contact_solve(c: &mut Criterion) {
    let p = academic([32, 16]);
    let sim = advanced(&p);
    let contact = p.contact.as_ref().expect("contact");
    let (w, _) = sim.free_velocity();
    let (data, p_hat) = sim.step_data(contact.restrict(&w)).expect("step data");
    let set = NewtonSettings::default();
    let mut factors = DelassusFactors::default();
    let (_, s, _) = sim.solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::Newton(set), None).expect("F.1");
    c.bench_function(&format!("newton::solve {} contact nodes", data.n()), |b| {
        b.iter(|| {
            newton::solve(black_box(&data), &mut factors, &s, &sim.state.lambda, &sim.state.t_fric, &set)
                .expect("newton")
        })
    });
}

criterion_group! {
    name = kernels;
    config = Criterion::default().sample_size(20);
    targets = assembly, time_step, contact_solve
}
criterion_main!(kernels);
