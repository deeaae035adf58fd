//! The runner: every sample of an experiment, in parallel, resumable.
//!
//! Each sample is independent and seeded (`ChaCha8`, portable across
//! platforms), and is computed by one thread from start to end, so the
//! packing does not depend on `--jobs`. Samples whose file already exists in
//! the output directory are read back instead of recomputed. What one
//! sample does is the `sample` module's; here are the loop over samples,
//! the resume and settings checks, the locks, the failed samples' states
//! and the tables.

use crate::batchlog::{BatchLog, Log};
use crate::error::ExperimentError;
use crate::grid::{self, Job};
use crate::lock;
use crate::outcome::Outcome;
use crate::plan::Plan;
use crate::schema::{Experiment, Observable};
use jamkit_format::{self as format, PackingFile};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Worker threads (`None`: all cores).
    pub jobs: Option<usize>,
    /// What to tell while running: a bar, batch-log lines, or nothing
    /// ([`Log::for_stderr`] picks by whether stderr is a terminal).
    pub log: Log,
    /// Run only this part of the jobs (`--shard I/K`). A part writes its
    /// packings and `experiment.ron` but no tables (they would hold only
    /// its own packings): a run without a shard into the same directory
    /// reuses every packing and writes them.
    pub shard: Option<grid::Shard>,
}

/// What a run produced.
#[derive(Debug)]
pub struct RunReport {
    /// Every packing made or reused, in grid order.
    pub packings: Vec<PackingFile>,
    /// How many were read back from an earlier run.
    pub reused: usize,
    /// Samples that failed, with their errors.
    pub failures: Vec<ExperimentError>,
    /// Per-point summaries, in grid order.
    pub summaries: Vec<format::PointSummary>,
    /// Packings another process was making (their lock was held): left to
    /// it; a later run gathers them. No tables are written while any is.
    pub elsewhere: Vec<String>,
    /// Samples not started because [`Hooks::stop`] was set: a rerun makes
    /// them. No tables but `results.csv` are written while any is.
    pub stopped: Vec<String>,
}

/// What a caller watching a run (the Python module) may ask of it.
#[derive(Clone, Copy, Default)]
pub struct Hooks<'a> {
    /// Once set, samples not yet started are left unmade
    /// ([`RunReport::stopped`]); a sample under way finishes and is saved.
    pub stop: Option<&'a AtomicBool>,
    /// Called as each sample ends, made, read back or failed, from the
    /// thread that ran it, with its id; not called for samples left to
    /// another process or stopped.
    #[allow(clippy::type_complexity)]
    pub finished: Option<&'a (dyn Fn(&str, Result<&PackingFile, &ExperimentError>) + Sync)>,
}

/// Run an experiment into `options.out`.
pub fn run(experiment: &Experiment, options: &RunOptions) -> Result<RunReport, ExperimentError> {
    run_with(experiment, options, Hooks::default())
}

/// [`run`], watched by `hooks`.
pub fn run_with(
    experiment: &Experiment,
    options: &RunOptions,
    hooks: Hooks<'_>,
) -> Result<RunReport, ExperimentError> {
    let mut plan = Plan::new(experiment)?;
    if let Some(shard) = options.shard {
        plan.keep_part(shard);
    }
    execute(&plan, options, hooks)
}

