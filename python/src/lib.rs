//! `irtp._irtp`: the Rust side of the Python package `irtp`, a thin layer
//! over [`irtp_app`] and [`irtp_paper`]. Python keywords become the equivalent `irtp` command
//! line ([`irtp_app::keywords`]), which the CLI's own definitions parse; the command runs
//! off the Python thread (`runner`); the [`irtp_app::Outcome`] comes back
//! as a dict whose tables are numpy arrays (each column's buffer is moved
//! into its array, not copied). The pure-Python layer (`python/irtp/`)
//! builds the public functions, result objects and progress bars on it.

mod runner;

use irtp::model::Drag;
use irtp::DragLaw;
use irtp_app::keywords::{self as argv, Value, Vocabulary};
use irtp_app::Outcome;
use irtp_paper::Cli;
use numpy::PyArray1;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

pyo3::create_exception!(
    _irtp,
    NumericalError,
    PyRuntimeError,
    "A numerical method failed to produce a trustworthy answer (it is refused, never returned)."
);

/// The keyword name of a library parameter or CLI flag (`--t-max` → `t_max`).
fn keyword(name: &str) -> String {
    name.trim_start_matches('-').replace('-', "_")
}

/// A library error as the Python exception the package documents; flags
/// named in a message read as keywords.
fn to_pyerr(command: &str, e: irtp::Error) -> PyErr {
    match &e {
        irtp::Error::InvalidParameter { .. }
        | irtp::Error::Unsupported { .. }
        | irtp::Error::TooCostly { .. } => {
            let msg = e.message_with(keyword);
            PyValueError::new_err(argv::flags_to_keywords::<Cli>(command, &msg))
        }
        irtp::Error::Interrupted => PyKeyboardInterrupt::new_err(e.to_string()),
        irtp::Error::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => NumericalError::new_err(e.to_string()),
    }
}

/// A JSON value as Python objects (through `json.loads`, which parses
/// numbers correctly rounded: the floats are the CLI's, bit for bit).
fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A Python keyword value.
fn value(v: &Bound<'_, PyAny>, name: &str) -> PyResult<Value> {
    if let Ok(b) = v.cast::<pyo3::types::PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(i) = v.extract::<i128>() {
        return Ok(Value::Int(i));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Value::Float(x));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Value::Str(s.extract::<String>()?));
    }
    if let Ok(l) = v.cast::<PyList>() {
        return Ok(Value::List(l.extract::<Vec<String>>()?));
    }
    let os = v.py().import("os")?;
    match os.call_method1("fspath", (v,)) {
        Ok(p) => Ok(Value::Str(p.extract::<String>()?)),
        Err(_) => Err(PyValueError::new_err(format!(
            "invalid {name}: a {} is not a number, string or path",
            v.get_type().name()?
        ))),
    }
}

/// The outcome as the dict the Python layer wraps.
fn outcome_to_py<'py>(py: Python<'py>, outcome: Outcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("command", outcome.command)?;
    d.set_item("provenance", json_to_py(py, &outcome.provenance)?)?;
    let (out, files) = match &outcome.written {
        Some((dir, files)) => {
            let f: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
            (Some(dir.display().to_string()), Some(f))
        }
        None => (None, None),
    };
    d.set_item("out", out)?;
    d.set_item("files", files)?;
    let o = outcome.results;
    d.set_item("method", &o.method)?;
    d.set_item("seed", o.seed)?;
    d.set_item("summary", json_to_py(py, &o.json)?)?;
    d.set_item("parameters", json_to_py(py, &o.parameters)?)?;
    d.set_item("text", &o.text)?;
    d.set_item("wall_time_s", o.wall_time_s)?;
    let tables = PyDict::new(py);
    for t in o.tables {
        let cols = PyDict::new(py);
        for (h, c) in t.header.into_iter().zip(t.columns) {
            cols.set_item(h, PyArray1::from_vec(py, c))?;
        }
        tables.set_item(t.name, cols)?;
    }
    d.set_item("tables", tables)?;
    Ok(d)
}

