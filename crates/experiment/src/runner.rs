//! The runner: every sample of an experiment, in parallel, resumable.
//!
//! Each sample is independent and seeded (`ChaCha8`, portable across
//! platforms), and is computed by one thread from start to end, so the
//! packing does not depend on `--jobs`. Samples whose file already exists in
//! the output directory are read back instead of recomputed.

use crate::batchlog::{BatchLog, Log};
use crate::error::ExperimentError;
use crate::grid::{self, Job, Point};
use crate::lock;
use crate::reload::{PackingVisitor, reload};
use crate::schema::{Experiment, Observable, Protocol, SpectrumRequest};
use jamkit_core::{Packing, Shape};
use jamkit_engine::{
    Fire, JamParams, PressureParams, Progress, Scene, compress_to_phi, compress_to_pressure, jam,
};
use jamkit_format::{self as format, Measures, PackingFile, SpectrumMeasures};
use jamkit_observe::gaps::GapCounts;
use jamkit_observe::saddle::{self, SaddleParams};
use jamkit_observe::spectrum::{self, Spectrum};
use jamkit_observe::{JammingSummary, RattlerRule, summarize_with};
use jamkit_registry::{self as registry, SceneVisitor};
use rand::SeedableRng;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

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
}

/// How one job ended in this process.
pub(crate) enum Outcome {
    /// Made here (`false`) or read back / measured on a saved packing
    /// (`true`).
    Done(Box<PackingFile>, bool),
    /// Another process holds its lock (the lock file's contents).
    Elsewhere(String),
}

/// Run an experiment into `options.out`.
pub fn run(experiment: &Experiment, options: &RunOptions) -> Result<RunReport, ExperimentError> {
    experiment.validate()?;
    let points = grid::points(experiment)?;
    let mut jobs = grid::jobs(experiment, &points);
    if let Some(shard) = options.shard {
        jobs = jobs
            .into_iter()
            .enumerate()
            .filter(|(j, _)| shard.owns(*j))
            .map(|(_, job)| job)
            .collect();
    }
    let packing_dir = options.out.join("packings");
    refuse_other_settings(experiment, &points, &jobs, &packing_dir)?;
    std::fs::create_dir_all(&packing_dir).map_err(|e| ExperimentError::io(&packing_dir, e))?;
    let effective = ron::ser::to_string_pretty(experiment, ron::ser::PrettyConfig::default())
        .expect("experiment serialises");
    format::write_atomic(&options.out.join("experiment.ron"), effective.as_bytes())?;

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
            format::results_csv(&rows).as_bytes(),
        )?;
        Ok(())
    };
    let make = |job: &Job| -> Result<Outcome, ExperimentError> {
        let path = packing_dir.join(format!("{}.json", job.id));
        let point = &points[job.point];
        let wanted = settings(experiment, point, job);
        let finished = || {
            PackingFile::load_matching(&path, &wanted)
                .filter(|done| covers(&stored(done), experiment))
        };
        if let Some(done) = finished() {
            return Ok(Outcome::Done(Box::new(done), true));
        }
        // Held until the packing is saved or has failed.
        let _held = match lock::claim(&packing_dir, &job.id)? {
            lock::Claim::Mine(held) => held,
            lock::Claim::Busy(holder) => return Ok(Outcome::Elsewhere(holder)),
        };
        // Another process may have finished it since the first look.
        let done = PackingFile::load_matching(&path, &wanted);
        let (file, eigen, reused) = match done {
            Some(done) if covers(&stored(&done), experiment) => {
                return Ok(Outcome::Done(Box::new(done), true));
            }
            // Same packing, other observables: measure them on the saved
            // configuration instead of making it again, keeping the ones
            // measured before (so that experiments sharing an output
            // directory add up their observables).
            Some(done) if done.positions.len() == done.particles => {
                let mut merged = experiment.clone();
                merged.observables = union(&stored(&done), &experiment.observables);
                let (file, eigen) = remeasure(&merged, done)?;
                (file, eigen, true)
            }
            _ => {
                let (file, eigen) = run_job_watched(experiment, point, job, log.begin(&job.id))
                    .map_err(|err| keep_failed_state(err, &packing_dir))?;
                (file, eigen, false)
            }
        };
        // The eigenvalues first: a packing file on disk means its sample is done.
        if let Some(table) = eigen {
            let dir = options.out.join("eigenvalues");
            std::fs::create_dir_all(&dir).map_err(|e| ExperimentError::io(&dir, e))?;
            format::write_atomic(&dir.join(format!("{}.csv", job.id)), table.as_bytes())?;
        }
        file.save(&path)?;
        // A stalled configuration from an earlier attempt is stale now.
        let _ = std::fs::remove_file(failed_path(&packing_dir, &job.id));
        Ok(Outcome::Done(Box::new(file), reused))
    };
    let work = |job: &Job| -> Result<Outcome, ExperimentError> {
        let made = make(job).and_then(|outcome| {
            if let Outcome::Done(file, _) = &outcome {
                table_so_far(job, file)?;
            }
            Ok(outcome)
        });
        log.finish(&job.id, &made);
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
    let mut reused = 0;
    for (r, job) in results.into_iter().zip(&jobs) {
        match r {
            Ok(Outcome::Done(f, was_reused)) => {
                reused += usize::from(was_reused);
                packings.push(*f);
            }
            Ok(Outcome::Elsewhere(_)) => elsewhere.push(job.id.clone()),
            Err(e) => failures.push(e),
        }
    }
    let groups = group_by_point(experiment, &points, &jobs, &packings);
    let summaries = format::summarize_points(&groups);
    if options.shard.is_some() || !elsewhere.is_empty() {
        return Ok(RunReport {
            packings,
            reused,
            failures,
            summaries,
            elsewhere,
        });
    }
    write_tables(experiment, &packings, &groups, &options.out)?;
    Ok(RunReport {
        packings,
        reused,
        failures,
        summaries,
        elsewhere,
    })
}

