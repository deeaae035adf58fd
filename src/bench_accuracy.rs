//! `jamkit bench accuracy`: speed against error of the near-disk gap models
//! (`FirstOrder`, `SecondOrder`, `Exact`) and of FIRE's tolerances, for
//! `docs/speed-vs-error.md`. One thread throughout (unless `--jobs`).
//!
//! 1. **Pairs** (a micro-benchmark, measured here): per model, `n` and `Δ`,
//!    the time of one pair evaluation (gap and gradient, `Shape::contacts`)
//!    over a batch of random pairs near contact, and the largest and RMS
//!    error of the gap against `Exact` over the same pairs; fitted log–log
//!    slopes of the largest error against `Δ`.
//! 2. **Packings**: the experiment file `experiments/accuracy/gap_models.ron`
//!    (whole jammed packings per gap model and `Δ`, `n = 2`, the same seeds,
//!    hence the same random starts, at every point), run by the runner into
//!    `RUNS/gap_models` (resumable, `results.csv`, `summary.csv`); each
//!    packing is compared with the packing of the most accurate model of the
//!    run (`Exact`) of the same `Δ` and seed: `φ_J`, `z_J`, `N_c`, rattlers.
//! 3. **Tolerances**: the experiment file `experiments/accuracy/tolerances.ron`
//!    run by the runner once per setting of the ladder (FIRE's force
//!    tolerance × the jamming window, as `--set` overrides) into
//!    `RUNS/tolerances/<setting>`; differences of `φ_J` and `N_c` from the
//!    tightest force tolerance that converged in the paper's window on the
//!    same seed.
//!
//! The two files are compiled in, so the command runs from any directory;
//! `--set-gap-models` / `--set-tolerances` edit them as `jamkit run --set`
//! does (`--quick` is a few such overrides). Everything else goes to `DIR`
//! (CSV, PNG + SVG figures, `tables.md`); with the default `DIR` the
//! generated block of `docs/speed-vs-error.md` is rewritten too.

use anyhow::{Context, Result, bail};
use jamkit_core::Shape;
use jamkit_core::Vector;
use jamkit_experiment::grid::{self, value_text};
use jamkit_experiment::runner::{self, RunOptions};
use jamkit_experiment::schema::{Observable, Protocol};
use jamkit_experiment::{Experiment, ExperimentError, Log, overrides};
use jamkit_format::PackingFile;
use jamkit_fourier::{Angle, FourierParams, NearDisk};
use jamkit_planar::gap2d::GapModel;
use jamkit_report::plot::{Figure, Guide, Series};
use plotters::prelude::SeriesLabelPosition;
use rand::{RngExt, SeedableRng};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default output directory; writing there also rewrites the
/// generated block of [`DOC`].
pub const DEFAULT_OUT: &str = "docs/speed-vs-error";
/// The default directory of the runner's runs (parts 2 and 3).
pub const DEFAULT_RUNS: &str = "out/accuracy";
/// The document whose generated block the default run rewrites.
const DOC: &str = "docs/speed-vs-error.md";
/// [`DEFAULT_OUT`] relative to the directory of [`DOC`].
const LINK_DIR: &str = "speed-vs-error";
const BEGIN: &str = "<!-- generated: jamkit bench accuracy -->";
const END: &str = "<!-- end generated -->";

/// The experiment file of part 2: its path in the repository and its text.
const GAP_MODELS_FILE: (&str, &str) = (
    "experiments/accuracy/gap_models.ron",
    include_str!("../experiments/accuracy/gap_models.ron"),
);
/// The experiment file of part 3 (one setting of the ladder).
const TOLERANCES_FILE: (&str, &str) = (
    "experiments/accuracy/tolerances.ron",
    include_str!("../experiments/accuracy/tolerances.ron"),
);
/// `--quick`: the overrides of the two files (before the user's own).
const QUICK_GAP_MODELS: [&str; 3] = ["particles=10", "samples=1", "params.delta=0.1"];
const QUICK_TOLERANCES: [&str; 2] = ["particles=12", "samples=2"];

const MODELS: [GapModel; 3] = [GapModel::FirstOrder, GapModel::SecondOrder, GapModel::Exact];
const NS: [u32; 4] = [2, 3, 4, 5];
const DELTAS: [f64; 6] = [1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3];
/// Slopes are fitted over `Δ ≤` this (where every `n ≤ 5` is convex).
const FIT_MAX_DELTA: f64 = 0.1;
/// The two sizes of the binary mixture.
const SIZES: (f64, f64) = (0.5, 0.7);
/// Where `Exact` is drawn on the log axis of the speed–error figure.
const EXACT_FLOOR: f64 = 1e-16;

/// Where an unchanged φ_J is drawn on the log axis of the tolerance figure.
const ZERO_FLOOR: f64 = 1e-12;

/// FIRE force tolerances of part 3 (`minimizer.force_tol`); the tightest
/// that converges on a seed (in the paper's window) is that seed's
/// reference. The file's `minimizer.max_steps` bounds each minimisation: a
/// tolerance below the round-off floor of the forces is never met.
const FORCE_TOLS: [f64; 6] = [1e-20, 1e-22, 1e-24, 1e-25, 1e-26, 1e-28];

/// Jamming windows `(E_low, E_high)` of part 3 (`protocol.energy_low`,
/// `protocol.energy_high`): the paper's, and one 100× looser (FIRE's
/// `energy_tol = 1e-16` stays below both; a tighter window would have to
/// move it too).
const WINDOWS: [(f64, f64); 2] = [(1e-16, 2e-16), (1e-14, 2e-14)];

/// What `jamkit bench accuracy` was asked for.
pub struct Options {
    /// Output directory of the tables and figures.
    pub out: PathBuf,
    /// Directory of the runner's runs (parts 2 and 3); a rerun resumes.
    pub runs: PathBuf,
    /// Small sizes, for a smoke test.
    pub quick: bool,
    /// `KEY=VALUE` overrides of `experiments/accuracy/gap_models.ron`.
    pub set_gap_models: Vec<String>,
    /// `KEY=VALUE` overrides of `experiments/accuracy/tolerances.ron`.
    pub set_tolerances: Vec<String>,
    /// Worker threads of the runs (1: the wall times of one core).
    pub jobs: usize,
}

