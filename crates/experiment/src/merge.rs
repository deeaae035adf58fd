//! `jamkit merge DIR… -o OUT`: the parts of a run that ran into separate
//! directories (`--shard I/K` without a shared file system), gathered into
//! one run directory with the tables of one plain run.
//!
//! Refused, naming what is wrong, when the parts ran different experiments
//! (their `experiment.ron` differ), when a packing was made with other
//! settings than its experiment's, when one packing appears in two parts
//! with different contents (timing aside), or when a packing of the grid is
//! in no part.

use crate::error::ExperimentError;
use crate::lock::first_difference;
use crate::plan::Plan;
use crate::runner;
use crate::schema::Experiment;
use jamkit_format::{self as format, PackingFile};
use std::path::{Path, PathBuf};

/// What a merge gathered.
#[derive(Debug)]
pub struct MergeReport {
    /// Packings in the merged run.
    pub packings: usize,
    /// Packings found in more than one part (with the same contents).
    pub duplicates: usize,
}

fn refuse(message: String) -> ExperimentError {
    ExperimentError::Merge { message }
}

/// A packing file's contents with every timing (`wall_s`, at any depth:
/// the packing's and its spectrum's) left out.
fn without_timing(file: &PackingFile) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("wall_s");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(file).expect("a packing serialises");
    strip(&mut v);
    v
}

/// Gather `dirs` into `out` (which may be one of them).
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<MergeReport, ExperimentError> {
    let Some(first) = dirs.first() else {
        return Err(refuse("no directories to merge".into()));
    };
    // The parts must have run one experiment.
    // Compared without the header comment that names the jamkit which
    // wrote it: parts run by different builds of one experiment merge (each
    // packing file records its own jamkit).
    let read = |d: &Path| -> Result<String, ExperimentError> {
        let path = d.join("experiment.ron");
        let text = std::fs::read_to_string(&path).map_err(|e| ExperimentError::io(&path, e))?;
        Ok(text
            .lines()
            .skip_while(|l| l.starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n"))
    };
    let text = read(first)?;
    for d in &dirs[1..] {
        let other = read(d)?;
        if other != text {
            let (line, a, b) = text
                .lines()
                .zip(other.lines())
                .enumerate()
                .find(|(_, (a, b))| a != b)
                .map(|(k, (a, b))| (k + 1, a.trim().to_string(), b.trim().to_string()))
                .unwrap_or((
                    text.lines().count().min(other.lines().count()) + 1,
                    "".into(),
                    "".into(),
                ));
            return Err(refuse(format!(
                "{} and {} ran different experiments: their experiment.ron differ at line {line} \
                 (`{a}` against `{b}`); merge only parts of one run",
                first.join("experiment.ron").display(),
                d.join("experiment.ron").display()
            )));
        }
    }
    let experiment = Experiment::from_file(&first.join("experiment.ron"))?;
    let plan = Plan::new(&experiment)?;
    let jobs = &plan.jobs;
    let mut packings = Vec::with_capacity(jobs.len());
    let mut missing = Vec::new();
    let mut duplicates = 0;
    // Where each packing came from, for the eigenvalue tables.
    let mut sources = Vec::with_capacity(jobs.len());
    for job in jobs {
        let name = format!("{}.json", job.id);
        let mut found: Option<(PackingFile, &PathBuf)> = None;
        for d in dirs {
            let path = d.join("packings").join(&name);
            if !path.exists() {
                continue;
            }
            let file = PackingFile::load_checked(&path)?;
            if let Some((key, here, there)) = first_difference(&job.settings, &file.settings) {
                return Err(refuse(format!(
                    "{} was made with {key} = {there}, its run's experiment.ron has {key} = \
                     {here}",
                    path.display()
                )));
            }
            // A packing saved before its observables (their measuring
            // failed, or its process was killed) is unfinished.
            if !runner::covers(&runner::stored(&file), &experiment) {
                continue;
            }
            match &found {
                None => found = Some((file, d)),
                Some((kept, from)) => {
                    if without_timing(kept) != without_timing(&file) {
                        return Err(refuse(format!(
                            "packing {} differs between {} and {} (timing aside): two parts made \
                             it differently; remove the wrong one",
                            job.id,
                            from.display(),
                            d.display()
                        )));
                    }
                    duplicates += 1;
                }
            }
        }
        match found {
            Some((file, from)) => {
                packings.push(file);
                sources.push(from.clone());
            }
            None => missing.push(job.id.clone()),
        }
    }
    if !missing.is_empty() {
        let shown: Vec<&str> = missing.iter().take(5).map(String::as_str).collect();
        return Err(refuse(format!(
            "{} of the run's {} packings are in none of the parts (e.g. {}): a part is missing \
             or unfinished; rerun it (it resumes) and merge again",
            missing.len(),
            jobs.len(),
            shown.join(", ")
        )));
    }
    // Write the merged run.
    let packing_dir = out.join("packings");
    std::fs::create_dir_all(&packing_dir).map_err(|e| ExperimentError::io(&packing_dir, e))?;
    let same = |a: &Path, b: &Path| matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
    for ((file, from), job) in packings.iter().zip(&sources).zip(jobs) {
        if same(from, out) {
            continue;
        }
        let table = from.join("eigenvalues").join(format!("{}.csv", job.id));
        if table.exists() {
            let dir = out.join("eigenvalues");
            std::fs::create_dir_all(&dir).map_err(|e| ExperimentError::io(&dir, e))?;
            let text = std::fs::read(&table).map_err(|e| ExperimentError::io(&table, e))?;
            format::write_atomic(&dir.join(format!("{}.csv", job.id)), &text)?;
        }
        file.save(&packing_dir.join(format!("{}.json", job.id)))?;
    }
    format::write_atomic(&out.join("experiment.ron"), text.as_bytes())?;
    runner::tables_of(&experiment, &packings, out)?;
    Ok(MergeReport {
        packings: packings.len(),
        duplicates,
    })
}
