//! The native half of the Python module `jamkit` (docs/reference/python.md): the
//! experiment runner, the packing-file reader and the measurements of a
//! packing in memory, each handing JSON to the Python layer
//! (`jamkit/__init__.py`), which turns it into numpy arrays. The numbers
//! are the command line's: the same library calls, the same bits.

use jamkit_core::Shape;
use jamkit_engine::Scene;
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_experiment::runner::{RunOptions, default_out, run as run_experiment};
use jamkit_experiment::{Experiment, ExperimentError, Log, overrides};
use jamkit_format::PackingFile;
use jamkit_observe::hessian::HessianOptions;
use jamkit_observe::spectrum::{DosParams, Spectrum, measure};
use pyo3::create_exception;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};

create_exception!(
    _native,
    JamkitError,
    pyo3::exceptions::PyValueError,
    "What jamkit refused or could not do; the message names the field, the value and what is allowed."
);

fn fail(e: impl std::fmt::Display) -> PyErr {
    JamkitError::new_err(e.to_string())
}

/// An experiment from RON text or (`json`) from the JSON of a Python dict,
/// with `--set`-style overrides, validated as the command line does.
fn experiment(
    text: &str,
    json: bool,
    origin: &str,
    sets: &[String],
) -> Result<Experiment, ExperimentError> {
    let e = if json {
        serde_json::from_str::<Experiment>(text).map_err(|e| ExperimentError::Parse {
            file: origin.to_string(),
            message: e.to_string(),
        })?
    } else {
        Experiment::from_ron(text, origin)?
    };
    let e = overrides::apply(&e, sets)?;
    e.validate()?;
    Ok(e)
}

/// Run an experiment; JSON `{"out", "ids", "reused"}`: the run directory
/// and the packing ids in grid order.
#[pyfunction]
#[pyo3(signature = (text, json, origin, out, jobs, sets))]
fn run(
    text: &str,
    json: bool,
    origin: &str,
    out: Option<String>,
    jobs: usize,
    sets: Vec<String>,
) -> PyResult<String> {
    let e = experiment(text, json, origin, &sets).map_err(fail)?;
    let out = out.map_or_else(|| default_out(&e), PathBuf::from);
    let options = RunOptions {
        out: out.clone(),
        jobs: Some(jobs.max(1)),
        log: Log::Quiet,
        shard: None,
    };
    let report = run_experiment(&e, &options).map_err(fail)?;
    if !report.failures.is_empty() {
        let all: Vec<String> = report.failures.iter().map(|f| f.to_string()).collect();
        return Err(fail(format!(
            "{} of the samples failed: {}",
            all.len(),
            all.join("; ")
        )));
    }
    let ids: Vec<&str> = report.packings.iter().map(|p| p.id.as_str()).collect();
    Ok(serde_json::json!({
        "out": out.display().to_string(),
        "ids": ids,
        "reused": report.reused,
    })
    .to_string())
}

/// A packing file, checked as `jamkit` checks it on load, as JSON.
#[pyfunction]
fn load(path: &str) -> PyResult<String> {
    let file = PackingFile::load_checked(Path::new(path)).map_err(fail)?;
    serde_json::to_string(&file).map_err(fail)
}

/// A packing handed back by the Python layer (the JSON of a packing file).
fn packing(json: &str) -> PyResult<PackingFile> {
    let file: PackingFile =
        serde_json::from_str(json).map_err(|e| fail(format!("not a jamkit packing: {e}")))?;
    file.check_as(format_args!("packing {}", file.id))
        .map_err(fail)?;
    Ok(file)
}

struct Contacts;

impl PackingVisitor for Contacts {
    type Output = Vec<(usize, usize, f64)>;
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
        let mut out = Vec::new();
        scene.for_each_contact(0.0, |i, j, _, c| {
            if c.gap < 0.0 {
                out.push((i, j, c.gap));
            }
        });
        out
    }
}

/// The contacts of a packing (gap `h < 0`, as `Contacts` counts them):
/// JSON `{"pairs": [[i, j], …], "gaps": [h, …]}`, one entry per contact
/// (bodies made of spheres may touch at several).
#[pyfunction]
fn contacts(packing_json: &str) -> PyResult<String> {
    let file = packing(packing_json)?;
    let found = reload(&file, Contacts).map_err(fail)?;
    let pairs: Vec<[usize; 2]> = found.iter().map(|&(i, j, _)| [i, j]).collect();
    let gaps: Vec<f64> = found.iter().map(|c| c.2).collect();
    Ok(serde_json::json!({"pairs": pairs, "gaps": gaps}).to_string())
}

struct Eigen {
    rattler: Vec<bool>,
    options: HessianOptions,
}

impl PackingVisitor for Eigen {
    type Output = jamkit_core::Result<Spectrum>;
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
        measure(
            &mut scene,
            &self.rattler,
            self.options,
            false,
            &DosParams::default(),
        )
    }
}

/// The eigenvalues of the packing's Hessian, as `jamkit spectrum` gives
/// them: JSON `{"eigenvalues": […], "zero_modes": {…}}`.
#[pyfunction]
#[pyo3(signature = (packing_json, stiffness_only, remove_rattlers))]
fn spectrum(packing_json: &str, stiffness_only: bool, remove_rattlers: bool) -> PyResult<String> {
    let file = packing(packing_json)?;
    let visitor = Eigen {
        rattler: file.rattler.clone(),
        options: HessianOptions {
            stiffness_only,
            remove_rattlers,
        },
    };
    let s = reload(&file, visitor).map_err(fail)?.map_err(fail)?;
    Ok(serde_json::json!({
        "eigenvalues": s.eigenvalues,
        "zero_modes": {
            "total": s.zero.total,
            "translations": s.zero.translations,
            "rattlers": s.zero.rattlers,
            "extra": s.zero.extra,
        },
    })
    .to_string())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(contacts, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum, m)?)?;
    m.add("JamkitError", m.py().get_type::<JamkitError>())?;
    Ok(())
}