/// Sizes of one run.
struct Plan {
    pairs: usize,
    min_secs: f64,
    /// Part 2, overrides applied.
    gap_models: Experiment,
    /// Part 3 (one setting; the ladder overrides it).
    tolerances: Experiment,
    /// Its one grid point.
    tolerance_point: grid::Point,
}

impl Plan {
    fn of(o: &Options) -> Result<Self> {
        let q = o.quick;
        if o.jobs == 0 {
            bail!("--jobs 0: must be at least 1");
        }
        let quick = |sets: &[&'static str]| -> Vec<&'static str> {
            if q { sets.to_vec() } else { Vec::new() }
        };
        let gap_models = experiment(
            GAP_MODELS_FILE,
            &quick(&QUICK_GAP_MODELS),
            &o.set_gap_models,
        )
        .context("--set-gap-models")?;
        let tolerances = experiment(
            TOLERANCES_FILE,
            &quick(&QUICK_TOLERANCES),
            &o.set_tolerances,
        )
        .context("--set-tolerances")?;
        for (name, e) in [
            ("--set-gap-models", &gap_models),
            ("--set-tolerances", &tolerances),
        ] {
            if !e.wants(&Observable::Contacts) {
                bail!(
                    "{name}: observables = {:?}: must include Contacts (z_J, N_c and \
                     rattlers are compared)",
                    e.observables
                );
            }
            if !matches!(e.protocol, Protocol::Jam { .. }) {
                bail!(
                    "{name}: protocol = {}: the study compares jammed packings; use Jam",
                    e.protocol.name()
                );
            }
        }
        // The comparisons group packings by Δ and gap model (part 2) and by
        // the ladder's setting (part 3): nothing else may scan.
        let mut keys = Vec::new();
        for p in grid::points(&gap_models).context("--set-gap-models")? {
            let key = (param(&p.params, "delta"), param(&p.params, "gap"));
            if key.0.is_none() || key.1.is_none() {
                bail!(
                    "--set-gap-models: family = {:?}: the comparison needs the parameters \
                     `delta` and `gap` (families fourier and fourier_sum)",
                    gap_models.family
                );
            }
            if keys.contains(&key) {
                bail!(
                    "--set-gap-models: the comparison groups packings by params.delta and \
                     params.gap; scan nothing else (dim, particles, other parameters)"
                );
            }
            keys.push(key);
        }
        let mut points = grid::points(&tolerances).context("--set-tolerances")?;
        if points.len() != 1 {
            bail!(
                "--set-tolerances: {} grid points: the ladder is the scan; give one value of \
                 dim, particles and every parameter",
                points.len()
            );
        }
        let plan = Plan {
            pairs: if q { 512 } else { 4096 },
            min_secs: if q { 0.002 } else { 0.05 },
            gap_models,
            tolerances,
            tolerance_point: points.remove(0),
        };
        Ok(plan)
    }
}

/// The experiment of `file` (path, text) with `quick` and then `sets`
/// applied, checked as `jamkit run` checks it.
fn experiment(file: (&str, &str), quick: &[&str], sets: &[String]) -> Result<Experiment> {
    let e = Experiment::from_ron(file.1, file.0)?;
    let sets: Vec<String> = quick
        .iter()
        .map(|s| s.to_string())
        .chain(sets.iter().cloned())
        .collect();
    let e = overrides::apply(&e, &sets)?;
    e.validate()?;
    Ok(e)
}

/// A family parameter of a grid point as text (`0.01`, `Exact`), `None`
/// when the family has no such parameter.
fn param(params: &jamkit_registry::ParamMap, name: &str) -> Option<String> {
    params
        .get(name)
        .map(|v| value_text(v).trim_matches('"').to_string())
}

fn shape(n: u32, delta: f64, gap: GapModel) -> Result<NearDisk> {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap,
    })
    .map_err(|e| anyhow::anyhow!("{e}"))
}

/// One pair: orientations and separation (sizes [`SIZES`]).
struct Pair {
    ti: Angle,
    tj: Angle,
    d: Vector<2>,
}

/// `count` pairs with random orientations and directions, centres
/// `R_i⁰ + R_j⁰ + Δ R̄ u`, `u` uniform in `[−1, 1]` and `R̄ = 0.6` the
/// mean size: within `±Δ R̄` of the disks' contact distance, where the
/// near-disks touch (as in `tests/gap_models.rs`, whose band is ±Δ/4).
fn random_pairs(count: usize, delta: f64, seed: u64) -> Vec<Pair> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mean = 0.5 * (SIZES.0 + SIZES.1);
    (0..count)
        .map(|_| {
            let ti = Angle::new(rng.random::<f64>() * 2.0 * PI);
            let tj = Angle::new(rng.random::<f64>() * 2.0 * PI);
            let a = rng.random::<f64>() * 2.0 * PI;
            let dist = SIZES.0 + SIZES.1 + delta * mean * (2.0 * rng.random::<f64>() - 1.0);
            Pair {
                ti,
                tj,
                d: Vector::<2>::new(dist * a.cos(), dist * a.sin()),
            }
        })
        .collect()
}

fn gaps(s: &NearDisk, pairs: &[Pair]) -> Vec<f64> {
    pairs
        .iter()
        .map(|p| {
            let mut h = f64::NAN;
            s.contacts(SIZES.0, &p.ti, SIZES.1, &p.tj, &p.d, f64::INFINITY, |c| {
                h = c.gap
            });
            h
        })
        .collect()
}