/// Run the jobs of `plan` into `options.out`, watched by `hooks`.
pub fn execute(
    plan: &Plan,
    options: &RunOptions,
    hooks: Hooks<'_>,
) -> Result<RunReport, ExperimentError> {
    let (experiment, jobs) = (&plan.experiment, &plan.jobs);
    let packing_dir = options.out.join("packings");
    refuse_other_settings(jobs, &packing_dir)?;
    std::fs::create_dir_all(&packing_dir).map_err(|e| ExperimentError::io(&packing_dir, e))?;
    let effective = ron::ser::to_string_pretty(experiment, ron::ser::PrettyConfig::default())
        .expect("experiment serialises");
    let header = format!("// {}\n", format::provenance::describe());
    format::write_atomic(
        &options.out.join("experiment.ron"),
        (header + &effective).as_bytes(),
    )?;

    let log = BatchLog::new(options.log, jobs.len());
    // The packings finished so far, in grid order and without their
    // configurations, for `results.csv` as the run goes (not for a part:
    // its table would hold its own packings only).
    let order: HashMap<&str, usize> = jobs
        .iter()
        .enumerate()
        .map(|(k, j)| (j.id.as_str(), k))
        .collect();
    let finished: Mutex<BTreeMap<usize, PackingFile>> = Mutex::new(BTreeMap::new());
    let table_so_far = |job: &Job, file: &PackingFile| -> Result<(), ExperimentError> {
        if options.shard.is_some() {
            return Ok(());
        }
        let mut done = finished.lock().unwrap_or_else(|e| e.into_inner());
        done.insert(order[job.id.as_str()], format::without_configuration(file));
        let rows: Vec<PackingFile> = done.values().cloned().collect();
        format::write_atomic(
            &options.out.join("results.csv"),
            format::results_csv(&rows, &experiment.scan_paths()).as_bytes(),
        )?;
        Ok(())
    };
    let make = |job: &Job| -> Result<Outcome, ExperimentError> {
        let path = packing_dir.join(format!("{}.json", job.id));
        let wanted = &job.settings;
        let finished = || {
            PackingFile::load_matching(&path, wanted)
                .filter(|done| covers(&stored(done), experiment))
        };
        if let Some(done) = finished() {
            if experiment.output.extxyz && !xyz_path(&path).exists() {
                write_extxyz(&done, &path)?;
            }
            return Ok(Outcome::Done(Box::new(done), true));
        }
        // Held until the packing is saved or has failed.
        let _held = match lock::claim(&packing_dir, &job.id)? {
            lock::Claim::Mine(held) => held,
            lock::Claim::Busy(holder) => return Ok(Outcome::Elsewhere(holder)),
        };
        // Another process may have finished it since the first look.
        let done = PackingFile::load_matching(&path, wanted);
        let (file, eigen, reused) = match done {
            Some(done) if covers(&stored(&done), experiment) => {
                if experiment.output.extxyz && !xyz_path(&path).exists() {
                    write_extxyz(&done, &path)?;
                }
                return Ok(Outcome::Done(Box::new(done), true));
            }
            // Same packing, other observables: measure them on the saved
            // configuration instead of making it again, keeping the ones
            // measured before (so that experiments sharing an output
            // directory add up their observables).
            Some(done) if done.positions.len() == done.particles => {
                let mut merged = experiment.clone();
                merged.observables = union(&stored(&done), &experiment.observables);
                let (file, eigen) = plan
                    .remeasure(&merged, job, done)
                    .map_err(|err| kept_unmeasured(err, &path))?;
                (file, eigen, true)
            }
            _ => {
                let jammed = plan
                    .jam(job, log.begin(&job.id))
                    .map_err(|err| keep_failed_state(err, &packing_dir))?;
                // The packing first, without observables (its file lists
                // none, so a rerun measures them on it instead of taking
                // it for finished): a measurement that fails, or a process
                // killed while measuring, leaves it on disk.
                jammed.file.save(&path)?;
                let (file, eigen) = plan
                    .measure(jammed)
                    .map_err(|err| measuring_failed(err, &packing_dir, &path))?;
                (file, eigen, false)
            }
        };
        // The eigenvalues first: a packing file that holds every observable
        // of the run means its sample is done.
        if let Some(table) = eigen {
            let dir = options.out.join("eigenvalues");
            std::fs::create_dir_all(&dir).map_err(|e| ExperimentError::io(&dir, e))?;
            format::write_atomic(&dir.join(format!("{}.csv", job.id)), table.as_bytes())?;
        }
        if experiment.output.extxyz {
            write_extxyz(&file, &path)?;
        }
        file.save(&path)?;
        // A stalled configuration from an earlier attempt is stale now.
        let _ = std::fs::remove_file(failed_path(&packing_dir, &job.id));
        Ok(Outcome::Done(Box::new(file), reused))
    };
    let work = |job: &Job| -> Result<Outcome, ExperimentError> {
        if hooks.stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
            return Ok(Outcome::Stopped);
        }
        let made = make(job).and_then(|outcome| {
            if let Outcome::Done(file, _) = &outcome {
                table_so_far(job, file)?;
            }
            Ok(outcome)
        });
        log.finish(&job.id, &made);
        if let Some(finished) = hooks.finished {
            match &made {
                Ok(Outcome::Done(file, _)) => finished(&job.id, Ok(file)),
                Err(e) => finished(&job.id, Err(e)),
                Ok(_) => {}
            }
        }
        made
    };
    let results: Vec<Result<Outcome, ExperimentError>> = std::thread::scope(|s| {
        let watcher = s.spawn(|| log.watch());
        let results = match options.jobs {
            Some(threads) => rayon::ThreadPoolBuilder::new()
                .num_threads(threads.max(1))
                .build()
                .expect("thread pool")
                .install(|| jobs.par_iter().map(work).collect()),
            None => jobs.par_iter().map(work).collect(),
        };
        log.close();
        watcher.thread().unpark();
        results
    });

    let mut packings = Vec::new();
    let mut failures = Vec::new();
    let mut elsewhere = Vec::new();
    let mut stopped = Vec::new();
    let mut reused = 0;
    for (r, job) in results.into_iter().zip(jobs) {
        match r {
            Ok(Outcome::Done(f, was_reused)) => {
                reused += usize::from(was_reused);
                packings.push(*f);
            }
            Ok(Outcome::Elsewhere(_)) => elsewhere.push(job.id.clone()),
            Ok(Outcome::Stopped) => stopped.push(job.id.clone()),
            Err(e) => failures.push(e),
        }
    }
    let groups = group_by_point(plan, &packings);
    let summaries = format::summarize_points(&groups);
    if options.shard.is_some() || !elsewhere.is_empty() || !stopped.is_empty() {
        return Ok(RunReport {
            packings,
            reused,
            failures,
            summaries,
            elsewhere,
            stopped,
        });
    }
    write_tables(experiment, &packings, &groups, &options.out)?;
    Ok(RunReport {
        packings,
        reused,
        failures,
        summaries,
        elsewhere,
        stopped,
    })
}