/// Refuse to run into a directory holding a packing of these jobs made
/// with other settings, naming the first that differs (`lock` module).
fn refuse_other_settings(
    experiment: &Experiment,
    points: &[Point],
    jobs: &[Job],
    packing_dir: &Path,
) -> Result<(), ExperimentError> {
    for job in jobs {
        let path = packing_dir.join(format!("{}.json", job.id));
        let Some(old) = PackingFile::load(&path) else {
            continue;
        };
        let wanted = settings(experiment, &points[job.point], job);
        if let Some((key, here, mut there)) = lock::first_difference(&wanted, &old.settings) {
            if key == "protocol.Jam.search" && there == "(not set)" {
                // Bisection packings record no search (`protocol_settings`).
                there = "\"Bisection\" (not written; the default before \"Extrapolated\": \
                         add `search: Bisection` to the protocol to resume them)"
                    .to_string();
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

/// Where the configuration of a failed sample goes.
pub fn failed_path(packing_dir: &Path, id: &str) -> PathBuf {
    packing_dir.join(format!("{id}.failed.json"))
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
            }
        }
        other => other,
    }
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
    format::write_atomic(
        &out.join("results.csv"),
        format::results_csv(packings).as_bytes(),
    )?;
    format::write_atomic(
        &out.join("summary.csv"),
        format::summary_csv(groups).as_bytes(),
    )?;
    if experiment.spectrum().is_some() {
        format::write_atomic(&out.join("dos.csv"), format::dos_csv(groups).as_bytes())?;
    }
    if experiment.gaps().is_some() {
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
    let points = grid::points(experiment)?;
    let jobs = grid::jobs(experiment, &points);
    let groups = group_by_point(experiment, &points, &jobs, packings);
    write_tables(experiment, packings, &groups, out)
}

fn group_by_point<'a>(
    experiment: &Experiment,
    points: &[Point],
    jobs: &[Job],
    packings: &'a [PackingFile],
) -> Vec<(String, Vec<&'a PackingFile>)> {
    points
        .iter()
        .map(|p| {
            let ids: Vec<&str> = jobs
                .iter()
                .filter(|j| j.point == p.index)
                .map(|j| j.id.as_str())
                .collect();
            let members = packings
                .iter()
                .filter(|f| ids.contains(&f.id.as_str()))
                .collect();
            (p.label(&experiment.family), members)
        })
        .filter(|(_, m): &(String, Vec<&PackingFile>)| !m.is_empty())
        .collect()
}

/// Everything that shapes one packing, for the resume check.
pub fn settings(experiment: &Experiment, point: &Point, job: &Job) -> serde_json::Value {
    let e = experiment;
    let minimizer = &point.minimizer;
    serde_json::json!({
        "dim": point.dim,
        "family": e.family,
        "params": point.params,
        "particles": point.particles,
        "seed": job.seed,
        "sizes": e.sizes,
        "protocol": protocol_settings(&e.protocol),
        "minimizer": minimizer,
        "potential": e.potential,
        "rattlers": e.rattlers,
        "engine": e.engine,
    })
}

/// The protocol as a packing records it: as written to `experiment.ron`,
/// except that `search: Bisection` is left out. Packings made before the
/// field existed were bisection packings and record no `search`, so they
/// still resume under an explicit `search: Bisection`; the default,
/// `Extrapolated`, is always written, so no packing of one search is ever
/// taken for the other's.
fn protocol_settings(protocol: &Protocol) -> serde_json::Value {
    let mut value = serde_json::to_value(protocol).expect("protocol serialises");
    if let Some(jam) = value.get_mut("Jam").and_then(|j| j.as_object_mut())
        && jam.get("search") == Some(&serde_json::json!("Bisection"))
    {
        jam.remove("search");
    }
    value
}

/// The observables of `experiment`, as stored with each packing.
fn observables_value(experiment: &Experiment) -> serde_json::Value {
    serde_json::to_value(&experiment.observables).expect("observables serialise")
}

/// The observables a packing file holds (none if they do not parse).
fn stored(file: &PackingFile) -> Vec<Observable> {
    serde_json::from_value(file.observables.clone()).unwrap_or_default()
}

/// Whether `have` holds every observable `experiment` asks for, with the
/// same options.
fn covers(have: &[Observable], experiment: &Experiment) -> bool {
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

/// Make one packing; with it, the table of its eigenvalues when the
/// experiment asks for them (`eigenvalues/<id>.csv`).
pub fn run_job(
    experiment: &Experiment,
    point: &Point,
    job: &Job,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    run_job_watched(experiment, point, job, None)
}

/// [`run_job`], its minimiser reporting to `progress` (a batch log's view;
/// the packing is the same bits).
pub fn run_job_watched(
    experiment: &Experiment,
    point: &Point,
    job: &Job,
    progress: Option<Arc<Progress>>,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let visitor = SampleVisitor {
        experiment,
        point,
        job,
        progress,
    };
    registry::dispatch(&experiment.family, point.dim, &point.params, visitor)?
}

struct SampleVisitor<'a> {
    experiment: &'a Experiment,
    point: &'a Point,
    job: &'a Job,
    progress: Option<Arc<Progress>>,
}

impl SceneVisitor for SampleVisitor<'_> {
    type Output = Result<(PackingFile, Option<String>), ExperimentError>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output {
        let (e, job) = (self.experiment, self.job);
        let sample_err = |source| ExperimentError::sample(job.id.clone(), source);
        let start = Instant::now();
        let minimizer = self.point.minimizer.clone();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(job.seed);
        let sizes = e.sizes.sample(self.point.particles, &mut rng);
        let min_reach = sizes
            .iter()
            .map(|&s| shape.bounding_radius(s))
            .fold(f64::INFINITY, f64::min);
        let packing = Packing::<D, S>::random(shape, sizes, e.protocol.phi_start(), &mut rng)
            .map_err(sample_err)?;
        let mut scene = Scene::new(packing, e.potential, e.engine.skin * min_reach);
        let mut fire = Fire::new(minimizer);
        if let Some(p) = &self.progress {
            fire.watch(p.clone());
        }
        let mut saddle_escapes = None;
        let outcome: Result<_, jamkit_core::Error> = match e.protocol {
            Protocol::Jam {
                eps,
                energy_low,
                energy_high,
                max_density_steps,
                escape_saddles,
                search,
                ..
            } => {
                let params = JamParams {
                    eps,
                    energy_low,
                    energy_high,
                    max_density_steps,
                    search,
                };
                jam(&mut scene, &mut fire, &params).and_then(|mut outcome| {
                    if escape_saddles {
                        let threshold = e
                            .rattlers
                            .min_contacts
                            .unwrap_or_else(|| scene.packing().shape.rattler_threshold());
                        let s = saddle::escape_saddles(
                            &mut scene,
                            &mut fire,
                            &params,
                            &SaddleParams::default(),
                            threshold,
                        )?;
                        outcome.phi = s.phi;
                        outcome.energy_per_particle = s.energy_per_particle;
                        outcome.fire_steps += s.fire_steps;
                        outcome.minimizations += s.minimizations;
                        saddle_escapes = Some(s.rounds);
                    }
                    Ok(outcome)
                })
            }
            Protocol::Phi { phi, eps, .. } => compress_to_phi(&mut scene, &mut fire, phi, eps),
            Protocol::Pressure {
                pressure,
                tol,
                eps,
                max_density_steps,
                ..
            } => compress_to_pressure(
                &mut scene,
                &mut fire,
                &PressureParams {
                    pressure,
                    tol,
                    eps,
                    max_density_steps,
                },
            ),
        };
        let outcome = match outcome {
            Ok(outcome) => outcome,
            Err(source) => {
                // Keep what the engine stopped at, for a look at why.
                let state = self.failed_state(&mut scene, &source, start);
                return Err(ExperimentError::Sample {
                    sample: job.id.clone(),
                    source: Box::new(source),
                    state: state.map(Box::new),
                    saved: None,
                });
            }
        };

        let observed = observe(e, &mut scene).map_err(sample_err)?;
        let measures = observed.measures(
            e,
            Protocolled {
                phi: outcome.phi,
                energy_per_particle: outcome.energy_per_particle,
                fire_steps: outcome.fire_steps,
                minimizations: outcome.minimizations,
                wall_s: start.elapsed().as_secs_f64(),
                saddle_escapes,
            },
            &scene.packing().shape,
        );
        let mut file = self.file(scene.packing(), e.output.packings, measures);
        file.rattler = observed.rattler();
        Ok((file, observed.eigenvalue_table))
    }
}