/// Nanoseconds per pair evaluation (gap and gradient): the median over
/// passes through the batch (at least 5, and until `min_secs` have gone
/// by), after one pass to warm up. The median ignores the passes during
/// which another process took the core.
fn time_pairs(s: &NearDisk, pairs: &[Pair], min_secs: f64) -> f64 {
    let mut sink = 0.0;
    let pass = |sink: &mut f64| {
        let s = black_box(s);
        for p in pairs {
            s.contacts(
                SIZES.0,
                black_box(&p.ti),
                SIZES.1,
                black_box(&p.tj),
                black_box(&p.d),
                f64::INFINITY,
                |c| *sink += c.gap + c.grad_r[0] + c.grad_rot_i[0] + c.grad_rot_j[0],
            );
        }
    };
    pass(&mut sink);
    let t = Instant::now();
    let mut passes = Vec::new();
    while passes.len() < 5 || t.elapsed().as_secs_f64() < min_secs {
        let tp = Instant::now();
        pass(&mut sink);
        passes.push(tp.elapsed().as_secs_f64());
    }
    black_box(sink);
    passes.sort_by(f64::total_cmp);
    passes[passes.len() / 2] * 1e9 / pairs.len() as f64
}

/// One line of part 1.
struct PairRow {
    model: GapModel,
    n: u32,
    delta: f64,
    convex: bool,
    /// `None`: the model refused the shape (Exact, non-convex).
    ns: Option<f64>,
    /// `None`: no exact reference (or the reference itself).
    max_err: Option<f64>,
    rms_err: Option<f64>,
}

fn bench_pairs(plan: &Plan) -> Result<Vec<PairRow>> {
    let mut rows = Vec::new();
    for &n in &NS {
        for (k, &delta) in DELTAS.iter().enumerate() {
            let convex = shape(n, delta, GapModel::FirstOrder)?.is_convex();
            let pairs = random_pairs(plan.pairs, delta, 1000 + 10 * n as u64 + k as u64);
            let exact = if convex {
                Some(shape(n, delta, GapModel::Exact)?)
            } else {
                None
            };
            let reference = exact.as_ref().map(|e| gaps(e, &pairs));
            if let Some(r) = &reference
                && let Some(bad) = r.iter().find(|h| !h.is_finite())
            {
                bail!("n = {n}, Δ = {delta}: the exact gap is {bad}");
            }
            for model in MODELS {
                let s = match (model, &exact) {
                    (GapModel::Exact, Some(e)) => e.clone(),
                    (GapModel::Exact, None) => {
                        rows.push(PairRow {
                            model,
                            n,
                            delta,
                            convex,
                            ns: None,
                            max_err: None,
                            rms_err: None,
                        });
                        continue;
                    }
                    _ => shape(n, delta, model)?,
                };
                let ns = time_pairs(&s, &pairs, plan.min_secs);
                let (max_err, rms_err) = match (&reference, model) {
                    (Some(r), m) if m != GapModel::Exact => {
                        let h = gaps(&s, &pairs);
                        let e: Vec<f64> = h.iter().zip(r).map(|(a, b)| (a - b).abs()).collect();
                        let max = e.iter().fold(0.0f64, |m, &x| m.max(x));
                        let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
                        (Some(max), Some(rms))
                    }
                    _ => (None, None),
                };
                rows.push(PairRow {
                    model,
                    n,
                    delta,
                    convex,
                    ns: Some(ns),
                    max_err,
                    rms_err,
                });
            }
        }
    }
    Ok(rows)
}

/// Fitted log–log slope of the largest error against `Δ` per approximate
/// model and `n`, over convex `Δ ≤ FIT_MAX_DELTA`.
fn slopes(rows: &[PairRow]) -> Vec<(GapModel, u32, f64, usize)> {
    let mut out = Vec::new();
    for model in [GapModel::FirstOrder, GapModel::SecondOrder] {
        for &n in &NS {
            let xy: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.model == model && r.n == n && r.delta <= FIT_MAX_DELTA)
                .filter_map(|r| Some((r.delta, r.max_err?)))
                .collect();
            if let Some((_, b)) = jamkit_report::fit::line(&xy) {
                out.push((model, n, b, xy.len()));
            }
        }
    }
    out
}

/// One packing of parts 2 and 3.
/// One packing of parts 2 and 3, as the runner recorded it.
#[derive(Clone)]
struct PackRow {
    seed: u64,
    /// `Err`: the protocol failed (message).
    result: std::result::Result<PackResult, String>,
}

#[derive(Clone, Copy)]
struct PackResult {
    wall_s: f64,
    steps: u64,
    phi: f64,
    z: f64,
    n_c: usize,
    rattlers: usize,
}

impl PackRow {
    fn of(f: &PackingFile) -> Self {
        let m = &f.measures;
        PackRow {
            seed: f.seed,
            result: Ok(PackResult {
                wall_s: m.wall_s,
                steps: m.fire_steps,
                phi: m.phi,
                z: m.z_j.unwrap_or(f64::NAN),
                n_c: m.n_contacts.unwrap_or(0),
                rattlers: m.n_rattlers.unwrap_or(0),
            }),
        }
    }
}

/// Run `e` into `out` by the runner (resuming what is there) and return
/// every job's packing, in grid order, with its point: the recorded
/// measures, or the error of a sample that failed.
fn run_rows(e: &Experiment, out: &Path, jobs: usize) -> Result<Vec<(grid::Point, PackRow)>> {
    let report = runner::run(
        e,
        &RunOptions {
            out: out.to_path_buf(),
            jobs: Some(jobs),
            log: Log::for_stderr(false, false),
            shard: None,
        },
    )
    .with_context(|| format!("running {} into {}", e.name, out.display()))?;
    if !report.elsewhere.is_empty() {
        bail!(
            "{}: another process is making {} of its packings ({}, …); run again when it is done",
            out.display(),
            report.elsewhere.len(),
            report.elsewhere[0]
        );
    }
    let points = grid::points(e)?;
    let mut rows = Vec::new();
    for job in grid::jobs(e, &points) {
        let row = if let Some(f) = report.packings.iter().find(|f| f.id == job.id) {
            PackRow::of(f)
        } else {
            let error = report.failures.iter().find_map(|err| match err {
                ExperimentError::Sample { sample, .. } if *sample == job.id => {
                    Some(err.to_string())
                }
                _ => None,
            });
            match error {
                Some(error) => PackRow {
                    seed: job.seed,
                    result: Err(error),
                },
                // Not a failed sample: an error of the run itself.
                None => match report.failures.first() {
                    Some(err) => bail!("{}: {err}", out.display()),
                    None => bail!("{}: the run made no packing {}", out.display(), job.id),
                },
            }
        };
        rows.push((points[job.point].clone(), row));
    }
    Ok(rows)
}

