//! `jamkit archive DIR -o OUT`: what a study's report needs, small enough to
//! commit.
//!
//! A packing file of N = 1024 near-disks weighs about 125 kB, almost all of
//! it the configuration (centres, sizes, orientations, rattler flags); the
//! measures that `jamkit report` reads (φ_J, contacts, the binned spectrum,
//! the gap counts) take 2–5 kB. The archive holds every packing file of the
//! run with its configuration left out ([`format::without_configuration`]),
//! the run's `experiment.ron` as it is, and the tables (`results.csv`,
//! `summary.csv`, and `dos.csv` / `gaps.csv` where measured) of the packings
//! it holds, written as a finished run writes them: for a finished run they
//! are the run's own tables, byte for byte. A packing in flight (its lock
//! present) is left out, since a process may be adding observables to it;
//! an unreadable one is refused by name. The packings a run has not made yet
//! are simply absent, so a study can be archived stage by stage while it
//! runs, and the tables say what the archive holds (a run in the middle of a
//! stage has rewritten its `results.csv` but not yet its `summary.csv`).
//!
//! A directory the experiment file does not describe alone (several files
//! run into one directory, or a packing outside the file's grid), or whose
//! `experiment.ron` no longer parses, keeps its tables as they are.
//!
//! An archive is read by `jamkit report` like a run directory. A run into
//! it reuses its packings for the observables they hold; an observable they
//! lack needs the configuration, which is gone, so those packings are made
//! again.

use crate::error::ExperimentError;
use crate::{plan::Plan, runner, schema::Experiment};
use jamkit_format::{self as format, PackingFile};
use std::path::Path;

/// What an archive holds.
#[derive(Debug)]
pub struct ArchiveReport {
    /// Packing files archived.
    pub packings: usize,
    /// Packings in flight (locked by a running process), left out.
    pub in_flight: usize,
    /// Their bytes before and after the configuration was left out.
    pub bytes: (u64, u64),
}

/// Archive the run in `dir` into `out` (created if needed; files of an
/// earlier archive of the same run are replaced).
pub fn archive(dir: &Path, out: &Path) -> Result<ArchiveReport, ExperimentError> {
    let packing_dir = dir.join("packings");
    let entries =
        std::fs::read_dir(&packing_dir).map_err(|e| ExperimentError::io(&packing_dir, e))?;
    let mut paths: Vec<_> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    // A packing in flight (its lock present) may be half-measured: left out.
    let locked: Vec<_> = paths
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "lock"))
        .map(|p| p.with_extension("json"))
        .collect();
    let is_packing = |p: &Path| {
        p.extension().is_some_and(|e| e == "json")
            && !p.to_string_lossy().ends_with(".failed.json")
            && !locked.iter().any(|l| l == p)
    };
    let out_packings = out.join("packings");
    std::fs::create_dir_all(&out_packings).map_err(|e| ExperimentError::io(&out_packings, e))?;
    let mut report = ArchiveReport {
        packings: 0,
        in_flight: locked.len(),
        bytes: (0, 0),
    };
    let mut kept_files = Vec::new();
    for path in paths.iter().filter(|p| is_packing(p)) {
        let file = PackingFile::load_checked(path)?;
        let kept = format::without_configuration(&file);
        let target = out_packings.join(path.file_name().expect("a listed file has a name"));
        kept.save(&target)?;
        report.packings += 1;
        report.bytes.0 += std::fs::metadata(path).map_or(0, |m| m.len());
        report.bytes.1 += std::fs::metadata(&target).map_or(0, |m| m.len());
        kept_files.push(kept);
    }
    let tables_written = match Experiment::from_file(&dir.join("experiment.ron")) {
        Ok(experiment) => tables(&experiment, kept_files, out)?,
        Err(_) => false,
    };
    // The run's own description (and, where the archive cannot write the
    // tables itself, its tables), byte for byte.
    let entries = std::fs::read_dir(dir).map_err(|e| ExperimentError::io(dir, e))?;
    for path in entries.filter_map(|e| e.ok().map(|e| e.path())) {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let Some(name) = name else { continue };
        if name == "experiment.ron" || (!tables_written && name.ends_with(".csv")) {
            let bytes = std::fs::read(&path).map_err(|e| ExperimentError::io(&path, e))?;
            format::write_atomic(&out.join(&name), &bytes)?;
        }
    }
    Ok(report)
}

/// The tables of the archived `packings`, in the grid's order as a run
/// writes them, with a spectrum or gap table wherever a packing holds
/// those measures; `false` (nothing written) when a packing is not one of
/// `experiment`'s grid.
fn tables(
    experiment: &Experiment,
    mut packings: Vec<PackingFile>,
    out: &Path,
) -> Result<bool, ExperimentError> {
    let plan = Plan::new(experiment)?;
    let jobs = &plan.jobs;
    let place = |f: &PackingFile| jobs.iter().position(|j| j.id == f.id);
    if packings.iter().any(|f| place(f).is_none()) {
        return Ok(false);
    }
    packings.sort_by_key(|f| place(f));
    // Several files run into one directory share a grid but not their
    // observables (the paper-size profile: `Gaps` in one file only).
    let measured = (
        experiment.spectrum().is_some() || packings.iter().any(|f| f.measures.spectrum.is_some()),
        experiment.gaps().is_some() || packings.iter().any(|f| f.measures.gaps.is_some()),
    );
    runner::tables_measured(experiment, &packings, measured, out)?;
    Ok(true)
}
