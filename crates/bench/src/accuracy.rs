//! `jamkit bench accuracy`: speed against error of the near-disk gap models
//! (`FirstOrder`, `SecondOrder`, `Exact`) and of FIRE's tolerances, for
//! `docs/reports/speed-vs-error.md`. One thread throughout (unless `--jobs`).
//!
//! A thin command that chains three things and writes their tables into
//! one document:
//!
//! 1. **Pairs**: the micro-benchmark of one pair evaluation per gap model
//!    ([`crate::pair`], also `jamkit bench pair` on its own).
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
//! Nothing is measured or compared here: this file checks the plan, runs,
//! and splices the tables.
//!
//! The two files are compiled in, so the command runs from any directory;
//! `--set-gap-models` / `--set-tolerances` edit them as `jamkit run --set`
//! does (`--quick` is a few such overrides). Everything else goes to `DIR`
//! (CSV, PNG + SVG figures, `tables.md`, default [`DEFAULT_OUT`]), and only
//! there: the manual's copy in `docs/speed-vs-error/` is that directory,
//! copied by hand.

use crate::output::{Print, environment, write};
use anyhow::{Context, Result, bail};
use jamkit_experiment::grid::value_text;
use jamkit_experiment::runner::{self, RunOptions};
use jamkit_experiment::schema::{Observable, Protocol};
use jamkit_experiment::{Experiment, ExperimentError, Log, overrides};
use jamkit_report::accuracy::{self, Study};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default output directory of the tables and figures.
pub const DEFAULT_OUT: &str = "out/bench-accuracy";
/// The default directory of the runner's runs (parts 2 and 3).
pub const DEFAULT_RUNS: &str = "out/accuracy";

/// The experiment file of part 2: its path in the repository and its text.
const GAP_MODELS_FILE: (&str, &str) = (
    "experiments/accuracy/gap_models.ron",
    include_str!("../../../experiments/accuracy/gap_models.ron"),
);
/// The experiment file of part 3 (one setting of the ladder).
const TOLERANCES_FILE: (&str, &str) = (
    "experiments/accuracy/tolerances.ron",
    include_str!("../../../experiments/accuracy/tolerances.ron"),
);
/// `--quick`: the overrides of the two files (before the user's own).
const QUICK_GAP_MODELS: [&str; 3] = ["particles=10", "samples=1", "params.delta=0.1"];
const QUICK_TOLERANCES: [&str; 2] = ["particles=12", "samples=2"];

/// What `jamkit bench accuracy` was asked for.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Output directory of the tables (tables.md), CSV files and figures;
    /// nothing else is written but the runs (--runs).
    #[arg(short, long, value_name = "DIR", default_value = DEFAULT_OUT)]
    pub out: PathBuf,
    /// Directory of the runner's runs of experiments/accuracy/*.ron
    /// (the gap models and the tolerances); a rerun into it resumes,
    /// reading back every packing it holds.
    #[arg(long, value_name = "DIR", default_value = DEFAULT_RUNS)]
    pub runs: PathBuf,
    /// Small sizes, for a smoke test (seconds): fewer pairs, and the
    /// files with --set particles=10 samples=1 params.delta=0.1 (gap
    /// models) and particles=12 samples=2 (tolerances).
    #[arg(long)]
    pub quick: bool,
    /// Override a field of experiments/accuracy/gap_models.ron, as
    /// `jamkit run --set` does: --set-gap-models samples=1.
    #[arg(long = "set-gap-models", value_name = "KEY=VALUE")]
    pub set_gap_models: Vec<String>,
    /// Override a field of experiments/accuracy/tolerances.ron (every
    /// setting of the ladder): --set-tolerances particles=64.
    #[arg(long = "set-tolerances", value_name = "KEY=VALUE")]
    pub set_tolerances: Vec<String>,
    /// Worker threads of the runs (packings in parallel; 1 keeps the
    /// wall times of one core). Results do not depend on it.
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
}

