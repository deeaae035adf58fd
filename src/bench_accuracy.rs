//! `jamkit bench accuracy`: speed against error of the near-disk gap models
//! (`FirstOrder`, `SecondOrder`, `Exact`) and of FIRE's tolerances, for
//! `docs/speed-vs-error.md`. One thread throughout.
//!
//! 1. **Pairs**: per model, `n` and `Δ`, the time of one pair evaluation
//!    (gap and gradient, `Shape::contacts`) over a batch of random pairs
//!    near contact, and the largest and RMS error of the gap against
//!    `Exact` over the same pairs; fitted log–log slopes of the largest
//!    error against `Δ`.
//! 2. **Packings**: per model and `Δ` (`n = 2`), whole jammed packings
//!    (the paper's protocol) from the same random starts, and their
//!    differences in `φ_J`, `z_J`, `N_c` and rattlers from `Exact`.
//! 3. **Tolerances**: `FirstOrder`, `n = 2`, `Δ = 0.1`: FIRE's force
//!    tolerance and the jamming window against the change of `φ_J` and
//!    `N_c` from the tightest setting on the same start.
//!
//! Everything goes to `DIR` (CSV, PNG + SVG figures, `tables.md`); with the
//! default `DIR` the generated block of `docs/speed-vs-error.md` is
//! rewritten too.

use crate::bench::{packing_hash, random_scene};
use anyhow::{Context, Result, bail};
use jamkit_core::Shape;
use jamkit_core::Vector;
use jamkit_engine::{Fire, FireParams, JamParams, JamSearch, jam};
use jamkit_fourier::{Angle, FourierParams, NearDisk};
use jamkit_observe::summarize;
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
/// The document whose generated block the default run rewrites.
const DOC: &str = "docs/speed-vs-error.md";
/// [`DEFAULT_OUT`] relative to the directory of [`DOC`].
const LINK_DIR: &str = "speed-vs-error";
const BEGIN: &str = "<!-- generated: jamkit bench accuracy -->";
const END: &str = "<!-- end generated -->";

const MODELS: [GapModel; 3] = [GapModel::FirstOrder, GapModel::SecondOrder, GapModel::Exact];
const NS: [u32; 4] = [2, 3, 4, 5];
const DELTAS: [f64; 6] = [1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3];
/// Slopes are fitted over `Δ ≤` this (where every `n ≤ 5` is convex).
const FIT_MAX_DELTA: f64 = 0.1;
/// The two sizes of the binary mixture.
const SIZES: (f64, f64) = (0.5, 0.7);
/// Where `Exact` is drawn on the log axis of the speed–error figure.
const EXACT_FLOOR: f64 = 1e-16;

/// Bodies per packing of part 2 by default: an `Exact` packing costs
/// ~7.5 µs of CPU per body and FIRE step (~200× the first-order gap), so
/// one at N = 256 would take ~15 min; at N = 64 it takes ~1.3 min.
pub const PACKING_PARTICLES: usize = 64;

/// Where an unchanged φ_J is drawn on the log axis of the tolerance figure.
const ZERO_FLOOR: f64 = 1e-12;

/// FIRE force tolerances of part 3; the tightest that converges on a seed
/// (in the paper's window) is that seed's reference.
const FORCE_TOLS: [f64; 6] = [1e-20, 1e-22, 1e-24, 1e-25, 1e-26, 1e-28];
/// FIRE steps allowed per minimisation in part 3 (the default is 2·10⁷):
/// a tolerance below the round-off floor of the forces is never met, and
/// FIRE would run to the limit in every minimisation. A whole packing of
/// N = 256 takes ~4·10⁵ steps at the default tolerance.
const TOL_MAX_STEPS: u64 = 1_000_000;

/// Jamming windows `(E_low, E_high)` of part 3: the paper's, and one 100×
/// looser (FIRE's `energy_tol = 1e-16` stays below both; a tighter window
/// would have to move it too).
const WINDOWS: [(f64, f64); 2] = [(1e-16, 2e-16), (1e-14, 2e-14)];

/// What `jamkit bench accuracy` was asked for.
pub struct Options {
    /// Output directory.
    pub out: PathBuf,
    /// Small sizes, for a smoke test.
    pub quick: bool,
    /// Seeds of the packings of part 2 (default 1,2,3; quick: 1).
    pub seeds: Option<Vec<u64>>,
    /// Seeds of part 3 (default 1,2,3,4; quick: 1,2).
    pub tol_seeds: Option<Vec<u64>>,
    /// Bodies per packing of part 3 (default 256; quick: 12).
    pub particles: Option<usize>,
    /// Bodies per packing of part 2 (default 64, see [`PACKING_PARTICLES`];
    /// quick: 10).
    pub packing_particles: Option<usize>,
    /// Δ of the packings of part 2.
    pub packing_deltas: Option<Vec<f64>>,
}