/// Part 2 per `Δ` and model, in the file's order: `(Δ, n, model, rows)`.
type ModelRuns = Vec<(String, String, String, Vec<PackRow>)>;

fn run_gap_models(plan: &Plan, o: &Options) -> Result<ModelRuns> {
    let mut runs: ModelRuns = Vec::new();
    for (point, row) in run_rows(&plan.gap_models, &o.runs.join("gap_models"), o.jobs)? {
        let p = |name| param(&point.params, name).unwrap_or_default();
        let (delta, n, model) = (p("delta"), p("n"), p("gap"));
        match runs.iter_mut().find(|r| r.0 == delta && r.2 == model) {
            Some(run) => run.3.push(row),
            None => runs.push((delta, n, model, vec![row])),
        }
    }
    Ok(runs)
}

/// How close a gap model is to the exact gap (the most accurate one of a
/// `Δ` is the reference of its packings).
fn accuracy_rank(model: &str) -> usize {
    ["FirstOrder", "SecondOrder", "Exact"]
        .iter()
        .position(|m| *m == model)
        .unwrap_or(0)
}

/// The model whose packings are the reference at `delta`: `Exact` when
/// the run has it.
fn reference_model(runs: &ModelRuns, delta: &str) -> String {
    runs.iter()
        .filter(|r| r.0 == delta)
        .max_by_key(|r| accuracy_rank(&r.2))
        .map(|r| r.2.clone())
        .unwrap_or_default()
}

fn reference_rows<'a>(runs: &'a ModelRuns, delta: &str) -> &'a [PackRow] {
    let model = reference_model(runs, delta);
    runs.iter()
        .find(|r| r.0 == delta && r.2 == model)
        .map(|r| r.3.as_slice())
        .unwrap_or(&[])
}

/// Part 3: `((window, force_tol), rows)`.
type TolRuns = Vec<(((f64, f64), f64), Vec<PackRow>)>;

/// Per seed, the packing of the tightest force tolerance that converged in
/// the paper's window, with that tolerance.
fn tol_reference(runs: &TolRuns) -> Vec<(PackRow, f64)> {
    let mut refs: Vec<(PackRow, f64)> = Vec::new();
    for ((w, ft), rows) in runs.iter().rev() {
        if *w != WINDOWS[0] {
            continue;
        }
        for r in rows {
            if r.result.is_ok() && !refs.iter().any(|(e, _)| e.seed == r.seed) {
                refs.push((r.clone(), *ft));
            }
        }
    }
    refs.sort_by_key(|(r, _)| r.seed);
    refs
}

/// True when `setting` is the reference of every seed.
fn is_reference(refs: &[(PackRow, f64)], setting: ((f64, f64), f64)) -> bool {
    setting.0 == WINDOWS[0] && !refs.is_empty() && refs.iter().all(|(_, ft)| *ft == setting.1)
}

/// The directory of one setting of the ladder under `RUNS/tolerances`.
fn setting_dir(runs: &Path, (lo, hi): (f64, f64), force_tol: f64) -> PathBuf {
    runs.join("tolerances")
        .join(format!("window{lo:e}-{hi:e}_force_tol{force_tol:e}"))
}

fn run_tolerances(plan: &Plan, o: &Options) -> Result<TolRuns> {
    let mut runs = Vec::new();
    for &window in &WINDOWS {
        for &force_tol in &FORCE_TOLS {
            let sets = [
                format!("minimizer.force_tol={force_tol:e}"),
                format!("protocol.energy_low={:e}", window.0),
                format!("protocol.energy_high={:e}", window.1),
            ];
            let e = overrides::apply(&plan.tolerances, &sets)?;
            e.validate()?;
            let dir = setting_dir(&o.runs, window, force_tol);
            eprintln!("{}", dir.display());
            let rows = run_rows(&e, &dir, o.jobs)?;
            runs.push((
                (window, force_tol),
                rows.into_iter().map(|(_, r)| r).collect(),
            ));
        }
    }
    Ok(runs)
}

use jamkit_core::stats::{mean, std_dev};

fn opt(x: Option<f64>, fmt: impl Fn(f64) -> String) -> String {
    x.map(fmt).unwrap_or_default()
}

/// `x` with `digits` decimals, "–" when undefined (no packing converged).
fn fixed(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "–".into()
    }
}

/// `(Δφ_J, Δz_J, ΔN_c, Δrattlers)` of one packing from its reference.
type Diff = (f64, f64, i64, i64);

/// The differences `(Δφ_J, Δz_J, ΔN_c, Δrattlers)` of `rows` from `reference`,
/// seed by seed (both converged).
fn differences(rows: &[PackRow], reference: &[PackRow]) -> Vec<Diff> {
    rows.iter()
        .filter_map(|r| {
            let e = reference.iter().find(|e| e.seed == r.seed)?;
            let (a, b) = (r.result.as_ref().ok()?, e.result.as_ref().ok()?);
            Some((
                a.phi - b.phi,
                a.z - b.z,
                a.n_c as i64 - b.n_c as i64,
                a.rattlers as i64 - b.rattlers as i64,
            ))
        })
        .collect()
}

fn ok_results(rows: &[PackRow]) -> Vec<PackResult> {
    rows.iter()
        .filter_map(|r| r.result.as_ref().ok().copied())
        .collect()
}