impl SampleVisitor<'_> {
    /// The packing file of `p` with `measures` (the configuration only when
    /// `write`).
    fn file<const D: usize, S: Shape<D>>(
        &self,
        p: &Packing<D, S>,
        write: bool,
        measures: Measures,
    ) -> PackingFile {
        let (e, job) = (self.experiment, self.job);
        PackingFile {
            id: job.id.clone(),
            experiment: e.name.clone(),
            family: e.family.clone(),
            params: serde_json::to_value(&self.point.params).expect("params serialise"),
            dim: D,
            particles: p.len(),
            seed: job.seed,
            protocol: e.protocol.name().to_string(),
            settings: settings(e, self.point, job),
            observables: observables_value(e),
            phi: measures.phi,
            energy_per_particle: measures.energy_per_particle,
            measures,
            box_edges: p.bbox.edges().iter().copied().collect(),
            positions: if write {
                // Centres drift out of the box between neighbour-list
                // rebuilds; the file holds them in the primary cell.
                p.positions
                    .iter()
                    .map(|r| p.bbox.wrap(*r).iter().copied().collect())
                    .collect()
            } else {
                Vec::new()
            },
            radii: if write { p.sizes.clone() } else { Vec::new() },
            orientations: if write && p.shape.rot_dof() > 0 {
                p.orientations
                    .iter()
                    .map(|o| p.shape.orientation_coords(o))
                    .collect()
            } else {
                Vec::new()
            },
            rattler: Vec::new(),
            spheres: if write { sphere_rows(p) } else { Vec::new() },
        }
    }

    /// The configuration a failed protocol stopped at, as a packing file
    /// whose `flag` is the error: a minimisation that hit its step cap
    /// (`fire_steps` its steps) or a jamming search that gave up
    /// (`fire_steps` 0). `None` for errors with nothing to look at: a bad
    /// start, a box too small, a non-finite energy.
    fn failed_state<const D: usize, S: Shape<D>>(
        &self,
        scene: &mut Scene<D, S>,
        error: &jamkit_core::Error,
        start: Instant,
    ) -> Option<PackingFile> {
        let steps = match error {
            jamkit_core::Error::NotConverged { steps, .. } => *steps,
            jamkit_core::Error::JammingFailed { .. } => 0,
            _ => return None,
        };
        let bodies = scene.packing().len().max(1) as f64;
        let energy = scene.energy();
        let measures = Measures {
            phi: scene.packing().phi(),
            energy_per_particle: energy / bodies,
            n_contacts: None,
            n_rattlers: None,
            z_j: None,
            iso_margin: None,
            n_rot_rattlers: None,
            free_rotations: None,
            pressure: None,
            fire_steps: steps,
            minimizations: 0,
            wall_s: start.elapsed().as_secs_f64(),
            flag: error.to_string(),
            saddle_escapes: None,
            spectrum: None,
            gaps: None,
        };
        Some(self.file(scene.packing(), true, measures))
    }
}

