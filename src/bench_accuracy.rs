//! `jamkit bench accuracy`: speed against error of the near-disk gap models
//! (`FirstOrder`, `SecondOrder`, `Exact`) and of FIRE's tolerances, for
//! `docs/reports/speed-vs-error.md`. One thread throughout (unless `--jobs`).
//!
//! A thin command that chains three things and writes their tables into
//! one document:
//!
//! 1. **Pairs**: the micro-benchmark of one pair evaluation per gap model
//!    (`bench_pair.rs`, also `jamkit bench pair` on its own).
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
//! (CSV, PNG + SVG figures, `tables.md`); with the default `DIR` the
//! generated block of `docs/reports/speed-vs-error.md` is rewritten too.

use anyhow::{Context, Result, bail};
use jamkit_experiment::grid::{self, value_text};
use jamkit_experiment::runner::{self, RunOptions};
use jamkit_experiment::schema::{Observable, Protocol};
use jamkit_experiment::{Experiment, ExperimentError, Log, overrides};
use jamkit_report::accuracy::{self, Study};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default output directory; writing there also rewrites the
/// generated block of [`DOC`].
pub const DEFAULT_OUT: &str = "docs/speed-vs-error";
/// The default directory of the runner's runs (parts 2 and 3).
pub const DEFAULT_RUNS: &str = "out/accuracy";
/// The document whose generated block the default run rewrites.
const DOC: &str = "docs/reports/speed-vs-error.md";
/// [`DEFAULT_OUT`] relative to the directory of [`DOC`].
const LINK_DIR: &str = "../speed-vs-error";
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

/// The commit (marked when the tree has uncommitted changes) and the
/// machine (CPU model and cores) a benchmark ran on.
pub(crate) fn environment() -> (String, String) {
    let cmd = |prog: &str, args: &[&str]| {
        std::process::Command::new(prog)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
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
    (commit, format!("{cpu}, {cores} cores"))
}

/// Run the whole benchmark: part 1 by `bench_pair`, parts 2 and 3 by the
/// runner and `jamkit_report::accuracy`.
pub fn run(o: &Options) -> Result<()> {
    let plan = Plan::of(o)?;
    std::fs::create_dir_all(&o.out).with_context(|| format!("creating {}", o.out.display()))?;
    let (commit, machine) = environment();
    let t0 = Instant::now();

    eprintln!("part 1: pair evaluations");
    let pair_md = crate::bench_pair::measure(&o.out, o.quick)?;
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
        "Generated by `jamkit bench accuracy{args}` at commit `{commit}`, {machine}, one \
         thread per packing; {total:.0} s in all (packings the runs of `{}` already held \
         were read back, not timed again). Compare wall times within one run.",
        o.runs.display()
    );
    md.push('\n');
    md.push_str(&pair_md);
    md.push_str(&sections);
    out!("{md}");
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
