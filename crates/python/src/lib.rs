//! The native half of the Python module `jamkit` (docs/reference/python.md): the
//! experiment runner, the packing-file reader and the measurements of a
//! packing in memory, each handing JSON to the Python layer
//! (`jamkit/__init__.py`), which turns it into numpy arrays. The numbers
//! are the command line's: the same library calls, the same bits.

use jamkit_core::{Packing, PeriodicBox, Shape, Vector};
use jamkit_engine::Scene;
use jamkit_experiment::reload::{PHI_TOLERANCE, PackingVisitor, reload};
use jamkit_experiment::runner::{Hooks, RunOptions, default_out, run_with};
use jamkit_experiment::{Experiment, ExperimentError, Log, Plan, overrides, sample};
use jamkit_format::{Measures, PackingFile};
use jamkit_observe::hessian::HessianOptions;
use jamkit_observe::spectrum::{DosParams, Spectrum, measure};
use jamkit_registry::{self as registry, SceneVisitor};
use pyo3::create_exception;
use pyo3::prelude::*;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

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

/// Run an experiment; JSON `{"out", "ids", "failures", "stopped",
/// "reused"}`: the run directory, the ids of the packings made or reused
/// in grid order, the failed samples (`{"id", "message"}`) and the samples
/// not started. The run goes on in another thread while this one, the
/// caller's, waits without the GIL and checks for signals every 0.1 s; a
/// signal's exception (`KeyboardInterrupt`), or one raised by `progress`,
/// stops the run after the samples under way and is raised when they are
/// saved. `progress` is called with a dict (`done`, `total`, `id`, `phi`,
/// `error`) as each sample ends.
#[pyfunction]
#[pyo3(signature = (text, json, origin, out, jobs, sets, progress=None))]
#[allow(clippy::too_many_arguments)]
fn run(
    py: Python<'_>,
    text: &str,
    json: bool,
    origin: &str,
    out: Option<String>,
    jobs: usize,
    sets: Vec<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let e = experiment(text, json, origin, &sets).map_err(fail)?;
    let total = Plan::new(&e).map_err(fail)?.jobs.len();
    let out = out.map_or_else(|| default_out(&e), PathBuf::from);
    let options = RunOptions {
        out: out.clone(),
        jobs: Some(jobs.max(1)),
        log: Log::Quiet,
        shard: None,
    };
    let stop = AtomicBool::new(false);
    let raised: Mutex<Option<PyErr>> = Mutex::new(None);
    let done = AtomicUsize::new(0);
    let keep = |err: PyErr| {
        let mut slot = raised.lock().unwrap_or_else(|e| e.into_inner());
        slot.get_or_insert(err);
        stop.store(true, Ordering::SeqCst);
    };
    let finished = |id: &str, outcome: Result<&PackingFile, &ExperimentError>| {
        let done = done.fetch_add(1, Ordering::SeqCst) + 1;
        let Some(callback) = &progress else {
            return;
        };
        Python::attach(|py| {
            let event = pyo3::types::PyDict::new(py);
            let (phi, error) = match outcome {
                Ok(f) => (Some(f.phi), None),
                Err(e) => (None, Some(e.to_string())),
            };
            let filled = event
                .set_item("done", done)
                .and_then(|()| event.set_item("total", total))
                .and_then(|()| event.set_item("id", id))
                .and_then(|()| event.set_item("phi", phi))
                .and_then(|()| event.set_item("error", error));
            if let Err(err) = filled.and_then(|()| callback.call1(py, (event,)).map(drop)) {
                keep(err);
            }
        });
    };
    let hooks = Hooks {
        stop: Some(&stop),
        finished: Some(&finished),
    };
    let (tx, mut rx) = mpsc::channel();
    let report = std::thread::scope(|s| {
        s.spawn(|| {
            let _ = tx.send(run_with(&e, &options, hooks));
        });
        loop {
            // The receiver goes into the GIL-free wait and comes back (a
            // `Receiver` is not `Sync`, so it cannot be borrowed there).
            let (back, got) = py.detach(move || {
                let got = rx.recv_timeout(Duration::from_millis(100));
                (rx, got)
            });
            rx = back;
            match got {
                Ok(report) => break report,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(err) = py.check_signals() {
                        keep(err);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break Err(ExperimentError::invalid(
                        "run",
                        "…",
                        "the run's thread ended without a result",
                    ));
                }
            }
        }
    });
    if let Some(err) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(err);
    }
    let report = report.map_err(fail)?;
    let ids: Vec<&str> = report.packings.iter().map(|p| p.id.as_str()).collect();
    let failures: Vec<Value> = report
        .failures
        .iter()
        .map(|f| {
            let id = match f {
                ExperimentError::Sample { sample, .. } => sample.clone(),
                _ => String::new(),
            };
            json!({"id": id, "message": f.to_string()})
        })
        .collect();
    Ok(json!({
        "out": out.display().to_string(),
        "ids": ids,
        "failures": failures,
        "stopped": report.stopped,
        "elsewhere": report.elsewhere,
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

/// φ of the family's bodies of these sizes in this box.
struct PhiOf<'a> {
    sizes: &'a [f64],
    edges: &'a [f64],
}

impl SceneVisitor for PhiOf<'_> {
    type Output = f64;
    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> f64 {
        let packing = Packing {
            shape,
            bbox: PeriodicBox::new(Vector::<D>::from_column_slice(self.edges)),
            positions: Vec::new(),
            orientations: Vec::new(),
            sizes: self.sizes.to_vec(),
        };
        packing.phi()
    }
}

/// The `spheres` rows and `V/N` of a packing's configuration.
struct Derived;

impl PackingVisitor for Derived {
    type Output = (Vec<Vec<f64>>, f64);
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
        let n = scene.packing().len().max(1) as f64;
        let energy = scene.energy() / n;
        (sample::sphere_rows(scene.packing()), energy)
    }
}