/// What the protocol ended with, as stored.
struct Protocolled {
    phi: f64,
    energy_per_particle: f64,
    fire_steps: u64,
    minimizations: u64,
    wall_s: f64,
    saddle_escapes: Option<u32>,
}

/// The observables of one packing.
struct Observed {
    contacts: Option<JammingSummary>,
    pressure: Option<f64>,
    spectrum: Option<SpectrumMeasures>,
    eigenvalue_table: Option<String>,
    gaps: Option<GapCounts>,
}

/// The rattler rule of `e` for this packing: an explicit
/// `rattlers.min_contacts` counts contacts; otherwise rotating bodies made
/// of spheres go by rank (a body held on one sphere keeps its contacts,
/// see `jamkit_observe::find_rattlers_by_rank`), and every other family by
/// its own count (`d + 1` for disks and near-disks).
fn rattler_rule<const D: usize, S: Shape<D>>(e: &Experiment, p: &Packing<D, S>) -> RattlerRule {
    let made_of_spheres = p.shape.rot_dof() > 0
        && p.sizes
            .first()
            .zip(p.orientations.first())
            .is_some_and(|(&s, o)| p.shape.sphere_decomposition(s, o).is_some());
    match e.rattlers.min_contacts {
        Some(t) => RattlerRule::Count(t),
        None if made_of_spheres => RattlerRule::Rank,
        None => RattlerRule::Count(p.shape.rattler_threshold()),
    }
}

