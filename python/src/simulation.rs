//! `dyncontact.Simulation`: the library's one time loop ([`Simulation::steps`]) driven from
//! Python, one step per `next()`, the GIL released during each step.

use std::mem::ManuallyDrop;
use std::ptr::NonNull;

use dyncontact::output::{HISTORY, csv};
use dyncontact::problem::Problem;
use dyncontact::simulation::{Simulation, StepRecord};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{py_result, to_py};
use crate::scene::PyScene;
use crate::vectors;

/// The time loop of a scene, step by step:
///
/// ```python
/// sim = dc.Simulation(scene)
/// for rec in sim.steps():      # steps 1..N (sim.initial_record() is t = 0)
///     rec.t, rec.u, rec.v, rec.normal_force
/// ```
///
/// The operators are assembled and factored when it is made. A failed step raises SolverError
/// and ends the loop.
#[pyclass(name = "Simulation", module = "dyncontact")]
pub struct PySimulation {
    /// borrows `*problem`: dropped first (see Drop)
    sim: ManuallyDrop<Simulation<'static>>,
    /// owned: made by Box::leak in `new`, freed in Drop after `sim`; never moved or mutated
    problem: NonNull<Problem>,
    failed: bool,
    /// the record of t = 0, made with the simulation (the state moves on with its steps)
    initial: Py<PyStepRecord>,
}

// SAFETY: the problem is owned by this object alone (leaked from a Box in `new`, freed in
// Drop) and only read through `sim`; Problem and Simulation are Send and Sync, so moving or
// sharing the pair across threads is as safe as moving or sharing a (Problem, Simulation).
unsafe impl Send for PySimulation {}
unsafe impl Sync for PySimulation {}

impl Drop for PySimulation {
    fn drop(&mut self) {
        // SAFETY: `sim` is dropped once, before the problem it borrows; the problem came from
        // Box::leak in `new` and is freed once.
        unsafe {
            ManuallyDrop::drop(&mut self.sim);
            drop(Box::from_raw(self.problem.as_ptr()));
        }
    }
}

impl PySimulation {
    fn problem(&self) -> &Problem {
        self.sim.problem
    }
}

// the SAFETY argument above, checked by the compiler
const _: fn() = || {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Problem>();
    send_sync::<Simulation<'static>>();
};

#[pymethods]
impl PySimulation {
    /// Build the problem of `scene` (a Scene, or the path of a scene file, as `run` takes) and
    /// its operators (assembly, the factorization of A_k, the Delassus operator), without the GIL.
    #[new]
    fn new(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<PySimulation> {
        let from_path;
        let held: PyRef<'_, PyScene> = match scene.extract::<PyRef<'_, PyScene>>() {
            Ok(s) => s,
            Err(_) => match scene.extract::<std::path::PathBuf>() {
                Ok(path) => {
                    from_path = Bound::new(py, PyScene::from_file(py, path)?)?;
                    from_path.borrow()
                }
                Err(_) => {
                    return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                        "scene: expected a dyncontact.Scene or the path of a scene file, got {}",
                        scene.get_type().name()?
                    )));
                }
            },
        };
        let scene: &PyScene = &held;
        let built = py.detach(|| -> dyncontact::Result<(&'static Problem, Simulation<'static>)> {
            let problem: &'static Problem = Box::leak(Box::new(scene.problem(None)?));
            match Simulation::new(problem) {
                Ok(sim) => Ok((problem, sim)),
                Err(e) => {
                    // SAFETY: nothing borrows the leaked problem any more
                    unsafe { drop(Box::from_raw(std::ptr::from_ref(problem).cast_mut())) };
                    Err(e)
                }
            }
        });
        let (problem, sim) = py_result(py, built)?;
        let initial = PyStepRecord::of(py, &sim.initial_record(), &sim).and_then(|r| Py::new(py, r));
        let initial = match initial {
            Ok(r) => r,
            Err(e) => {
                drop(sim);
                // SAFETY: `sim`, the only borrower of the leaked problem, is dropped
                unsafe { drop(Box::from_raw(std::ptr::from_ref(problem).cast_mut())) };
                return Err(e);
            }
        };
        Ok(PySimulation { sim: ManuallyDrop::new(sim), problem: NonNull::from(problem), failed: false, initial })
    }

    /// An iterator over the remaining steps, one StepRecord each (the library's
    /// `Simulation::steps`): it ends after the scene's last step; a failed step raises
    /// SolverError.
    fn steps(slf: Py<Self>) -> Steps {
        Steps { sim: slf }
    }

    /// The record of t = 0 (history.csv's first row), whatever steps were taken since.
    fn initial_record(&self, py: Python<'_>) -> Py<PyStepRecord> {
        self.initial.clone_ref(py)
    }

    /// Advance one step and return its record (None after the last step).
    fn step(&mut self, py: Python<'_>) -> PyResult<Option<PyStepRecord>> {
        if self.failed || self.sim.state.n >= self.problem().steps {
            return Ok(None);
        }
        let sim = &mut *self.sim;
        let rec = py.detach(|| sim.step());
        match rec {
            Ok(rec) => PyStepRecord::of(py, &rec, &self.sim).map(Some),
            Err(e) => {
                self.failed = true;
                Err(to_py(py, &e))
            }
        }
    }

    /// The number of steps completed.
    #[getter]
    fn step_index(&self) -> usize {
        self.sim.state.n
    }

    /// The scene's number of steps.
    #[getter]
    fn n_steps(&self) -> usize {
        self.problem().steps
    }

    /// The time of the current state.
    #[getter]
    fn t(&self) -> f64 {
        self.problem().time(self.sim.state.n)
    }

    /// The space dimension d.
    #[getter]
    fn dimension(&self) -> usize {
        self.problem().mesh.dim()
    }
}

