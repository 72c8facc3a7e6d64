//! Python values as TOML: a dict as a scene or sweep table, a dict of overrides as `--set`
//! arguments.

use dyncontact::overrides::Override;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A Python value as a TOML value: bool, int, float, str, dict (a table, string keys), list or
/// tuple (an array). `at` names the value in the error.
pub fn to_toml(v: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    // numpy arrays and scalars (np.int64, np.bool_, a size-1 array): the plain Python values
    // `tolist` gives, before any scalar conversion reads a size-1 array as its element
    let builtin = v.is_instance_of::<PyBool>()
        || v.is_instance_of::<PyString>()
        || v.is_instance_of::<PyFloat>()
        || v.is_instance_of::<PyInt>()
        || v.is_instance_of::<PyDict>()
        || v.is_instance_of::<PyList>()
        || v.is_instance_of::<PyTuple>();
    if !builtin
        && v.hasattr("tolist")?
        && let Ok(plain) = v.call_method0("tolist")
        && !plain.is(v)
    {
        return to_toml(&plain, at);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(table(d, at)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v.try_iter()?.enumerate().map(|(k, x)| to_toml(&x?, &format!("{at}[{k}]")));
        return Ok(toml::Value::Array(items.collect::<PyResult<_>>()?));
    }
    Err(PyTypeError::new_err(format!(
        "{at}: a {} is not a TOML value (give a bool, int, float, str, list or dict)",
        v.get_type().name()?
    )))
}

/// A dict with string keys as a TOML table.
pub fn table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k.extract().map_err(|_| PyTypeError::new_err(format!("{at}: keys must be strings")))?;
        let here = if at.is_empty() { key.clone() } else { format!("{at}.{key}") };
        t.insert(key, to_toml(&v, &here)?);
    }
    Ok(t)
}

/// Overrides as the `--set KEY=VALUE` arguments they are: a dict {KEY: VALUE} (a str value is
/// the text after `=`, exactly as typed on the command line; any other value is written as TOML
/// first) or a list of "KEY=VALUE" strings.
pub fn set_arguments(values: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(d) = values.cast::<PyDict>() {
        let mut args = Vec::new();
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| PyTypeError::new_err("with_set: keys must be strings"))?;
            let text = if v.is_instance_of::<PyString>() { v.extract()? } else { text_of(&to_toml(&v, &key)?) };
            args.push(format!("{key}={text}"));
        }
        return Ok(args);
    }
    if values.is_instance_of::<PyString>() {
        return Ok(vec![values.extract()?]);
    }
    values.try_iter()?.map(|a| a?.extract::<String>()).collect()
}

/// A TOML value as `--set` text, its floats in the shortest text that reads back as the same
/// f64 (1e300, not 301 digits; valid TOML for every f64, `nan` for NaN).
fn text_of(value: &toml::Value) -> String {
    match value {
        toml::Value::Float(x) if x.is_nan() => "nan".to_string(),
        toml::Value::Float(x) => format!("{x:?}"),
        toml::Value::Array(items) => format!("[{}]", items.iter().map(text_of).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

/// `--set` arguments parsed as the command line parses them.
pub fn overrides(args: &[String]) -> dyncontact::Result<Vec<Override>> {
    args.iter().map(|a| Override::parse(a)).collect()
}