/// Measure what `e` asks for on a relaxed scene.
fn observe<const D: usize, S: Shape<D>>(
    e: &Experiment,
    scene: &mut Scene<D, S>,
) -> jamkit_core::Result<Observed> {
    let contacts = e
        .needs_contacts()
        .then(|| summarize_with(scene, rattler_rule(e, scene.packing())));
    let pressure = e.wants(&Observable::Pressure).then(|| scene.pressure());
    let rattler = contacts.as_ref().map_or(&[][..], |s| &s.rattler[..]);
    let (spectrum, eigenvalue_table) = match e.spectrum() {
        Some(request) => {
            let (m, table) = measure_spectrum(scene, rattler, &request)?;
            (Some(m), table)
        }
        None => (None, None),
    };
    let gaps = e
        .gaps()
        .map(|params| GapCounts::of_scene(scene, rattler, &params));
    Ok(Observed {
        contacts,
        pressure,
        spectrum,
        eigenvalue_table,
        gaps,
    })
}

impl Observed {
    fn measures<const D: usize, S: Shape<D>>(
        &self,
        e: &Experiment,
        run: Protocolled,
        shape: &S,
    ) -> Measures {
        let contacts = self.contacts.as_ref();
        let mut flags = shape.warnings();
        if let (Some(s), Protocol::Jam { .. }, true) =
            (contacts, &e.protocol, shape.expects_isostatic())
            && s.iso_margin < 1
        {
            flags.push(format!(
                "hypostatic: iso_margin = {} < 1; some contact is likely not closed (the minimisation stopped early) or the packing is not rigid",
                s.iso_margin
            ));
        }
        Measures {
            phi: run.phi,
            energy_per_particle: run.energy_per_particle,
            n_contacts: contacts.map(|s| s.n_contacts),
            n_rattlers: contacts.map(|s| s.n_rattlers),
            z_j: contacts.map(|s| s.z_j),
            iso_margin: contacts.map(|s| s.iso_margin),
            pressure: self.pressure,
            fire_steps: run.fire_steps,
            minimizations: run.minimizations,
            wall_s: run.wall_s,
            flag: flags.join("; "),
            saddle_escapes: run.saddle_escapes,
            spectrum: self.spectrum.clone(),
            gaps: self.gaps.clone(),
            n_rot_rattlers: contacts.map(|s| s.n_rot_rattlers),
            free_rotations: contacts.map(|s| s.free_rotations),
        }
    }