/// Refuse to run into a directory holding a packing of these jobs made
/// with other settings, naming the first that differs (`lock` module).
fn refuse_other_settings(jobs: &[Job], packing_dir: &Path) -> Result<(), ExperimentError> {
    for job in jobs {
        let path = packing_dir.join(format!("{}.json", job.id));
        let Some(old) = PackingFile::load(&path) else {
            continue;
        };
        if let Some((key, here, mut there)) = lock::first_difference(&job.settings, &old.settings) {
            if let Some(former) = former_default(&key, &there) {
                there = former.to_string();
            }
            return Err(ExperimentError::SettingsDiffer {
                file: path.display().to_string(),
                key,
                here,
                there,
            });
        }
    }
    Ok(())
}

/// A packing's setting that was jamkit's default before today's, said
/// with how to resume such packings. Where the settings leave a value out
/// so that packings made before it existed resume (`sample::settings`),
/// the packing records it as `(not set)`.
fn former_default(key: &str, there: &str) -> Option<&'static str> {
    match (key, there) {
        // Packings of the paper's summed force rule, the default before `Max`.
        ("minimizer.force_criterion", "\"Sum\"") => Some(
            "\"Sum\" (the default before \"Max\": add `force_criterion: Sum` to the \
             minimizer, or `--set minimizer.force_criterion=Sum`, to resume them)",
        ),
        // Packings of the extrapolated search, the default before `Adaptive`.
        ("protocol.Jam.search" | "protocol.AboveJam.search", "\"Extrapolated\"") => Some(
            "\"Extrapolated\" (the default before \"Adaptive\": add `search: Extrapolated` \
             to the protocol, or `--set protocol.search=Extrapolated`, to resume them)",
        ),
        (_, "(not set)") => unwritten_setting(key),
        _ => None,
    }
}

