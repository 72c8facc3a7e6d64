//! `dyncontact.Scene`: a scene as the command line reads it — its text, where it came from and
//! its `--set` overrides — validated when it is made, so a bad key raises at once.

use std::path::{Path, PathBuf};

use dyncontact::output::ModelInfo;
use dyncontact::problem::Problem;
use dyncontact::resources;
use dyncontact::scene::{DEFAULT_SCENE, parse};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::py_result;
use crate::values;

/// What a pickled scene holds: its source text, label, folder and overrides.
type SceneState = (String, String, PathBuf, Vec<String>);

/// The label of the embedded default scene in messages and summary.json (the CLI's).
pub const EMBEDDED: &str = "<embedded academic scene>";

/// A dyncontact scene (the TOML scene of the README), validated.
///
/// Make one with `Scene.default()`, `Scene.from_file(path)`, `Scene.from_toml(text)` or
/// `Scene.from_dict(d)`; `scene.with_set({...})` returns a new scene with overrides applied by
/// the rules of `dyncontact run --set`. A scene is immutable.
#[pyclass(name = "Scene", module = "dyncontact", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyScene {
    /// the source text, as written
    text: String,
    /// the source, as messages name it (a path, or `<embedded academic scene>`)
    pub file: String,
    /// the folder relative paths in the scene are read from
    pub dir: PathBuf,
    /// the `--set KEY=VALUE` arguments, in order
    pub overrides: Vec<String>,
    /// the effective scene (overrides applied): what a run keeps as scene.toml
    pub effective: String,
    pub name: String,
}

impl PyScene {
    /// The scene as the base of a sweep or refinement: its source text, label and folder (the
    /// overrides are applied on top, as `--set`).
    pub fn base(&self) -> dyncontact::sweep::Base {
        dyncontact::sweep::Base { text: self.text.clone(), label: self.file.clone(), dir: self.dir.clone() }
    }

    /// Read `text` with `overrides` as the command line does, and validate the model.
    pub fn load(text: String, file: String, dir: PathBuf, overrides: Vec<String>) -> dyncontact::Result<PyScene> {
        let parsed = values::overrides(&overrides)?;
        let (scene, effective) = parse::load(&text, &file, &parsed, &dir)?;
        scene.validate()?;
        Ok(PyScene { text, file, dir, overrides, effective, name: scene.name })
    }

    /// The model and its discrete problem, refused (as `dyncontact run` refuses it) when it
    /// would not fit in this machine's memory or a load is not finite at a time a step samples
    /// it; `out`, when given, must have room for the outputs.
    pub fn problem(&self, out: Option<&Path>) -> dyncontact::Result<Problem> {
        let model = dyncontact::scene::Scene::from_toml(&self.effective, &self.file)?.validate()?;
        let estimate = resources::estimate(&model, &self.dir)?;
        resources::check_fits(&estimate, resources::available_memory())?;
        if let Some(out) = out {
            dyncontact::output::folder::check_target(out)?;
            resources::check_disk(&estimate, out)?;
        }
        // refused before any step, as `dyncontact run` refuses it
        let problem = Problem::new(model, &self.dir)?;
        problem.check_load_times()?;
        Ok(problem)
    }

    fn from_text(py: Python<'_>, text: String, file: String, dir: Option<PathBuf>) -> PyResult<PyScene> {
        let dir = dir.unwrap_or_else(|| PathBuf::from("."));
        py_result(py, PyScene::load(text, file, dir, Vec::new()))
    }
}