/// Where and when: date, commit, machine, load.
fn environment() -> (String, String, String) {
    let cmd = |prog: &str, args: &[&str]| {
        std::process::Command::new(prog)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let date = cmd("date", &["-u", "+%Y-%m-%d %H:%M UTC"]).unwrap_or_else(|| "unknown".into());
    let mut commit =
        cmd("git", &["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    if cmd("git", &["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty())
    {
        commit.push_str(" (with uncommitted changes)");
    }
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(0);
    (date, commit, format!("{cpu}, {cores} cores"))
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into())
}

/// Run the whole benchmark.
/// Run the whole benchmark.
pub fn run(o: &Options) -> Result<()> {
    let plan = Plan::of(o)?;
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;
    let (date, commit, machine) = environment();
    let load_start = load();
    let t0 = Instant::now();

    eprintln!("part 1: pair evaluations");
    let pairs = bench_pairs(&plan)?;
    let fitted = slopes(&pairs);
    eprintln!("part 2: packings ({})", GAP_MODELS_FILE.0);
    let packs = run_gap_models(&plan, o)?;
    eprintln!("part 3: tolerances ({})", TOLERANCES_FILE.0);
    let tols = run_tolerances(&plan, o)?;
    let total = t0.elapsed().as_secs_f64();
    let load_end = load();

    write_csvs(&o.out, &pairs, &fitted, &packs, &tols, &plan)?;
    figures(&o.out, &pairs, &tols, &plan)?;

    let mut md = String::new();
    let mut args = String::new();
    if o.quick {
        args.push_str(" --quick");
    }
    for (flag, sets) in [
        ("--set-gap-models", &o.set_gap_models),
        ("--set-tolerances", &o.set_tolerances),
    ] {
        for s in sets {
            let _ = write!(args, " {flag} '{s}'");
        }
    }
    let _ = writeln!(
        md,
        "Generated by `jamkit bench accuracy{args}` on {date}, commit `{commit}`, \
         {machine}, one thread per packing; load average (1, 5, 15 min) {load_start} at the \
         start and {load_end} at the end; {total:.0} s in all (packings the runs of `{}` \
         already held were read back, not timed again). Wall times are from a shared \
         machine: compare them within one run.",
        o.runs.display()
    );
    md.push('\n');
    md.push_str(&pair_tables(&plan, &pairs, &fitted));
    md.push_str(&packing_table(&plan, &packs));
    md.push_str(&tolerance_table(&plan, &tols));
    out!("{md}");
    for (m, n, b, k) in &fitted {
        out!(
            "slope {} n = {n}: {b:.3} ({k} values of Δ ≤ {FIT_MAX_DELTA})",
            m.name()
        );
    }
    write(&o.out.join("tables.md"), &md)?;
    if o.out == Path::new(DEFAULT_OUT) {
        rewrite_doc(Path::new(DOC), &md)?;
    }
    out!(
        "written to {} (the runs: {})",
        o.out.display(),
        o.runs.display()
    );
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<()> {
    jamkit_format::write_atomic(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// Replace the text between the markers of `doc` by `md`.
fn rewrite_doc(doc: &Path, md: &str) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(doc) else {
        eprintln!(
            "note: {} not found; only the tables were written",
            doc.display()
        );
        return Ok(());
    };
    // Headings of the tables are one level below the document's sections,
    // and the links of tables.md (to files next to it) go into the
    // output directory.
    let body = md
        .replace("\n## ", "\n### ")
        .replace("](", &format!("]({LINK_DIR}/"));
    match splice(&text, &body) {
        Ok(new) => {
            write(doc, &new)?;
            eprintln!("rewrote the generated block of {}", doc.display());
        }
        Err(why) => eprintln!("note: {}: {why}; left alone", doc.display()),
    }
    Ok(())
}

/// `text` with the lines strictly between the line `BEGIN` and the line
/// `END` replaced by `body`. Only whole lines count as markers, so that
/// prose may quote them; exactly one pair must exist.
fn splice(text: &str, body: &str) -> std::result::Result<String, String> {
    let mut begin = Vec::new();
    let mut end = Vec::new();
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        match line.trim_end() {
            BEGIN => begin.push(at + line.len()),
            END => end.push(at),
            _ => {}
        }
        at += line.len();
    }
    match (begin.as_slice(), end.as_slice()) {
        ([b], [e]) if b <= e => Ok(format!("{}\n{body}\n{}", &text[..*b], &text[*e..])),
        ([_], [_]) => Err(format!("`{END}` comes before `{BEGIN}`")),
        _ => Err(format!(
            "needs exactly one line `{BEGIN}` and one line `{END}` (found {} and {})",
            begin.len(),
            end.len()
        )),
    }
}

fn write_csvs(
    dir: &Path,
    pairs: &[PairRow],
    fitted: &[(GapModel, u32, f64, usize)],
    packs: &ModelRuns,
    tols: &TolRuns,
    plan: &Plan,
) -> Result<()> {
    let mut s = String::from("model,n,delta,convex,ns_per_pair,max_err,rms_err,note\n");
    for r in pairs {
        let note = match (r.model, r.convex) {
            (GapModel::Exact, false) => "refused: non-convex outline",
            (GapModel::Exact, true) => "reference",
            (_, false) => "no exact reference",
            _ => "",
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{note}",
            r.model.name(),
            r.n,
            r.delta,
            r.convex,
            opt(r.ns, |x| format!("{x:.2}")),
            opt(r.max_err, |x| format!("{x:.6e}")),
            opt(r.rms_err, |x| format!("{x:.6e}")),
        );
    }
    write(&dir.join("pairs.csv"), &s)?;

    let mut s = String::from("model,n,slope,points\n");
    for (m, n, b, k) in fitted {
        let _ = writeln!(s, "{},{n},{b:.4},{k}", m.name());
    }
    write(&dir.join("slopes.csv"), &s)?;

    // One line per packing, with its differences from the reference packing
    // of its seed (empty when either failed; exactly 0 on the reference's
    // own line).
    let header = "seed,wall_s,fire_steps,phi_j,z_j,n_c,rattlers,\
                  d_phi_j,d_z_j,d_n_c,d_rattlers,error\n";
    let line = |s: &mut String, prefix: String, r: &PackRow, reference: &[PackRow]| {
        let d = differences(std::slice::from_ref(r), reference);
        let d = match d.first() {
            Some((dp, dz, dn, dr)) => format!("{dp:e},{dz:e},{dn},{dr}"),
            None => ",,,".into(),
        };
        let _ = match &r.result {
            Ok(p) => writeln!(
                s,
                "{prefix},{},{:.3},{},{:.9},{:.5},{},{},{d},",
                r.seed, p.wall_s, p.steps, p.phi, p.z, p.n_c, p.rattlers
            ),
            Err(e) => writeln!(
                s,
                "{prefix},{},,,,,,,{d},\"{}\"",
                r.seed,
                e.replace(['"', ','], ";")
            ),
        };
    };
    let particles = |e: &Experiment| e.particles.first().unwrap_or_default();
    let mut s = format!("model,n,delta,particles,reference,{header}");
    for (delta, n, model, rows) in packs {
        let reference = reference_model(packs, delta);
        for r in rows {
            let prefix = format!(
                "{model},{n},{delta},{},{reference}",
                particles(&plan.gap_models)
            );
            line(&mut s, prefix, r, reference_rows(packs, delta));
        }
    }
    write(&dir.join("packings.csv"), &s)?;

    let reference: Vec<PackRow> = tol_reference(tols).into_iter().map(|(r, _)| r).collect();
    let mut s = format!("energy_low,energy_high,force_tol,particles,{header}");
    for (((lo, hi), ft), rows) in tols {
        for r in rows {
            let prefix = format!("{lo:e},{hi:e},{ft:e},{}", particles(&plan.tolerances));
            line(&mut s, prefix, r, &reference);
        }
    }
    write(&dir.join("tolerances.csv"), &s)?;
    Ok(())
}

fn pair_tables(plan: &Plan, rows: &[PairRow], fitted: &[(GapModel, u32, f64, usize)]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Pair evaluations\n\n\
         Time of one evaluation of gap and gradient (`Shape::contacts`), in ns, \
         over {} random pairs of sizes {} and {} near contact (random orientations \
         and directions, centres within ±Δ·0.6 of the disks' contact distance), \
         repeated for at least {} ms; largest and RMS error of the gap `h` against \
         `Exact` over the same pairs, in units of the size (the larger body has \
         R⁰ = {}). Empty errors: no exact reference (non-convex outline, which \
         `Exact` refuses).\n",
        plan.pairs,
        SIZES.0,
        SIZES.1,
        plan.min_secs * 1e3,
        SIZES.1
    );
    md.push_str(
        "| n | Δ | convex | FirstOrder ns | FirstOrder max err | FirstOrder RMS err \
         | SecondOrder ns | SecondOrder max err | SecondOrder RMS err | Exact ns |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let find = |m: GapModel, n: u32, d: f64| {
        rows.iter()
            .find(|r| r.model == m && r.n == n && r.delta == d)
    };
    for &n in &NS {
        for &d in &DELTAS {
            let (Some(f), Some(s), Some(e)) = (
                find(GapModel::FirstOrder, n, d),
                find(GapModel::SecondOrder, n, d),
                find(GapModel::Exact, n, d),
            ) else {
                continue;
            };
            let ns = |r: &PairRow| opt(r.ns, |x| format!("{x:.1}"));
            let err = |x: Option<f64>| opt(x, sci);
            let _ = writeln!(
                md,
                "| {n} | {d} | {} | {} | {} | {} | {} | {} | {} | {} |",
                if f.convex { "yes" } else { "no" },
                ns(f),
                err(f.max_err),
                err(f.rms_err),
                ns(s),
                err(s.max_err),
                err(s.rms_err),
                if e.ns.is_some() {
                    ns(e)
                } else {
                    "refused".into()
                },
            );
        }
    }
    md.push_str("\nMean time per pair evaluation over all n and Δ (ns):");
    for m in MODELS {
        let t: Vec<f64> = rows
            .iter()
            .filter(|r| r.model == m)
            .filter_map(|r| r.ns)
            .collect();
        let _ = write!(md, " {} {:.1};", m.name(), mean(&t));
    }
    md.pop();
    md.push_str(".\n\n");
    let _ = writeln!(
        md,
        "Fitted log–log slope of the largest error against Δ (Δ = 10⁻³ … {FIT_MAX_DELTA}):\n\n\
         | n | FirstOrder (expected 2) | SecondOrder (expected 3) |\n|---|---|---|"
    );
    for &n in &NS {
        let get = |m: GapModel| {
            fitted
                .iter()
                .find(|(fm, fnn, _, _)| *fm == m && *fnn == n)
                .map(|(_, _, b, _)| format!("{b:.3}"))
                .unwrap_or_default()
        };
        let _ = writeln!(
            md,
            "| {n} | {} | {} |",
            get(GapModel::FirstOrder),
            get(GapModel::SecondOrder)
        );
    }
    md.push_str(
        "\nFigures: [error against Δ](errors_vs_delta.png) ([SVG](errors_vs_delta.svg)), \
         [time per pair against error, n = 2](speed_vs_error.png) ([SVG](speed_vs_error.svg)).\n\n",
    );
    md
}

/// The seeds of `e`'s packings, `seed, seed + 1, …`, as a list.
fn seed_list(e: &Experiment) -> String {
    (0..e.samples as u64)
        .map(|k| e.seed.wrapping_add(k).to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The jamming window of a `Jam` protocol, `(E_low, E_high)`.
fn window(e: &Experiment) -> (f64, f64) {
    match e.protocol {
        Protocol::Jam {
            energy_low,
            energy_high,
            ..
        } => (energy_low, energy_high),
        _ => (f64::NAN, f64::NAN),
    }
}

fn packing_table(plan: &Plan, runs: &ModelRuns) -> String {
    let e = &plan.gap_models;
    let mut md = String::new();
    let particles = e.particles.first().unwrap_or_default();
    let (lo, hi) = window(e);
    let _ = writeln!(
        md,
        "## Packings\n\n\
         `{}`: near-disks, N = {particles}{}, the paper's protocol (FIRE force tolerance \
         {:e}, window {lo:e} < V/N < {hi:e}, bisection), seeds {}: one packing per seed \
         and model, each seed the same random start for every model (the runner seeds a \
         start by its seed alone). Means over seeds; \"vs ref.\": the largest difference \
         over seeds from the packing of the same seed with the most accurate model of the \
         run (the \"ref.\" row: Exact), signed mean in brackets; \"sd\": the standard \
         deviation of φ_J across seeds, the statistical error one pays anyway. The run: \
         `RUNS/gap_models` (`results.csv`, `summary.csv`).\n",
        GAP_MODELS_FILE.0,
        if particles < 256 {
            " (not more: Exact packings take minutes each at N = 256; the N = 256 \
             comparison is the Fig. 5 gap-model run of docs/reproduction.md)"
        } else {
            ""
        },
        e.minimizer.force_tol,
        seed_list(e),
    );
    md.push_str(
        "| Δ | model | ok | wall s | FIRE steps | φ_J | sd φ_J | z_J | N_c | rattlers \
         | max \\|Δφ_J\\| (mean Δφ_J) | max \\|Δz_J\\| | max \\|ΔN_c\\| | max \\|Δrattlers\\| |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (delta, _, model, rows) in runs {
        let ok = ok_results(rows);
        let col = |f: fn(&PackResult) -> f64, digits: usize| {
            fixed(mean(&ok.iter().map(f).collect::<Vec<_>>()), digits)
        };
        let phis: Vec<f64> = ok.iter().map(|r| r.phi).collect();
        let diffs = if *model == reference_model(runs, delta) {
            None
        } else {
            Some(differences(rows, reference_rows(runs, delta)))
        };
        let dcol = |f: &dyn Fn(&Diff) -> f64, digits: usize| match &diffs {
            Some(d) if !d.is_empty() => {
                format!("{:.*}", digits, d.iter().map(f).fold(0.0f64, f64::max))
            }
            Some(_) => "–".into(),
            None => "ref.".into(),
        };
        let dphi = match &diffs {
            Some(d) if !d.is_empty() => format!(
                "{} ({:+.1e})",
                sci(d.iter().map(|x| x.0.abs()).fold(0.0f64, f64::max)),
                mean(&d.iter().map(|x| x.0).collect::<Vec<_>>())
            ),
            Some(_) => "–".into(),
            None => "ref.".into(),
        };
        let _ = writeln!(
            md,
            "| {delta} | {model} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {dphi} | {} | {} | {} |",
            ok.len(),
            rows.len(),
            col(|r| r.wall_s, 2),
            col(|r| r.steps as f64, 0),
            col(|r| r.phi, 6),
            sci(std_dev(&phis)),
            col(|r| r.z, 4),
            col(|r| r.n_c as f64, 1),
            col(|r| r.rattlers as f64, 1),
            dcol(&|x| x.1.abs(), 4),
            dcol(&|x| x.2.abs() as f64, 0),
            dcol(&|x| x.3.abs() as f64, 0),
        );
    }
    for (delta, _, model, rows) in runs {
        for r in rows {
            if let Err(e) = &r.result {
                let _ = writeln!(md, "\nΔ = {delta}, {model}, seed {}: failed: {e}", r.seed);
            }
        }
    }
    md.push_str("\nPer packing: [packings.csv](packings.csv).\n\n");
    md
}

fn tolerance_table(plan: &Plan, runs: &TolRuns) -> String {
    let e = &plan.tolerances;
    let mut md = String::new();
    let refs = tol_reference(runs);
    let reference: Vec<PackRow> = refs.iter().map(|(r, _)| r.clone()).collect();
    let ref_text: Vec<String> = refs
        .iter()
        .map(|(r, ft)| format!("seed {}: {ft:.0e}", r.seed))
        .collect();
    let p = |name| param(&plan.tolerance_point.params, name).unwrap_or_default();
    let _ = writeln!(
        md,
        "## Tolerances\n\n\
         `{}`: {} near-disks n = {}, Δ = {}, N = {}, seeds {}, run once per setting \
         (`RUNS/tolerances/<setting>`): FIRE's force \
         tolerance (stop when Σ(∂V/∂q)² falls below it; the default is 1e-25) and \
         the jamming window (the paper's 1e-16 < V/N < 2e-16, and one 100× looser, \
         the shortcut a user would try; a tighter one would need FIRE's \
         energy_tol = 1e-16 moved as well, mixing two changes). At most {} \
         FIRE steps per minimisation: a tolerance FIRE cannot reach fails. Differences \
         are from the tightest force tolerance that converged in the paper's window on \
         the same seed ({}), largest over seeds; \"sd φ_J\" is the spread across seeds \
         at that setting.\n",
        TOLERANCES_FILE.0,
        p("gap"),
        p("n"),
        p("delta"),
        e.particles.first().unwrap_or_default(),
        seed_list(e),
        e.minimizer.max_steps,
        ref_text.join(", ")
    );
    md.push_str(
        "| window V/N | force tol | ok | wall s | FIRE steps | max \\|Δφ_J\\| | max \\|ΔN_c\\| \
         | max \\|Δrattlers\\| | sd φ_J |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for (((lo, hi), ft), rows) in runs {
        let ok = ok_results(rows);
        let d = differences(rows, &reference);
        let is_ref = is_reference(&refs, ((*lo, *hi), *ft));
        let dmax = |f: &dyn Fn(&Diff) -> f64, fmt: &dyn Fn(f64) -> String| {
            if is_ref {
                "ref.".to_string()
            } else if d.is_empty() {
                "–".into()
            } else {
                fmt(d.iter().map(f).fold(0.0f64, f64::max))
            }
        };
        let phis: Vec<f64> = ok.iter().map(|r| r.phi).collect();
        let _ = writeln!(
            md,
            "| {lo:.0e}…{hi:.0e} | {ft:.0e} | {}/{} | {} | {} | {} | {} | {} | {} |",
            ok.len(),
            rows.len(),
            fixed(mean(&ok.iter().map(|r| r.wall_s).collect::<Vec<_>>()), 2),
            fixed(
                mean(&ok.iter().map(|r| r.steps as f64).collect::<Vec<_>>()),
                0
            ),
            dmax(&|x| x.0.abs(), &sci),
            dmax(&|x| x.2.abs() as f64, &|v| format!("{v:.0}")),
            dmax(&|x| x.3.abs() as f64, &|v| format!("{v:.0}")),
            sci(std_dev(&phis)),
        );
    }
    for (((lo, _), ft), rows) in runs {
        for r in rows {
            if let Err(e) = &r.result {
                let _ = writeln!(
                    md,
                    "\nwindow from {lo:e}, force tolerance {ft:e}, seed {}: failed: {e}",
                    r.seed
                );
            }
        }
    }
    md.push_str(
        "\nPer packing: [tolerances.csv](tolerances.csv). Figure: [time per packing \
         against the change of φ_J](tolerances.png) ([SVG](tolerances.svg)).\n",
    );
    md
}

fn figures(dir: &Path, pairs: &[PairRow], tols: &TolRuns, plan: &Plan) -> Result<()> {
    let p = |name| param(&plan.tolerance_point.params, name).unwrap_or_default();
    let mut series = Vec::new();
    for model in [GapModel::FirstOrder, GapModel::SecondOrder] {
        for &n in &NS {
            let points: Vec<(f64, f64, f64)> = pairs
                .iter()
                .filter(|r| r.model == model && r.n == n)
                .filter_map(|r| Some((r.delta, r.max_err?, 0.0)))
                .collect();
            series.push(Series {
                label: format!("{} n = {n}", model.name()),
                points,
                line: true,
            });
        }
    }
    let at = |m: GapModel| {
        pairs
            .iter()
            .find(|r| r.model == m && r.n == 2 && r.delta == 1e-2)
            .and_then(|r| Some((r.delta, r.max_err?)))
    };
    let mut guides = Vec::new();
    if let Some(p) = at(GapModel::FirstOrder) {
        guides.push(Guide::power_law_through("∝ Δ²", 2.0, p, 1e-3, 0.3));
    }
    if let Some(p) = at(GapModel::SecondOrder) {
        guides.push(Guide::power_law_through("∝ Δ³", 3.0, p, 1e-3, 0.3));
    }
    Figure {
        title: "Largest gap error against Exact, pairs near contact".into(),
        x_label: "Δ".into(),
        y_label: "max |h − h_exact|".into(),
        log_x: true,
        log_y: true,
        series,
        guides,
        legend: SeriesLabelPosition::LowerRight,
    }
    .write(&dir.join("errors_vs_delta"))
    .map_err(|e| anyhow::anyhow!("{e}"))?;

    let series = MODELS
        .iter()
        .map(|&m| Series {
            label: if m == GapModel::Exact {
                format!("Exact (error 0, drawn at {EXACT_FLOOR:.0e})")
            } else {
                m.name().to_string()
            },
            points: pairs
                .iter()
                .filter(|r| r.model == m && r.n == 2)
                .filter_map(|r| {
                    let e = if m == GapModel::Exact {
                        EXACT_FLOOR
                    } else {
                        r.max_err?
                    };
                    Some((r.ns?, e, 0.0))
                })
                .collect(),
            line: false,
        })
        .collect();
    Figure {
        title: "Speed against error, n = 2 (one marker per Δ)".into(),
        x_label: "time per pair evaluation (ns)".into(),
        y_label: "max |h − h_exact|".into(),
        log_x: true,
        log_y: true,
        series,
        guides: Vec::new(),
        legend: SeriesLabelPosition::UpperRight,
    }
    .write(&dir.join("speed_vs_error"))
    .map_err(|e| anyhow::anyhow!("{e}"))?;

    let refs = tol_reference(tols);
    let reference: Vec<PackRow> = refs.iter().map(|(r, _)| r.clone()).collect();
    // (window, time, largest |Δφ_J|) per setting but the reference.
    let points: Vec<((f64, f64), f64, f64)> = tols
        .iter()
        .filter(|(setting, _)| !is_reference(&refs, *setting))
        .filter_map(|((w, _), rows)| {
            let ok = ok_results(rows);
            let d = differences(rows, &reference);
            if ok.is_empty() || d.is_empty() {
                return None;
            }
            let t = mean(&ok.iter().map(|r| r.wall_s).collect::<Vec<_>>());
            Some((*w, t, d.iter().map(|x| x.0.abs()).fold(0.0f64, f64::max)))
        })
        .collect();
    let mut series: Vec<Series> = WINDOWS
        .iter()
        .map(|&w| Series {
            label: format!("window {:.0e} < V/N < {:.0e}", w.0, w.1),
            points: points
                .iter()
                .filter(|p| p.0 == w && p.2 > 0.0)
                .map(|p| (p.1, p.2, 0.0))
                .collect(),
            line: false,
        })
        .collect();
    series.push(Series {
        label: format!("φ_J unchanged (drawn at {ZERO_FLOOR:.0e})"),
        points: points
            .iter()
            .filter(|p| p.2 == 0.0)
            .map(|p| (p.1, ZERO_FLOOR, 0.0))
            .collect(),
        line: false,
    });
    Figure {
        title: format!(
            "FIRE tolerance: time against change of φ_J ({}, n = {}, Δ = {})",
            p("gap"),
            p("n"),
            p("delta")
        ),
        x_label: "wall time per packing (s)".into(),
        y_label: "max |φ_J − φ_J(tightest converged)|".into(),
        log_x: true,
        log_y: true,
        series,
        guides: Vec::new(),
        legend: SeriesLabelPosition::UpperRight,
    }
    .write(&dir.join("tolerances"))
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_marker_lines_delimit_the_generated_block() {
        let doc =
            format!("prose quoting `{BEGIN}` and `{END}`\n{BEGIN}\nold\ntables\n{END}\nafter\n");
        let new = splice(&doc, "NEW").unwrap();
        assert_eq!(
            new,
            format!("prose quoting `{BEGIN}` and `{END}`\n{BEGIN}\n\nNEW\n{END}\nafter\n")
        );
        // Idempotent: a second run replaces the block it wrote.
        assert_eq!(splice(&new, "NEW").unwrap(), new);
        assert!(splice("no markers\n", "x").is_err());
        assert!(splice(&format!("{END}\n{BEGIN}\n"), "x").is_err());
        assert!(splice(&format!("{BEGIN}\n{END}\n{BEGIN}\n{END}\n"), "x").is_err());
    }
}