/// What a setting that a packing does not record stood for.
fn unwritten_setting(key: &str) -> Option<&'static str> {
    match key {
        // Bisection packings record no search (`protocol_settings`).
        "protocol.Jam.search" => Some(
            "\"Bisection\" (not written; the default before \"Extrapolated\": \
             add `search: Bisection` to the protocol to resume them)",
        ),
        // Plain-mass packings record no masses (`grid::minimizer_settings`).
        "minimizer.masses" => Some(
            "\"Plain\" (not written; the default before the family's: \
             add `masses: Plain` to the minimizer to resume them)",
        ),
        // Packings of `rejams: 0`, the default before 2, record none
        // (`grid::protocol_settings`).
        "protocol.AboveJam.rejams" => Some(
            "0 (not written; the default before 2: add `rejams: 0` to the \
             protocol, or `--set protocol.rejams=0`, to resume them)",
        ),
        // Packings made without the saddle escape record none
        // (`grid::protocol_settings`).
        "protocol.Jam.escape_saddles" => Some(
            "false (not written; the default before true: add \
             `escape_saddles: false` to the protocol, or \
             `--set protocol.escape_saddles=false`, to resume them)",
        ),
        // Packings made without the unjamming forecast record none
        // (`grid::minimizer_settings`).
        "minimizer.unjam_forecast" => Some(
            "false (not written; the default before true: add \
             `unjam_forecast: false` to the minimizer, or \
             `--set minimizer.unjam_forecast=false`, to resume them)",
        ),
        // Packings made without the plateau escape record none
        // (`grid::minimizer_settings`).
        "minimizer.escape_plateaus" => Some(
            "false (not written; the default before true: add \
             `escape_plateaus: false` to the minimizer, or \
             `--set minimizer.escape_plateaus=false`, to resume them)",
        ),
        // Packings made without the stiff-mode check of `Δt_max` record
        // none (`grid::minimizer_settings`).
        "minimizer.stable_dt" => Some(
            "false (not written; the default before true: add \
             `stable_dt: false` to the minimizer, or \
             `--set minimizer.stable_dt=false`, to resume them)",
        ),
        // Packings without L-BFGS record none (`sample::minimizer_settings`).
        "minimizer.lbfgs" => Some(
            "None (not written; the default before the family's: \
             add `lbfgs: None` to the minimizer, or \
             `--set minimizer.lbfgs=None`, to resume them)",
        ),
        _ => None,
    }
}

/// `packings/<id>.xyz` beside `packings/<id>.json`.
fn xyz_path(json: &Path) -> PathBuf {
    json.with_extension("xyz")
}

/// The packing's extended XYZ frame (`output.extxyz`), written atomically.
fn write_extxyz(file: &PackingFile, json: &Path) -> Result<(), ExperimentError> {
    let frame = crate::extxyz::frame(file)?;
    format::write_atomic(&xyz_path(json), frame.as_bytes())?;
    Ok(())
}

/// Where the configuration of a failed sample goes.
pub fn failed_path(packing_dir: &Path, id: &str) -> PathBuf {
    packing_dir.join(format!("{id}.failed.json"))
}

/// A sample whose observables failed on its freshly saved packing. A
/// failed shear stabilisation (an error carrying the fixed-box packing as
/// its `state`) leaves no packing file, as a failed minimisation does: its
/// state is kept as `<id>.failed.json`, and a rerun, with other
/// `protocol.stabilise` settings too, tries the sample again. Any other
/// failure keeps the packing at `path` and says so.
fn measuring_failed(err: ExperimentError, packing_dir: &Path, path: &Path) -> ExperimentError {
    match err {
        ExperimentError::Sample {
            state: Some(_),
            saved: None,
            ..
        } => {
            let _ = std::fs::remove_file(path);
            keep_failed_state(err, packing_dir)
        }
        other => kept_unmeasured(other, path),
    }
}

/// A measuring error with the path of the packing it leaves on disk
/// without the observables that failed.
fn kept_unmeasured(err: ExperimentError, path: &Path) -> ExperimentError {
    match err {
        ExperimentError::Sample {
            sample,
            source,
            state,
            saved,
            observable: Some(observable),
            kept: None,
        } => ExperimentError::Sample {
            sample,
            source,
            state,
            saved,
            observable: Some(observable),
            kept: Some(path.display().to_string()),
        },
        other => other,
    }
}