/// The two experiments, overrides applied and checked.
struct Plan {
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
        for p in &jamkit_experiment::Plan::new(&gap_models)
            .context("--set-gap-models")?
            .points
        {
            let key = (param(&p.params, "delta"), param(&p.params, "gap"));
            if key.0.is_none() || key.1.is_none() {
                bail!(
                    "--set-gap-models: family = {:?}: the comparison needs the parameters \
                     `delta` and `gap` (families fourier and fourier_sum)",
                    gap_models.family
                );
            }
            let n = param(&p.params, "n").and_then(|v| v.parse::<u32>().ok());
            let delta = key.0.as_deref().and_then(|v| v.parse::<f64>().ok());
            if gap_models.family == "fourier"
                && let (Some(n), Some(delta)) = (n, delta)
                && !crate::pair::convex(n, delta)?
            {
                bail!(
                    "--set-gap-models: params.delta = {delta} at n = {n} makes a non-convex \
                     outline (Δ(n + 1/n) ≥ 1); the comparison takes the convex exact gap \
                     (params.gap = Exact) as its reference: use a smaller params.delta"
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
        for p in &jamkit_experiment::Plan::new(&tolerances)
            .context("--set-tolerances")?
            .points
        {
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

/// Run the whole benchmark: part 1 by [`crate::pair`], parts 2 and 3 by
/// the runner and `jamkit_report::accuracy`; print the tables and write
/// them to `OUT/tables.md`.
pub fn run(o: &Options, print: Print) -> Result<()> {
    let plan = Plan::of(o)?;
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;
    let (commit, machine) = environment();
    let t0 = Instant::now();

    eprintln!("part 1: pair evaluations");
    let pair_md = crate::pair::measure(&o.out, o.quick, print)?;
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

    let mut sections = String::new();
    for (file, _, dir, study) in studies {
        sections.push_str(&accuracy::report(study, &[o.runs.join(dir)], &o.out, file)?);
    }

    let mut md = String::new();
    let args = arguments(o);
    let _ = writeln!(
        md,
        "Generated by `jamkit bench accuracy{args}` at commit `{commit}`, {machine}, one \
         thread per packing; {total:.0} s in all (packings the runs of `{}` already held \
         were read back, not timed again). Compare wall times within one run.",
        o.runs.display()
    );
    md.push('\n');
    md.push_str(&pair_md);
    md.push_str(&sections);
    print(&md);
    write(&o.out.join("tables.md"), &md)?;
    print(&format!(
        "written to {} (the runs: {})",
        o.out.display(),
        o.runs.display()
    ));
    Ok(())
}

/// The options that change the study, as the command line gives them
/// (` --quick --set-gap-models 'samples=1'`), for the tables' first line.
fn arguments(o: &Options) -> String {
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
    args
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        options: Options,
    }

    fn options(args: &[&str]) -> Options {
        let argv = std::iter::once("accuracy").chain(args.iter().copied());
        Cli::try_parse_from(argv).unwrap().options
    }

    #[test]
    fn the_default_output_is_outside_the_manual() {
        let o = options(&[]);
        assert_eq!(o.out, Path::new(DEFAULT_OUT));
        assert_eq!(o.runs, Path::new(DEFAULT_RUNS));
        assert!(!o.out.starts_with("docs") && !o.runs.starts_with("docs"));
        assert_eq!(o.jobs, 1);
    }

    #[test]
    fn quick_and_the_users_overrides_apply_in_that_order() {
        let sizes = |e: &Experiment| (e.particles.values(), e.samples);
        let plan = Plan::of(&options(&["--quick"])).unwrap();
        assert_eq!(sizes(&plan.gap_models), (vec![10], 1));
        assert_eq!(sizes(&plan.tolerances), (vec![12], 2));
        let o = options(&["--quick", "--set-gap-models", "particles=16"]);
        assert_eq!(sizes(&Plan::of(&o).unwrap().gap_models), (vec![16], 1));
        // Without --quick, the files as committed.
        let full = Plan::of(&options(&[])).unwrap();
        assert_eq!(sizes(&full.gap_models), (vec![64], 3));
        assert_eq!(sizes(&full.tolerances), (vec![256], 4));
    }

    #[test]
    fn a_plan_the_comparison_cannot_group_is_refused() {
        for (args, names) in [
            (vec!["--jobs", "0"], "--jobs 0"),
            (
                vec!["--set-gap-models", "particles=[8, 10]"],
                "params.delta and params.gap",
            ),
            (
                vec!["--set-gap-models", "observables=[Pressure]"],
                "Contacts",
            ),
            (
                vec!["--set-tolerances", "params.delta=[0.1, 0.2]"],
                "--set-tolerances",
            ),
        ] {
            let err = Plan::of(&options(&args)).err().map(|e| format!("{e:#}"));
            let err = err.unwrap_or_else(|| panic!("{args:?}: accepted"));
            assert!(err.contains(names), "{args:?}: {err}");
        }
    }

    #[test]
    fn the_tables_name_the_options_that_changed_the_study() {
        assert_eq!(arguments(&options(&["--jobs", "2"])), "");
        let o = options(&[
            "--quick",
            "--set-tolerances",
            "particles=64",
            "--set-gap-models",
            "samples=1",
        ]);
        assert_eq!(
            arguments(&o),
            " --quick --set-gap-models 'samples=1' --set-tolerances 'particles=64'"
        );
    }
}
