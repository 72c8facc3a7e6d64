//! The library's errors as Python exceptions: bad input → `dyncontact.SceneError` (a
//! `ValueError`, with `.key`), a solver that could not continue → `dyncontact.SolverError` (a
//! `RuntimeError`, with `.step`, `.time`, `.residuals`), a stopped run → `KeyboardInterrupt`,
//! a folder or an output that cannot be written → `OSError`. The message is the command line's
//! (`error: MESSAGE` without `error: `).

use dyncontact::Error;
use dyncontact::failure::{FailureKind, StepFailureCause};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The Python exception of a library error.
pub fn to_py(py: Python<'_>, e: &Error) -> PyErr {
    let message = e.to_string();
    let raised = match e.kind() {
        FailureKind::Input => python_error(py, "SceneError", |cls| cls.call1((message.clone(), e.key()))),
        FailureKind::Solver | FailureKind::NonFinite | FailureKind::LinearAlgebra => {
            python_error(py, "SolverError", |cls| {
                let residuals = PyDict::new(py);
                let (step, time) = match e {
                    Error::Solver(f) => {
                        residuals_of(&residuals, &f.cause)?;
                        (Some(f.step), Some(f.time))
                    }
                    _ => (None, None),
                };
                residuals.set_item("kind", e.kind().to_string())?;
                cls.call1((message.clone(), step, time, residuals))
            })
        }
        FailureKind::Interrupted => return PyKeyboardInterrupt::new_err(message),
        FailureKind::Folder | FailureKind::Output => return PyOSError::new_err(message),
        FailureKind::Internal => return PyRuntimeError::new_err(message),
    };
    raised.unwrap_or_else(|err| err)
}

/// A library result as a Python result.
pub fn py_result<T>(py: Python<'_>, r: dyncontact::Result<T>) -> PyResult<T> {
    r.map_err(|e| to_py(py, &e))
}

/// An instance of `dyncontact._errors.NAME` made by `make`, as the error to raise.
fn python_error<'py>(
    py: Python<'py>,
    name: &str,
    make: impl FnOnce(&Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>>,
) -> PyResult<PyErr> {
    let cls = py.import("dyncontact._errors")?.getattr(name)?;
    Ok(PyErr::from_value(make(&cls)?))
}

/// The residuals of a failed step: the inner solver's at its last iterate, or the (E.1) guard's.
fn residuals_of(d: &Bound<'_, PyDict>, cause: &StepFailureCause) -> PyResult<()> {
    match cause {
        StepFailureCause::Contact(c) => {
            d.set_item("solver", c.inner.solver())?;
            d.set_item("fixed_point_iteration", c.fixed_point_iteration)?;
            d.set_item("iterations", c.inner.iterations())?;
            d.set_item("inner_residual", c.inner.residual())?;
        }
        StepFailureCause::NonFinite { entry } => d.set_item("non_finite_entry", *entry)?,
        StepFailureCause::NonFiniteEnergy => d.set_item("non_finite_energy", true)?,
        StepFailureCause::EnergyBalance { relative, limit } => {
            d.set_item("energy_residual_relative", *relative)?;
            d.set_item("energy_residual_limit", *limit)?;
        }
    }
    Ok(())
}