/// Save the configuration a failed sample stopped at (if it carries one)
/// as `<id>.failed.json` and say where in the error. A failure to save it
/// is mentioned instead; the sample's own error is what matters.
fn keep_failed_state(err: ExperimentError, packing_dir: &Path) -> ExperimentError {
    match err {
        ExperimentError::Sample {
            sample,
            source,
            state: Some(state),
            saved: None,
            observable,
            kept,
        } => {
            let path = failed_path(packing_dir, &sample);
            let saved = match state.save(&path) {
                Ok(()) => path.display().to_string(),
                Err(e) => format!("nowhere: saving it failed ({e})"),
            };
            ExperimentError::Sample {
                sample,
                source,
                state: None,
                saved: Some(saved),
                observable,
                kept,
            }
        }
        other => other,
    }
}

/// The tables of several experiment files run one after the other into
/// the same directory (`jamkit run A.ron B.ron --out DIR`), which each
/// run's own tables would leave holding the last file's packings only:
/// every packing of every run, in the order the files first made or read
/// it (a packing that two files share appears once, with the measures of
/// the last run that touched it), and the points of all the files, a point
/// that two files share once. Returns the number of packings.
pub fn tables_of_runs(
    runs: &[(&Experiment, &RunReport)],
    out: &Path,
) -> Result<usize, ExperimentError> {
    let mut order: Vec<&str> = Vec::new();
    let mut latest: HashMap<&str, &PackingFile> = HashMap::new();
    for (_, report) in runs {
        for f in &report.packings {
            if latest.insert(f.id.as_str(), f).is_none() {
                order.push(f.id.as_str());
            }
        }
    }
    let packings: Vec<PackingFile> = order.iter().map(|id| latest[id].clone()).collect();
    let mut labels: Vec<(String, Vec<String>)> = Vec::new();
    for (experiment, _) in runs {
        let plan = Plan::new(experiment)?;
        let jobs = &plan.jobs;
        for p in &plan.points {
            let label = p.label(&experiment.family);
            let at = match labels.iter().position(|(l, _)| *l == label) {
                Some(at) => at,
                None => {
                    labels.push((label, Vec::new()));
                    labels.len() - 1
                }
            };
            for j in jobs.iter().filter(|j| j.point == p.index) {
                if !labels[at].1.contains(&j.id) {
                    labels[at].1.push(j.id.clone());
                }
            }
        }
    }
    let by_id: HashMap<&str, &PackingFile> = packings.iter().map(|f| (f.id.as_str(), f)).collect();
    let groups: Vec<(String, Vec<&PackingFile>)> = labels
        .into_iter()
        .map(|(label, ids)| {
            let members = ids
                .iter()
                .filter_map(|id| by_id.get(id.as_str()).copied())
                .collect();
            (label, members)
        })
        .filter(|(_, m): &(String, Vec<&PackingFile>)| !m.is_empty())
        .collect();
    let spectrum = runs.iter().any(|(e, _)| e.spectrum().is_some());
    let gaps = runs.iter().any(|(e, _)| e.gaps().is_some());
    // Every file's scanned settings, each path once, in the files' order.
    let mut scanned: Vec<String> = Vec::new();
    for (experiment, _) in runs {
        for path in experiment.scan_paths() {
            if !scanned.contains(&path) {
                scanned.push(path);
            }
        }
    }
    write_table_files(&packings, &groups, (spectrum, gaps), &scanned, out)?;
    Ok(packings.len())
}

/// The tables of a whole run in `out`: `results.csv`, `summary.csv`, and
/// `dos.csv` / `gaps.csv` where the experiment measures them (one plain run
/// and `jamkit merge` write them alike).
fn write_tables(
    experiment: &Experiment,
    packings: &[PackingFile],
    groups: &[(String, Vec<&PackingFile>)],
    out: &Path,
) -> Result<(), ExperimentError> {
    let measured = (experiment.spectrum().is_some(), experiment.gaps().is_some());
    write_table_files(packings, groups, measured, &experiment.scan_paths(), out)
}