/// A packing handed over by the Python layer (the JSON of a packing file
/// holding the `Packing`'s arrays as they are), made consistent with its
/// arrays: `particles` the number of centres, `phi` from its box and sizes
/// (the recorded one where they give it to `reload`'s tolerance),
/// the `spheres` rows of bodies made of spheres from its centres and
/// orientations; with `energy`, also `V/N` from its configuration.
fn packing_with(json: &str, energy: bool) -> PyResult<PackingFile> {
    let mut file: PackingFile =
        serde_json::from_str(json).map_err(|e| fail(format!("not a jamkit packing: {e}")))?;
    file.particles = file.positions.len();
    file.check_as(format_args!("packing {}", file.id))
        .map_err(fail)?;
    if file.positions.is_empty() {
        return Err(fail(format!(
            "packing {}: positions = []: the packing holds no configuration (made with output.packings = false, or from an archive)",
            file.id
        )));
    }
    let params = registry::params_from_json(&file.params).map_err(fail)?;
    let phi = registry::dispatch(
        &file.family,
        file.dim,
        &params,
        PhiOf {
            sizes: &file.radii,
            edges: &file.box_edges,
        },
    )
    .map_err(fail)?;
    // A recorded φ that the arrays give to `reload`'s tolerance stays (the
    // protocol's own, to the last bits); edited sizes or box give theirs.
    let agrees = (phi - file.phi).abs() <= PHI_TOLERANCE * phi;
    if !agrees {
        file.phi = phi;
        file.measures.phi = phi;
    }
    file.spheres = Vec::new();
    let (spheres, v) = reload(&file, Derived).map_err(fail)?;
    file.spheres = spheres;
    if energy {
        file.energy_per_particle = v;
        file.measures.energy_per_particle = v;
    }
    Ok(file)
}

fn packing(json: &str) -> PyResult<PackingFile> {
    packing_with(json, false)
}

fn to_json(file: &PackingFile) -> PyResult<String> {
    serde_json::to_string(file).map_err(fail)
}