/// The iterator of `Simulation.steps()`.
#[pyclass(module = "dyncontact")]
pub struct Steps {
    sim: Py<PySimulation>,
}

#[pymethods]
impl Steps {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&self, py: Python<'_>) -> PyResult<Option<PyStepRecord>> {
        self.sim.borrow_mut(py).step(py)
    }
}

/// One step of the time loop: its history.csv row and the state after it.
#[pyclass(name = "StepRecord", module = "dyncontact", frozen)]
pub struct PyStepRecord {
    #[pyo3(get)]
    step: usize,
    #[pyo3(get)]
    t: f64,
    /// total compressive force on Γ3 (per unit thickness in 2-D)
    #[pyo3(get)]
    normal_force: f64,
    #[pyo3(get)]
    tangential_force: f64,
    #[pyo3(get)]
    max_penetration: f64,
    /// nodal displacement and velocity, shape (nodes, d)
    #[pyo3(get)]
    u: Py<PyAny>,
    #[pyo3(get)]
    v: Py<PyAny>,
    row: Vec<f64>,
}

impl PyStepRecord {
    fn of(py: Python<'_>, rec: &StepRecord, sim: &Simulation) -> PyResult<PyStepRecord> {
        let p = sim.problem;
        let d = p.mesh.dim();
        let row = HISTORY.iter().map(|(_, value)| value(rec).value()).collect();
        Ok(PyStepRecord {
            step: rec.step,
            t: rec.t,
            // as history.csv holds them (a zero without its sign)
            normal_force: csv::as_written(rec.normal_force),
            tangential_force: csv::as_written(rec.tangential_force),
            max_penetration: csv::as_written(rec.max_penetration),
            u: vectors(py, &p.dofs.expand_dim(&sim.state.u), d).unbind(),
            v: vectors(py, &p.dofs.expand_dim(&sim.state.v), d).unbind(),
            row,
        })
    }
}

#[pymethods]
impl PyStepRecord {
    /// The step's history.csv row: {column: float}.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for ((name, _), x) in HISTORY.iter().zip(&self.row) {
            d.set_item(*name, *x)?;
        }
        Ok(d)
    }

    /// The (E.1) energy terms after the step: {kinetic, elastic, compliance, external_work,
    /// viscous_dissipation, friction_dissipation, constraint_dissipation,
    /// persistency_dissipation, energy_residual}.
    #[getter]
    fn energy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        const TERMS: [&str; 9] = [
            "kinetic",
            "elastic",
            "compliance",
            "external_work",
            "viscous_dissipation",
            "friction_dissipation",
            "constraint_dissipation",
            "persistency_dissipation",
            "energy_residual",
        ];
        let d = PyDict::new(py);
        for ((name, _), x) in HISTORY.iter().zip(&self.row) {
            if TERMS.contains(name) {
                d.set_item(*name, *x)?;
            }
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("StepRecord(step={}, t={}, normal_force={})", self.step, self.t, self.normal_force)
    }
}