/// [`write_tables`] with what was measured given as `(spectrum, gaps)`
/// and the scanned setting paths as `scanned`.
fn write_table_files(
    packings: &[PackingFile],
    groups: &[(String, Vec<&PackingFile>)],
    (spectrum, gaps): (bool, bool),
    scanned: &[String],
    out: &Path,
) -> Result<(), ExperimentError> {
    format::write_atomic(
        &out.join("results.csv"),
        format::results_csv(packings, scanned).as_bytes(),
    )?;
    format::write_atomic(
        &out.join("summary.csv"),
        format::summary_csv(groups).as_bytes(),
    )?;
    if spectrum {
        format::write_atomic(&out.join("dos.csv"), format::dos_csv(groups).as_bytes())?;
    }
    if gaps {
        format::write_atomic(&out.join("gaps.csv"), format::gaps_csv(groups).as_bytes())?;
    }
    Ok(())
}

/// The grid's points and jobs of `experiment`, and the tables of
/// `packings` (in grid order) written into `out`: the end of a run, for
/// `jamkit merge`.
pub(crate) fn tables_of(
    experiment: &Experiment,
    packings: &[PackingFile],
    out: &Path,
) -> Result<(), ExperimentError> {
    let measured = (experiment.spectrum().is_some(), experiment.gaps().is_some());
    tables_measured(experiment, packings, measured, out)
}

/// [`tables_of`] with what was measured, `(spectrum, gaps)`, given: an
/// archive's packings may hold measures of other files run into the same
/// directory.
pub(crate) fn tables_measured(
    experiment: &Experiment,
    packings: &[PackingFile],
    measured: (bool, bool),
    out: &Path,
) -> Result<(), ExperimentError> {
    let groups = group_by_point(&Plan::new(experiment)?, packings);
    write_table_files(packings, &groups, measured, &experiment.scan_paths(), out)
}

/// The packings of each point of `plan` with the point's label, in grid
/// order; points with none left out.
fn group_by_point<'a>(
    plan: &Plan,
    packings: &'a [PackingFile],
) -> Vec<(String, Vec<&'a PackingFile>)> {
    plan.points
        .iter()
        .map(|p| {
            let ids: Vec<&str> = plan
                .jobs
                .iter()
                .filter(|j| j.point == p.index)
                .map(|j| j.id.as_str())
                .collect();
            let members = packings
                .iter()
                .filter(|f| ids.contains(&f.id.as_str()))
                .collect();
            (p.label(&plan.experiment.family), members)
        })
        .filter(|(_, m): &(String, Vec<&PackingFile>)| !m.is_empty())
        .collect()
}

/// The observables a packing file holds (none if they do not parse).
pub(crate) fn stored(file: &PackingFile) -> Vec<Observable> {
    serde_json::from_value(file.observables.clone()).unwrap_or_default()
}

/// Whether `have` holds every observable `experiment` asks for, with the
/// same options.
pub(crate) fn covers(have: &[Observable], experiment: &Experiment) -> bool {
    experiment.observables.iter().all(|o| have.contains(o))
}

/// `wanted`, plus the observables of `have` of a kind `wanted` does not
/// list (a kind listed in both takes `wanted`'s options).
fn union(have: &[Observable], wanted: &[Observable]) -> Vec<Observable> {
    let kind = std::mem::discriminant::<Observable>;
    let mut out = wanted.to_vec();
    out.extend(
        have.iter()
            .filter(|h| !wanted.iter().any(|w| kind(w) == kind(h)))
            .cloned(),
    );
    out
}