    fn rattler(&self) -> Vec<bool> {
        self.contacts
            .as_ref()
            .map(|s| s.rattler.clone())
            .unwrap_or_default()
    }
}

/// Measure the observables of `e` on a saved packing (same settings,
/// other observables); the protocol's own figures are kept, and the
/// measuring time is added to `wall_s`.
pub(crate) fn remeasure(
    e: &Experiment,
    file: PackingFile,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    struct Remeasure<'a> {
        e: &'a Experiment,
        file: PackingFile,
    }
    impl PackingVisitor for Remeasure<'_> {
        type Output = Result<(PackingFile, Option<String>), ExperimentError>;
        fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
            let (e, mut file) = (self.e, self.file);
            let start = Instant::now();
            let observed = observe(e, &mut scene)
                .map_err(|source| ExperimentError::sample(file.id.clone(), source))?;
            let old = &file.measures;
            let run = Protocolled {
                phi: old.phi,
                energy_per_particle: old.energy_per_particle,
                fire_steps: old.fire_steps,
                minimizations: old.minimizations,
                wall_s: old.wall_s + start.elapsed().as_secs_f64(),
                saddle_escapes: old.saddle_escapes,
            };
            file.measures = observed.measures(e, run, &scene.packing().shape);
            file.rattler = observed.rattler();
            file.observables = observables_value(e);
            Ok((file, observed.eigenvalue_table))
        }
    }
    let id = file.id.clone();
    reload(&file.clone(), Remeasure { e, file })
        .and_then(|r| r)
        .map_err(|err| match err {
            ExperimentError::Sample { .. } => err,
            other => ExperimentError::invalid(format!("packing {id}"), "…", other.to_string()),
        })
}

/// The spectrum of a jammed scene as stored, and the eigenvalue table if
/// asked for.
fn measure_spectrum<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
    request: &SpectrumRequest,
) -> jamkit_core::Result<(SpectrumMeasures, Option<String>)> {
    let start = Instant::now();
    let s = spectrum::measure(scene, rattler, request.hessian, request.modes, &request.dos)?;
    let table = (request.eigenvalues || request.modes).then(|| eigenvalue_table(&s));
    let measures = SpectrumMeasures {
        coordinates: s.eigenvalues.len(),
        zero_modes: s.zero,
        lambda_min: s.eigenvalues.first().copied().unwrap_or(f64::NAN),
        lambda_max: s.eigenvalues.last().copied().unwrap_or(f64::NAN),
        histogram: s.histogram,
        dos: request.dos.clone(),
        wall_s: start.elapsed().as_secs_f64(),
    };
    Ok((measures, table))
}

/// `eigenvalues/<id>.csv`: `lambda,omega` per mode, ascending, with
/// `participation,rotational_share` when the eigenvectors were computed.
pub fn eigenvalue_table(s: &Spectrum) -> String {
    let mut out = String::from(match s.modes {
        Some(_) => "lambda,omega,participation,rotational_share\n",
        None => "lambda,omega\n",
    });
    for (n, &l) in s.eigenvalues.iter().enumerate() {
        out += &format!("{l:e},{:e}", spectrum::frequency(l));
        if let Some(m) = &s.modes {
            out += &format!(",{:e},{:e}", m[n].participation, m[n].rotational_share);
        }
        out.push('\n');
    }
    out
}

/// The `spheres` rows of a packing file: `[x, y(, z), radius, body]` for
/// every sphere of every body, empty unless the family is made of spheres.
fn sphere_rows<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> Vec<Vec<f64>> {
    let mut rows = Vec::new();
    for (i, (r, (&size, o))) in p
        .positions
        .iter()
        .zip(p.sizes.iter().zip(&p.orientations))
        .enumerate()
    {
        let Some(balls) = p.shape.sphere_decomposition(size, o) else {
            return Vec::new();
        };
        let centre = p.bbox.wrap(*r);
        for (offset, radius) in balls {
            let mut row: Vec<f64> = (centre + offset).iter().copied().collect();
            row.extend([radius, i as f64]);
            rows.push(row);
        }
    }
    rows
}

/// The default output directory of an experiment: `out/<name>`.
pub fn default_out(experiment: &Experiment) -> PathBuf {
    Path::new("out").join(experiment.name.replace(['/', '\\', ' '], "_"))
}