/// A packing file of a configuration given as arrays (nothing measured;
/// `V/N` of the configuration).
#[pyfunction]
#[pyo3(signature = (family, params_json, positions, sizes, box_edges, orientations))]
fn from_arrays(
    family: &str,
    params_json: &str,
    positions: Vec<Vec<f64>>,
    sizes: Vec<f64>,
    box_edges: Vec<f64>,
    orientations: Vec<Vec<f64>>,
) -> PyResult<String> {
    let params: Value = serde_json::from_str(params_json).map_err(fail)?;
    registry::family_info(family).map_err(fail)?;
    let (jamkit_version, git_commit) = jamkit_format::provenance::stamp();
    let file = PackingFile {
        id: "arrays".into(),
        experiment: "python".into(),
        family: family.into(),
        params,
        dim: box_edges.len(),
        particles: positions.len(),
        seed: 0,
        protocol: "none".into(),
        settings: json!({}),
        observables: json!([]),
        phi: 0.0,
        energy_per_particle: 0.0,
        measures: Measures::bare(0.0, 0.0),
        box_edges,
        positions,
        radii: sizes,
        orientations,
        rattler: Vec::new(),
        spheres: Vec::new(),
        jamkit_version,
        git_commit,
    };
    to_json(&packing_with(&to_json(&file)?, true)?)
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
    Ok(json!({"pairs": pairs, "gaps": gaps}).to_string())
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
fn spectrum(
    py: Python<'_>,
    packing_json: &str,
    stiffness_only: bool,
    remove_rattlers: bool,
) -> PyResult<String> {
    let file = packing(packing_json)?;
    let visitor = Eigen {
        rattler: file.rattler.clone(),
        options: HessianOptions {
            stiffness_only,
            remove_rattlers,
        },
    };
    let s = py
        .detach(|| reload(&file, visitor))
        .map_err(fail)?
        .map_err(fail)?;
    Ok(json!({
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

/// The experiment of one packing: its family, parameters, dimension, body
/// count, seed, potential, rattler rule and engine settings, with the
/// given observables and (when given) protocol and minimiser; everything
/// else the experiment file's defaults.
fn experiment_of(
    file: &PackingFile,
    observables: Value,
    protocol: Option<Value>,
    minimizer: Option<Value>,
) -> Result<Experiment, ExperimentError> {
    let name = if file.experiment.is_empty() {
        "python"
    } else {
        &file.experiment
    };
    // A packing file writes an unset optional parameter as `null`; an
    // experiment leaves it out.
    let params: serde_json::Map<String, Value> = file
        .params
        .as_object()
        .map(|m| {
            m.iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect()
        })
        .unwrap_or_default();
    let mut e = json!({
        "name": name,
        "family": file.family,
        "dim": file.dim,
        "params": params,
        "particles": file.particles,
        "seed": file.seed,
        "observables": observables,
    });
    for key in ["potential", "rattlers", "engine"] {
        if let Some(v) = file.settings.get(key) {
            e[key] = v.clone();
        }
    }
    if let Some(p) = protocol {
        e["protocol"] = p;
    }
    if let Some(m) = minimizer {
        e["minimizer"] = m;
    }
    let e: Experiment = serde_json::from_value(e).map_err(|err| ExperimentError::Parse {
        file: format!("packing {}", file.id),
        message: err.to_string(),
    })?;
    e.validate()?;
    Ok(e)
}

fn parse(what: &str, text: &str) -> PyResult<Value> {
    serde_json::from_str(text).map_err(|e| fail(format!("{what}: {e}")))
}

/// The packing with `observables` (the JSON of an experiment file's list)
/// measured on it as a run measures them: JSON of the packing file.
#[pyfunction]
fn measure_packing(py: Python<'_>, packing_json: &str, observables: &str) -> PyResult<String> {
    let file = packing(packing_json)?;
    let e = experiment_of(&file, parse("observables", observables)?, None, None).map_err(fail)?;
    let (file, _) = py.detach(|| sample::measure_file(&e, file)).map_err(fail)?;
    to_json(&file)
}

/// The packing after `protocol` (JSON of an experiment file's protocol)
/// run from its configuration with `minimizer` (JSON, or empty for the
/// default), then `observables` measured: JSON of the packing file.
#[pyfunction]
fn run_protocol(
    py: Python<'_>,
    packing_json: &str,
    protocol: &str,
    minimizer: &str,
    observables: &str,
) -> PyResult<String> {
    let file = packing(packing_json)?;
    let minimizer = if minimizer.is_empty() {
        None
    } else {
        Some(parse("minimizer", minimizer)?)
    };
    let e = experiment_of(
        &file,
        parse("observables", observables)?,
        Some(parse("protocol", protocol)?),
        minimizer,
    )
    .map_err(fail)?;
    let (file, _) = py
        .detach(|| Plan::new(&e).and_then(|plan| plan.run_from_file(&file)))
        .map_err(fail)?;
    to_json(&file)
}

/// Draw the packing as `jamkit draw` does (2D outlines, or a 3D ray-cast
/// seen along z), to an SVG or PNG file.
#[pyfunction]
fn draw(py: Python<'_>, packing_json: &str, path: &str, size: u32) -> PyResult<()> {
    let file = packing(packing_json)?;
    let path = Path::new(path);
    py.detach(|| -> Result<(), jamkit_draw::DrawError> {
        if file.dim == 3 {
            let p = jamkit_draw::Packing3d::from_file(&file)?;
            jamkit_draw::draw_packing_3d(&p, jamkit_draw::scene3d::View::Whole, path, size)
        } else {
            let p = jamkit_draw::Packing2d::from_file(&file)?;
            jamkit_draw::draw_packing(&p, path, size)
        }
    })
    .map_err(fail)
}

/// Write the packing as one frame of extended XYZ, as `jamkit export`.
#[pyfunction]
fn export_xyz(packing_json: &str, path: &str) -> PyResult<()> {
    let file = packing(packing_json)?;
    let frame = jamkit_experiment::extxyz::frame(&file).map_err(fail)?;
    jamkit_format::write_atomic(Path::new(path), frame.as_bytes()).map_err(fail)
}

/// The packings (JSON of packing files, a list) written to `path` as
/// HOOMD-blue's GSD, one frame each, as `jamkit export … -o FILE.gsd` does.
#[pyfunction]
fn export_gsd(packings_json: Vec<String>, path: &str) -> PyResult<()> {
    let files = packings_json
        .iter()
        .map(|json| packing(json))
        .collect::<PyResult<Vec<_>>>()?;
    let bytes = jamkit_experiment::gsd::file(&files).map_err(fail)?;
    jamkit_format::write_atomic(Path::new(path), &bytes).map_err(fail)
}

/// The packing made consistent with its arrays (see `packing_with`).
#[pyfunction]
fn normalize(packing_json: &str) -> PyResult<String> {
    to_json(&packing(packing_json)?)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(normalize, m)?)?;
    m.add_function(wrap_pyfunction!(contacts, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(measure_packing, m)?)?;
    m.add_function(wrap_pyfunction!(run_protocol, m)?)?;
    m.add_function(wrap_pyfunction!(draw, m)?)?;
    m.add_function(wrap_pyfunction!(export_xyz, m)?)?;
    m.add_function(wrap_pyfunction!(export_gsd, m)?)?;
    m.add("JamkitError", m.py().get_type::<JamkitError>())?;
    Ok(())
}