/// The default output directory of an experiment: `out/<name>`.
pub fn default_out(experiment: &Experiment) -> PathBuf {
    Path::new("out").join(experiment.name.replace(['/', '\\', ' '], "_"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(out: &Path) -> RunOptions {
        RunOptions {
            out: out.to_path_buf(),
            jobs: Some(1),
            log: Log::Quiet,
            shard: None,
        }
    }

    /// 2D dimers at pressure 10⁻³, `observables` measured, `extra` added
    /// to the protocol.
    fn dimers(observables: &str, extra: &str) -> Experiment {
        let e = Experiment::from_ron(
            &format!(
                r#"(name: "keep", family: "nmer", dim: 2, params: {{"alpha": 1.5}},
                particles: 32, seed: 1,
                protocol: Pressure(pressure: 1e-3, tol: 1e-2{extra}),
                observables: [{observables}])"#
            ),
            "keep",
        )
        .unwrap();
        e.validate().unwrap();
        e
    }

    /// A measurement that fails after the packing is made leaves the
    /// packing on disk, readable, listing no observable: here the moduli of
    /// a shear-stabilised cell of dimers, whose rattlers go by rank, without
    /// `rattlers.min_contacts` (the stabilised cell finds rattlers by
    /// count). The error names the sample, the observable and the kept
    /// file; the configuration is the one a run without the stabilisation
    /// makes, bit for bit. A rerun does not take the file for finished: it
    /// measures the packing again without making it again, and fails the
    /// same way.
    #[test]
    fn a_failed_measurement_keeps_the_packing_it_was_measuring() {
        let e = dimers("Contacts, Moduli()", ", shear_stabilised: true");
        let dir = tempfile::tempdir().unwrap();
        let report = run(&e, &options(dir.path())).unwrap();
        assert!(report.packings.is_empty());
        assert_eq!(report.failures.len(), 1);
        let id = "nmer_d2_N32_alpha1.5_s1";
        let path = dir.path().join("packings").join(format!("{id}.json"));
        let message = report.failures[0].to_string();
        for part in [
            &format!("sample {id}: measuring Moduli: "),
            "rattlers.min_contacts",
            &format!("the packing is kept in {}", path.display()),
        ] {
            assert!(message.contains(part), "{part:?} missing from: {message}");
        }
        let kept = PackingFile::load_checked(&path).unwrap();
        assert_eq!(kept.observables, serde_json::json!([]));
        assert_eq!(kept.positions.len(), 32);
        assert_eq!(kept.orientations.len(), 32);
        assert!(kept.measures.n_contacts.is_none() && kept.measures.moduli.is_none());
        assert!(kept.measures.fire_steps > 0);
        assert!(!failed_path(&dir.path().join("packings"), id).exists());

        // The same packing as a run that measures what it can.
        let plain_dir = tempfile::tempdir().unwrap();
        let plain = run(
            &dimers("Contacts, Moduli()", ""),
            &options(plain_dir.path()),
        )
        .unwrap();
        assert!(plain.failures.is_empty(), "{:?}", plain.failures);
        let made = &plain.packings[0];
        assert_eq!(kept.positions, made.positions);
        assert_eq!(kept.orientations, made.orientations);
        assert_eq!(kept.phi.to_bits(), made.phi.to_bits());
        assert_eq!(kept.measures.fire_steps, made.measures.fire_steps);

        // A rerun measures it again, and only measures it.
        let again = run(&e, &options(dir.path())).unwrap();
        assert_eq!(again.failures.len(), 1);
        let message = again.failures[0].to_string();
        assert!(message.contains("measuring Moduli"), "{message}");
        let still = PackingFile::load_checked(&path).unwrap();
        assert_eq!(still.positions, kept.positions);
        assert_eq!(still.measures.fire_steps, kept.measures.fire_steps);
        assert_eq!(still.observables, serde_json::json!([]));
    }

    /// A stop set by the hook of the first sample (one thread) leaves the
    /// others unstarted: one packing on disk, the rest listed as stopped,
    /// no summary; a rerun makes the rest, and the first is the same bits.
    #[test]
    fn a_stop_between_samples_keeps_the_finished_and_leaves_the_rest() {
        let e = Experiment::from_ron(
            r#"(name: "stopped", family: "sphere", particles: 16, samples: 3, seed: 5)"#,
            "stopped",
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let stop = AtomicBool::new(false);
        let seen = Mutex::new(Vec::new());
        let finished = |id: &str, outcome: Result<&PackingFile, &ExperimentError>| {
            assert!(outcome.is_ok());
            seen.lock().unwrap().push(id.to_string());
            stop.store(true, Ordering::SeqCst);
        };
        let hooks = Hooks {
            stop: Some(&stop),
            finished: Some(&finished),
        };
        let report = run_with(&e, &options(dir.path()), hooks).unwrap();
        let ids: Vec<String> = Plan::new(&e)
            .unwrap()
            .jobs
            .into_iter()
            .map(|j| j.id)
            .collect();
        assert_eq!(*seen.lock().unwrap(), ids[..1]);
        assert_eq!(report.packings.len(), 1);
        assert_eq!(report.stopped, ids[1..]);
        assert!(report.failures.is_empty());
        assert!(!dir.path().join("summary.csv").exists());
        let again = run(&e, &options(dir.path())).unwrap();
        assert_eq!((again.packings.len(), again.reused), (3, 1));
        assert!(again.stopped.is_empty() && dir.path().join("summary.csv").exists());
        assert_eq!(again.packings[0].positions, report.packings[0].positions);
    }

    /// `run_from_file` with a run's own `Jam` protocol, from the jammed
    /// packing's file: the search starts inside the window, so it ends
    /// there after its first relaxation, at the file's φ, with the bodies
    /// where they were to far better than a contact's overlap (`~10⁻⁸` at
    /// `V/N ~ 10⁻¹⁶`).
    #[test]
    fn jamming_a_jammed_packing_again_leaves_it_where_it_is() {
        let e = Experiment::from_ron(
            r#"(name: "again", family: "sphere", particles: 16, seed: 2)"#,
            "again",
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let made = run(&e, &options(dir.path())).unwrap().packings.remove(0);
        let (again, _) = Plan::new(&e).unwrap().run_from_file(&made).unwrap();
        assert_eq!(again.id, made.id);
        assert_eq!(again.phi.to_bits(), made.phi.to_bits());
        assert!(again.energy_per_particle > 1e-16 && again.energy_per_particle < 2e-16);
        let mut moved: f64 = 0.0;
        for (a, b) in again.positions.iter().zip(&made.positions) {
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                let l = made.box_edges[k];
                let d = x - y;
                moved = moved.max((d - l * (d / l).round()).abs());
            }
        }
        assert!(moved < 1e-10, "a body moved by {moved:e}");
        assert_eq!(again.measures.n_contacts, made.measures.n_contacts);
    }

    /// A run killed while measuring leaves the packing saved before its
    /// observables (as the runner saves it when the protocol ends); a
    /// rerun does not take it for finished, measures it without making it
    /// again, and gets the measures of an uninterrupted run bit for bit
    /// (timings aside).
    #[test]
    fn a_packing_saved_before_its_observables_is_measured_by_a_rerun() {
        let e = Experiment::from_ron(
            r#"(name: "killed", family: "sphere", particles: 32, seed: 3,
            observables: [Contacts, Pressure, Spectrum()])"#,
            "killed",
        )
        .unwrap();
        let plan = Plan::new(&e).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let packings = dir.path().join("packings");
        std::fs::create_dir_all(&packings).unwrap();
        let path = packings.join(format!("{}.json", plan.jobs[0].id));
        let jammed = plan.jam(&plan.jobs[0], None).unwrap();
        jammed.file.save(&path).unwrap();

        let resumed = run(&e, &options(dir.path())).unwrap();
        assert!(resumed.failures.is_empty(), "{:?}", resumed.failures);
        assert_eq!(resumed.reused, 1, "measured on the saved packing");
        let whole_dir = tempfile::tempdir().unwrap();
        let whole = run(&e, &options(whole_dir.path())).unwrap();
        assert_eq!(whole.reused, 0);
        let (a, b) = (&resumed.packings[0], &whole.packings[0]);
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.observables, b.observables);
        let untimed = |f: &PackingFile| {
            let mut m = f.measures.clone();
            m.wall_s = 0.0;
            if let Some(s) = m.spectrum.as_mut() {
                s.wall_s = 0.0;
            }
            m
        };
        assert_eq!(untimed(a), untimed(b));
        assert!(a.measures.spectrum.is_some() && a.measures.n_contacts.is_some());
        assert_eq!(
            PackingFile::load_checked(&path).unwrap().observables,
            b.observables
        );
    }
}
