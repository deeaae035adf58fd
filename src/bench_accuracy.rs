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
//!    `RUNS/gap_models` (resumable, `results.csv`, `summary.csv`), then
//!    compared by `jamkit_report::accuracy` (`jamkit report --accuracy
//!    gap-models`).
//! 3. **Tolerances**: the experiment file `experiments/accuracy/tolerances.ron`,
//!    whose `scan` is the ladder (FIRE's force tolerance × the jamming
//!    window), run by the runner into `RUNS/tolerances`, then compared by
//!    `jamkit_report::accuracy` (`jamkit report --accuracy tolerances`).
//!
//! Parts 2 and 3 are thus a run and a report each, which this command
//! chains; only part 1, a micro-benchmark of one function, is measured here.
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
use jamkit_fourier::{Angle, FourierParams, NearDisk};
use jamkit_planar::gap2d::GapModel;
use jamkit_report::accuracy::{self, Study, sci};
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
    /// Part 3 (its `scan` is the ladder).
    tolerances: Experiment,
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
        // The comparison groups packings by the ladder's setting: the scan
        // of the file, and nothing else.
        let mut settings = Vec::new();
        for p in grid::points(&tolerances).context("--set-tolerances")? {
            let (lo, hi) = window(&p.protocol);
            let key = (lo, hi, p.minimizer.force_tol);
            if settings.contains(&key) {
                bail!(
                    "--set-tolerances: the comparison groups packings by protocol.energy_low, \
                     protocol.energy_high and minimizer.force_tol (the file's scan); scan \
                     nothing else (dim, particles, parameters)"
                );
            }
            settings.push(key);
        }
        let plan = Plan {
            pairs: if q { 512 } else { 4096 },
            min_secs: if q { 0.002 } else { 0.05 },
            gap_models,
            tolerances,
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

/// Run `e` into `out` by the runner (resuming what is there); a sample
/// that failed is data for the report, any other error ends the command.
fn run_into(e: &Experiment, out: &Path, jobs: usize) -> Result<()> {
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
    if let Some(err) = report
        .failures
        .iter()
        .find(|err| !matches!(err, ExperimentError::Sample { .. }))
    {
        bail!("{}: {err}", out.display());
    }
    Ok(())
}

use jamkit_core::stats::mean;

fn opt(x: Option<f64>, fmt: impl Fn(f64) -> String) -> String {
    x.map(fmt).unwrap_or_default()
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

/// Run the whole benchmark: part 1 here, parts 2 and 3 by the runner and
/// `jamkit_report::accuracy`.
pub fn run(o: &Options) -> Result<()> {
    let plan = Plan::of(o)?;
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;
    let (date, commit, machine) = environment();
    let load_start = load();
    let t0 = Instant::now();

    eprintln!("part 1: pair evaluations");
    let pairs = bench_pairs(&plan)?;
    let fitted = slopes(&pairs);
    let studies = [
        (
            GAP_MODELS_FILE.0,
            &plan.gap_models,
            "gap_models",
            Study::GapModels,
        ),
        (
            TOLERANCES_FILE.0,
            &plan.tolerances,
            "tolerances",
            Study::Tolerances,
        ),
    ];
    for (k, (file, e, dir, _)) in studies.iter().enumerate() {
        eprintln!("part {}: {file}", k + 2);
        run_into(e, &o.runs.join(dir), o.jobs)?;
    }
    let total = t0.elapsed().as_secs_f64();
    let load_end = load();

    write_csvs(&o.out, &pairs, &fitted)?;
    figures(&o.out, &pairs)?;
    let mut sections = String::new();
    for (file, _, dir, study) in studies {
        sections.push_str(&accuracy::report(study, &[o.runs.join(dir)], &o.out, file)?);
    }

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
    md.push_str(&sections);
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

fn write_csvs(dir: &Path, pairs: &[PairRow], fitted: &[(GapModel, u32, f64, usize)]) -> Result<()> {
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

/// The jamming window of a `Jam` protocol, `(E_low, E_high)`.
fn window(protocol: &Protocol) -> (f64, f64) {
    match protocol {
        Protocol::Jam {
            energy_low,
            energy_high,
            ..
        } => (*energy_low, *energy_high),
        _ => (f64::NAN, f64::NAN),
    }
}

fn figures(dir: &Path, pairs: &[PairRow]) -> Result<()> {
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