/// Sizes of one run.
struct Plan {
    pairs: usize,
    min_secs: f64,
    particles: usize,
    packing_particles: usize,
    seeds: Vec<u64>,
    tol_seeds: Vec<u64>,
    packing_deltas: Vec<f64>,
}

impl Plan {
    fn of(o: &Options) -> Result<Self> {
        let q = o.quick;
        let plan = Plan {
            pairs: if q { 512 } else { 4096 },
            min_secs: if q { 0.002 } else { 0.05 },
            particles: o.particles.unwrap_or(if q { 12 } else { 256 }),
            packing_particles: o.packing_particles.unwrap_or(if q {
                10
            } else {
                PACKING_PARTICLES
            }),
            seeds: o
                .seeds
                .clone()
                .unwrap_or_else(|| if q { vec![1] } else { vec![1, 2, 3] }),
            tol_seeds: o
                .tol_seeds
                .clone()
                .unwrap_or_else(|| if q { vec![1, 2] } else { vec![1, 2, 3, 4] }),
            packing_deltas: o
                .packing_deltas
                .clone()
                .unwrap_or_else(|| if q { vec![0.1] } else { vec![0.01, 0.1] }),
        };
        if plan.particles < 4 {
            bail!("--particles {}: must be at least 4", plan.particles);
        }
        if plan.packing_particles < 4 {
            bail!(
                "--packing-particles {}: must be at least 4",
                plan.packing_particles
            );
        }
        if plan.seeds.is_empty() || plan.tol_seeds.is_empty() {
            bail!("--seeds / --tol-seeds: give at least one seed");
        }
        for &d in &plan.packing_deltas {
            if !(d > 0.0 && d < 1.0) {
                bail!("--packing-deltas {d}: each Δ must lie in (0, 1)");
            }
            if !shape(2, d, GapModel::FirstOrder)?.is_convex() {
                bail!(
                    "--packing-deltas {d}: the n = 2 outline is not convex there, \
                     so there is no Exact packing to compare with"
                );
            }
        }
        Ok(plan)
    }
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
#[derive(Clone)]
struct PackRow {
    seed: u64,
    start_hash: u64,
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
    hash: u64,
}

fn one_packing(
    s: NearDisk,
    particles: usize,
    seed: u64,
    fire: FireParams,
    jam_params: &JamParams,
) -> Result<PackRow> {
    let mut scene = random_scene::<2, _>(s, particles, seed, 0.1, 0.4)?;
    let start_hash = packing_hash(scene.packing());
    let mut fire = Fire::new(fire);
    let t = Instant::now();
    let result = match jam(&mut scene, &mut fire, jam_params) {
        Ok(out) => {
            let wall_s = t.elapsed().as_secs_f64();
            let threshold = scene.packing().shape.rattler_threshold();
            let sum = summarize(&mut scene, threshold);
            Ok(PackResult {
                wall_s,
                steps: out.fire_steps,
                phi: out.phi,
                z: sum.z_j,
                n_c: sum.n_contacts,
                rattlers: sum.n_rattlers,
                hash: packing_hash(scene.packing()),
            })
        }
        Err(e) => Err(e.to_string()),
    };
    Ok(PackRow {
        seed,
        start_hash,
        result,
    })
}

/// Part 2: `(Δ, model, rows)`, the Exact packings first.
type ModelRuns = Vec<(f64, GapModel, Vec<PackRow>)>;

fn bench_packings(plan: &Plan) -> Result<ModelRuns> {
    let mut runs = Vec::new();
    for &delta in &plan.packing_deltas {
        for model in [GapModel::Exact, GapModel::FirstOrder, GapModel::SecondOrder] {
            let mut rows = Vec::new();
            for &seed in &plan.seeds {
                let row = one_packing(
                    shape(2, delta, model)?,
                    plan.packing_particles,
                    seed,
                    FireParams::default(),
                    &study_jam_params(),
                )?;
                progress(
                    &format!("packing Δ = {delta} {} seed {seed}", model.name()),
                    &row,
                );
                rows.push(row);
            }
            runs.push((delta, model, rows));
        }
    }
    // The same seed must give the same start whatever the model.
    for (delta, model, rows) in &runs {
        let exact = reference_rows(&runs, *delta);
        for (r, e) in rows.iter().zip(exact) {
            if r.start_hash != e.start_hash {
                bail!(
                    "Δ = {delta}, {}: seed {} started from another configuration than Exact",
                    model.name(),
                    r.seed
                );
            }
        }
    }
    Ok(runs)
}

/// The jamming search of the study: the bisection it was measured with
/// (docs/speed-vs-error.md), kept when the default became `Extrapolated`
/// so that the documented tables come out again bit for bit.
fn study_jam_params() -> JamParams {
    JamParams {
        search: JamSearch::Bisection,
        ..JamParams::default()
    }
}

fn reference_rows(runs: &ModelRuns, delta: f64) -> &[PackRow] {
    runs.iter()
        .find(|(d, m, _)| *d == delta && *m == GapModel::Exact)
        .map(|(_, _, r)| r.as_slice())
        .unwrap_or(&[])
}

fn progress(what: &str, row: &PackRow) {
    match &row.result {
        Ok(r) => eprintln!(
            "{what}: phi_J = {:.6}, N_c = {}, {:.2} s",
            r.phi, r.n_c, r.wall_s
        ),
        Err(e) => eprintln!("{what}: failed: {e}"),
    }
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

fn bench_tolerances(plan: &Plan) -> Result<TolRuns> {
    let mut runs = Vec::new();
    for &window in &WINDOWS {
        for &force_tol in &FORCE_TOLS {
            let mut rows = Vec::new();
            for &seed in &plan.tol_seeds {
                let fire = FireParams {
                    force_tol,
                    max_steps: TOL_MAX_STEPS,
                    ..FireParams::default()
                };
                let jp = JamParams {
                    energy_low: window.0,
                    energy_high: window.1,
                    ..study_jam_params()
                };
                let row = one_packing(
                    shape(2, 0.1, GapModel::FirstOrder)?,
                    plan.particles,
                    seed,
                    fire,
                    &jp,
                )?;
                progress(
                    &format!(
                        "tolerance window {:e} force_tol {force_tol:e} seed {seed}",
                        window.0
                    ),
                    &row,
                );
                rows.push(row);
            }
            runs.push(((window, force_tol), rows));
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
pub fn run(o: &Options) -> Result<()> {
    let plan = Plan::of(o)?;
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;
    let (date, commit, machine) = environment();
    let load_start = load();
    let t0 = Instant::now();

    eprintln!("part 1: pair evaluations");
    let pairs = bench_pairs(&plan)?;
    let fitted = slopes(&pairs);
    eprintln!("part 2: packings");
    let packs = bench_packings(&plan)?;
    eprintln!("part 3: tolerances");
    let tols = bench_tolerances(&plan)?;
    let total = t0.elapsed().as_secs_f64();
    let load_end = load();

    write_csvs(&o.out, &plan, &pairs, &fitted, &packs, &tols)?;
    figures(&o.out, &pairs, &tols)?;

    let mut md = String::new();
    let args = if o.quick { " --quick" } else { "" };
    let _ = writeln!(
        md,
        "Generated by `jamkit bench accuracy{args}` on {date}, commit `{commit}`, \
         {machine}, one thread; load average (1, 5, 15 min) {load_start} at the start \
         and {load_end} at the end; {total:.0} s in all. Wall times are from a shared \
         machine: compare them within one run."
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
    out!("written to {}", o.out.display());
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
    plan: &Plan,
    pairs: &[PairRow],
    fitted: &[(GapModel, u32, f64, usize)],
    packs: &ModelRuns,
    tols: &TolRuns,
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

    let header = "seed,start_hash,wall_s,fire_steps,phi_j,z_j,n_c,rattlers,packing_hash,error\n";
    let line = |s: &mut String, prefix: String, r: &PackRow| {
        let _ = match &r.result {
            Ok(p) => writeln!(
                s,
                "{prefix},{},{:016x},{:.3},{},{:.9},{:.5},{},{},{:016x},",
                r.seed, r.start_hash, p.wall_s, p.steps, p.phi, p.z, p.n_c, p.rattlers, p.hash
            ),
            Err(e) => writeln!(
                s,
                "{prefix},{},{:016x},,,,,,,,\"{}\"",
                r.seed,
                r.start_hash,
                e.replace(['"', ','], ";")
            ),
        };
    };
    let mut s = format!("model,n,delta,particles,{header}");
    for (delta, model, rows) in packs {
        for r in rows {
            line(
                &mut s,
                format!("{},2,{delta},{}", model.name(), plan.packing_particles),
                r,
            );
        }
    }
    write(&dir.join("packings.csv"), &s)?;

    let mut s = format!("energy_low,energy_high,force_tol,particles,{header}");
    for (((lo, hi), ft), rows) in tols {
        for r in rows {
            line(
                &mut s,
                format!("{lo:e},{hi:e},{ft:e},{}", plan.particles),
                r,
            );
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

fn packing_table(plan: &Plan, runs: &ModelRuns) -> String {
    let mut md = String::new();
    let seeds: Vec<String> = plan.seeds.iter().map(|s| s.to_string()).collect();
    let _ = writeln!(
        md,
        "## Packings\n\n\
         Near-disks n = 2, N = {}{}, the paper's protocol (FIRE force tolerance 1e-25, \
         window 1e-16 < V/N < 2e-16), seeds {}: one packing per seed and model, all \
         from the same random start per seed (checked by a hash of the start). \
         Means over seeds; \"vs Exact\": the largest difference over seeds from the \
         Exact packing of the same seed (signed mean in brackets); \"sd\": the \
         standard deviation of φ_J across seeds, the statistical error one pays anyway.\n",
        plan.packing_particles,
        if plan.packing_particles < plan.particles {
            " (not more: Exact packings take minutes each at N = 256; the N = 256 \
             comparison is the Fig. 5 gap-model run of docs/reproduction.md)"
        } else {
            ""
        },
        seeds.join(", ")
    );
    md.push_str(
        "| Δ | model | ok | wall s | FIRE steps | φ_J | sd φ_J | z_J | N_c | rattlers \
         | max \\|Δφ_J\\| (mean Δφ_J) | max \\|Δz_J\\| | max \\|ΔN_c\\| | max \\|Δrattlers\\| |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (delta, model, rows) in runs {
        let ok = ok_results(rows);
        let col = |f: fn(&PackResult) -> f64, digits: usize| {
            fixed(mean(&ok.iter().map(f).collect::<Vec<_>>()), digits)
        };
        let phis: Vec<f64> = ok.iter().map(|r| r.phi).collect();
        let diffs = if *model == GapModel::Exact {
            None
        } else {
            Some(differences(rows, reference_rows(runs, *delta)))
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
            "| {delta} | {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {dphi} | {} | {} | {} |",
            model.name(),
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
    for (delta, model, rows) in runs {
        for r in rows {
            if let Err(e) = &r.result {
                let _ = writeln!(
                    md,
                    "\nΔ = {delta}, {}, seed {}: failed: {e}",
                    model.name(),
                    r.seed
                );
            }
        }
    }
    md.push_str("\nPer packing: [packings.csv](packings.csv).\n\n");
    md
}

fn tolerance_table(plan: &Plan, runs: &TolRuns) -> String {
    let mut md = String::new();
    let seeds: Vec<String> = plan.tol_seeds.iter().map(|s| s.to_string()).collect();
    let refs = tol_reference(runs);
    let reference: Vec<PackRow> = refs.iter().map(|(r, _)| r.clone()).collect();
    let ref_text: Vec<String> = refs
        .iter()
        .map(|(r, ft)| format!("seed {}: {ft:.0e}", r.seed))
        .collect();
    let _ = writeln!(
        md,
        "## Tolerances\n\n\
         FirstOrder near-disks n = 2, Δ = 0.1, N = {}, seeds {}: FIRE's force \
         tolerance (stop when Σ(∂V/∂q)² falls below it; the default is 1e-25) and \
         the jamming window (the paper's 1e-16 < V/N < 2e-16, and one 100× looser, \
         the shortcut a user would try; a tighter one would need FIRE's \
         energy_tol = 1e-16 moved as well, mixing two changes). At most {TOL_MAX_STEPS} \
         FIRE steps per minimisation: a tolerance FIRE cannot reach fails. Differences \
         are from the tightest force tolerance that converged in the paper's window on \
         the same seed ({}), largest over seeds; \"sd φ_J\" is the spread across seeds \
         at that setting.\n",
        plan.particles,
        seeds.join(", "),
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

fn figures(dir: &Path, pairs: &[PairRow], tols: &TolRuns) -> Result<()> {
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
        title: "FIRE tolerance: time against change of φ_J (FirstOrder, n = 2, Δ = 0.1)".into(),
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