/// Run `irtp <command>` with keyword options; see `docs/python.md`.
#[pyfunction]
#[pyo3(signature = (command, options, progress=None, threads=None))]
fn run<'py>(
    py: Python<'py>,
    command: &str,
    options: &Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = Vec::new();
    for (k, v) in options.iter() {
        if v.is_none() {
            continue;
        }
        let name: String = k.extract()?;
        opts.push((name.clone(), value(&v, &name)?));
    }
    let argv = argv::build::<Cli>(command, opts).map_err(PyValueError::new_err)?;
    let cli = argv::parse::<Cli>(command, &argv).map_err(PyValueError::new_err)?;
    let progress = progress.filter(|p| !p.is_none());
    let outcome =
        runner::run(py, cli.command, argv, progress, threads)?.map_err(|e| to_pyerr(command, e))?;
    outcome_to_py(py, outcome)
}

/// The commands `run` accepts.
#[pyfunction]
fn commands() -> Vec<&'static str> {
    Cli::commands()
}

/// One dict per keyword of a command: name, flag, help, default, kind,
/// choices, required (from the CLI's definitions).
#[pyfunction]
fn describe<'py>(py: Python<'py>, command: &str) -> PyResult<Bound<'py, PyList>> {
    let cmd = argv::command::<Cli>(command).map_err(PyValueError::new_err)?;
    let list = PyList::empty(py);
    for a in argv::keywords(&cmd) {
        let d = PyDict::new(py);
        d.set_item("name", a.get_id().as_str())?;
        d.set_item("flag", a.get_long().map(|l| format!("--{l}")))?;
        // The long help (`--help`): a docstring has room for the spec syntax
        // and where a flag runs, which `-h` leaves out.
        let help = a.get_long_help().or(a.get_help());
        d.set_item("help", help.map(|h| h.to_string()).unwrap_or_default())?;
        let defaults: Vec<String> = a
            .get_default_values()
            .iter()
            .map(|v| v.to_string_lossy().into_owned())
            .collect();
        d.set_item(
            "default",
            (!defaults.is_empty()).then(|| defaults.join(",")),
        )?;
        d.set_item("kind", argv::kind(a))?;
        let choices: Vec<String> = a
            .get_possible_values()
            .iter()
            .map(|p| p.get_name().to_string())
            .collect();
        d.set_item("choices", (!choices.is_empty()).then_some(choices))?;
        d.set_item("required", a.is_required_set())?;
        list.append(d)?;
    }
    Ok(list)
}

/// The CLI's description of a command.
#[pyfunction]
fn about(command: &str) -> PyResult<String> {
    let cmd = argv::command::<Cli>(command).map_err(PyValueError::new_err)?;
    let text = cmd.get_long_about().or(cmd.get_about());
    Ok(text.map(|t| t.to_string()).unwrap_or_default())
}

/// The registered drag laws: name, description, force limit (inf:
/// unbounded), and for a law with parameters its keys in words and an
/// example spec (`power:n=0.5,k=1`; empty strings for a law without).
#[pyfunction]
fn drag_laws<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for law in DragLaw::examples() {
        let d = PyDict::new(py);
        let keys = law.keys_help();
        d.set_item("name", law.name())?;
        d.set_item("description", law.description())?;
        d.set_item("force_limit", law.force_limit())?;
        d.set_item("parameters", keys.clone())?;
        d.set_item(
            "example",
            if keys.is_empty() {
                String::new()
            } else {
                law.to_string()
            },
        )?;
        list.append(d)?;
    }
    Ok(list)
}

/// The `irtp` command line (`irtp_cli::run_cli`, the binary's own entry)
/// on `argv` (the program name first), off the GIL; its exit status. The
/// console script `irtp` of the wheel (`irtp._cli:main`) runs it, so
/// `pip install ./python` alone installs the whole tool.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
    let args = argv.into_iter().map(Into::into).collect();
    py.detach(|| irtp_cli::run_cli(args))
}

/// The module `irtp._irtp`.
#[pymodule]
fn _irtp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", irtp_app::VERSION)?;
    m.add("__git_revision__", irtp_app::GIT_REVISION)?;
    m.add("NumericalError", m.py().get_type::<NumericalError>())?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(commands, m)?)?;
    m.add_function(wrap_pyfunction!(describe, m)?)?;
    m.add_function(wrap_pyfunction!(about, m)?)?;
    m.add_function(wrap_pyfunction!(drag_laws, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    Ok(())
}