#[pymethods]
impl PyScene {
    /// Pickling (multiprocessing, concurrent.futures): a scene is its source text, label,
    /// folder and overrides, and is made again from them (validated again).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, SceneState)> {
        let restore = py.get_type::<PyScene>().getattr("_restore")?;
        Ok((restore, (self.text.clone(), self.file.clone(), self.dir.clone(), self.overrides.clone())))
    }

    /// The inverse of `__reduce__`.
    #[staticmethod]
    fn _restore(py: Python<'_>, text: String, file: String, dir: PathBuf, overrides: Vec<String>) -> PyResult<PyScene> {
        py_result(py, PyScene::load(text, file, dir, overrides))
    }

    /// The embedded default scene (`academic`): what `dyncontact run` runs without a scene.
    #[staticmethod]
    fn default(py: Python<'_>) -> PyResult<PyScene> {
        PyScene::from_text(py, DEFAULT_SCENE.to_string(), EMBEDDED.to_string(), None)
    }

    /// A scene file (TOML); relative paths in it (a Gmsh mesh) are read from its folder.
    #[staticmethod]
    pub(crate) fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        let text =
            std::fs::read_to_string(&path).map_err(|e| crate::errors::to_py(py, &dyncontact::Error::read(&path, e)));
        let dir = path.parent().map(Path::to_path_buf).filter(|d| !d.as_os_str().is_empty());
        PyScene::from_text(py, text?, path.display().to_string(), dir)
    }

    /// A scene from TOML text; `name` names it in messages, relative paths are read from `dir`
    /// (default: the current folder).
    #[staticmethod]
    #[pyo3(signature = (text, name = "<toml>".to_string(), dir = None))]
    fn from_toml(py: Python<'_>, text: String, name: String, dir: Option<PathBuf>) -> PyResult<PyScene> {
        PyScene::from_text(py, text, name, dir)
    }

    /// A scene from a dict of the scene file's tables ({"domain": {...}, "material": {...}, ...});
    /// relative paths are read from `dir` (default: the current folder).
    #[staticmethod]
    #[pyo3(signature = (d, dir = None))]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyDict>, dir: Option<PathBuf>) -> PyResult<PyScene> {
        let table = values::table(d, "")?;
        if let Some(key) = dotted_key(&table, "") {
            return py_result(
                py,
                Err(dyncontact::Error::scene(
                    key,
                    "a dotted key in a scene dict: nest it as tables ({\"contact\": {\"compliance\": 2000.0}}), or give it to with_set",
                )),
            );
        }
        let text = toml::to_string(&table)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("the dict is not a TOML table: {e}")))?;
        PyScene::from_text(py, text, "<dict>".to_string(), dir)
    }

    /// A new scene with overrides, by the rules of `dyncontact run --set KEY=VALUE`: `values` is
    /// a dict {"contact.compliance": 2000.0, "domain.cells": [64, 32], ...} (a str value is the
    /// text after `=` as typed on the command line, read as TOML or else as a string) or a list
    /// of "KEY=VALUE" strings. Raises SceneError naming the key, with the command line's message.
    fn with_set(&self, py: Python<'_>, values: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        let mut overrides = self.overrides.clone();
        overrides.extend(values::set_arguments(values)?);
        py_result(py, PyScene::load(self.text.clone(), self.file.clone(), self.dir.clone(), overrides))
    }

    /// Validate the scene and build its problem without solving, as `dyncontact check` does.
    /// Returns a dict: `name`, `dimension`, the sizes (`nodes`, `triangles`, `tetrahedra`,
    /// `velocity_unknowns`, `contact_nodes`, ...), `steps`, `step`, the (C.k) limit
    /// (`ck_step_limit`, `ck_limiting_node`, `ck_note`), `memory_estimate_bytes`,
    /// `output_estimate_bytes`, `fits` (False when `run` would refuse it for memory: then the
    /// estimate's sizes, `refused`, and no (C.k) limit), `lines` (what `dyncontact check` prints) and
    /// `warnings`. A time-dependent load that is not finite at a time a step samples it raises
    /// the scene error `dyncontact check` gives.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let model =
            py_result(py, dyncontact::scene::Scene::from_toml(&self.effective, &self.file).and_then(|s| s.validate()))?;
        let estimate = py_result(py, resources::estimate(&model, &self.dir))?;
        let d = PyDict::new(py);
        d.set_item("name", &model.name)?;
        // whole bytes (the estimates are reals)
        d.set_item("memory_estimate_bytes", estimate.total().round() as u64)?;
        d.set_item("output_estimate_bytes", estimate.outputs.total().round() as u64)?;
        if let Err(e) = resources::check_fits(&estimate, resources::available_memory()) {
            d.set_item("dimension", estimate.dim)?;
            // the sizes the estimate counted without building the mesh (upper bounds where the
            // clamped and contact sides are not resolved); (C.k) needs the contact nodes'
            // masses, which only the assembly gives
            d.set_item("nodes", estimate.nodes)?;
            let (triangles, tetrahedra) =
                if estimate.dim == 3 { (0, estimate.triangles) } else { (estimate.triangles, 0) };
            d.set_item("triangles", triangles)?;
            d.set_item("tetrahedra", tetrahedra)?;
            d.set_item("velocity_unknowns", estimate.unknowns)?;
            d.set_item("contact_nodes", estimate.contact_nodes)?;
            d.set_item("steps", model.time.steps)?;
            d.set_item("step", model.time.step)?;
            d.set_item("ck_step_limit", py.None())?;
            d.set_item("ck_limiting_node", py.None())?;
            d.set_item("ck_note", "not computed: the scene does not fit in the memory available")?;
            d.set_item("fits", false)?;
            d.set_item("warnings", &model.warnings)?;
            d.set_item("refused", e.to_string())?;
            d.set_item("lines", estimate.lines())?;
            return Ok(d);
        }
        let problem = py.detach(|| {
            Problem::new(model, &self.dir).and_then(|p| {
                let scan = p.check_load_times()?;
                Ok((p, scan))
            })
        });
        let (problem, scan) = py_result(py, problem)?;
        let info = ModelInfo::of(&problem);
        let json =
            serde_json::to_string(&info).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        let fields = py.import("json")?.call_method1("loads", (json,))?;
        d.call_method1("update", (fields,))?;
        d.set_item("dimension", info.dim)?;
        d.set_item("fits", true)?;
        d.set_item("lines", info.lines().into_iter().chain(estimate.lines()).chain(scan.line()).collect::<Vec<_>>())?;
        d.set_item("warnings", scan.warning().into_iter().chain(info.warnings()).collect::<Vec<_>>())?;
        Ok(d)
    }

    /// The scene's name (`[scene] name`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// Where the scene came from: its file, `<embedded academic scene>`, `<toml>` or `<dict>`.
    #[getter]
    fn source(&self) -> &str {
        &self.file
    }

    /// The overrides applied, as `--set KEY=VALUE` arguments in order.
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.overrides.clone()
    }

    /// The effective scene as TOML (overrides applied, a relative mesh path made absolute): the
    /// scene.toml a run writes.
    fn to_toml(&self) -> &str {
        &self.effective
    }

    fn __repr__(&self) -> String {
        let set = if self.overrides.is_empty() { String::new() } else { format!(", set={:?}", self.overrides) };
        format!("Scene({:?} from {}{set})", self.name, self.file)
    }
}

/// The first key of `t` (a path below `at`) that holds a dot: a `with_set` key given to
/// `from_dict`, where keys are table names (no scene key has a dot).
fn dotted_key(t: &toml::Table, at: &str) -> Option<String> {
    t.iter().find_map(|(k, v)| {
        let here = if at.is_empty() { k.clone() } else { format!("{at}.{k}") };
        match v {
            _ if k.contains('.') => Some(here),
            toml::Value::Table(inner) => dotted_key(inner, &here),
            _ => None,
        }
    })
}
