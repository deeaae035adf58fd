//! The runner: every sample of an experiment, in parallel, resumable.
//!
//! Each sample is independent and seeded (`ChaCha8`, portable across
//! platforms), and is computed by one thread from start to end, so the
//! packing does not depend on `--jobs`. Samples whose file already exists in
//! the output directory are read back instead of recomputed.

use crate::error::ExperimentError;
use crate::grid::{self, Job, Point};
use crate::record::{self, Measures, PackingFile};
use crate::registry::{self, SceneVisitor};
use crate::schema::{Experiment, Observable, Protocol};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use jamkit_core::{Packing, Shape};
use jamkit_engine::{
    Fire, JamParams, PressureParams, Scene, compress_to_phi, compress_to_pressure, jam,
};
use jamkit_observe::summarize;
use rand::SeedableRng;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Worker threads (`None`: all cores).
    pub jobs: Option<usize>,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
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
    pub summaries: Vec<record::PointSummary>,
}

/// Run an experiment into `options.out`.
pub fn run(experiment: &Experiment, options: &RunOptions) -> Result<RunReport, ExperimentError> {
    experiment.validate()?;
    let points = grid::points(experiment)?;
    let jobs = grid::jobs(experiment, &points);
    let packing_dir = options.out.join("packings");
    std::fs::create_dir_all(&packing_dir).map_err(|e| ExperimentError::io(&packing_dir, e))?;
    let effective = ron::ser::to_string_pretty(experiment, ron::ser::PrettyConfig::default())
        .expect("experiment serialises");
    record::write_atomic(&options.out.join("experiment.ron"), effective.as_bytes())?;

    let bar = if options.progress {
        ProgressBar::with_draw_target(Some(jobs.len() as u64), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} packings, {elapsed} elapsed, ~{eta} left",
        )
        .expect("valid template"),
    );
    let work = |job: &Job| -> Result<(PackingFile, bool), ExperimentError> {
        let path = packing_dir.join(format!("{}.json", job.id));
        if let Some(done) =
            PackingFile::load_matching(&path, &settings(experiment, &points[job.point], job))
        {
            bar.inc(1);
            return Ok((done, true));
        }
        let point = &points[job.point];
        let file = run_job(experiment, point, job)?;
        file.save(&path)?;
        bar.inc(1);
        Ok((file, false))
    };
    let results: Vec<Result<(PackingFile, bool), ExperimentError>> = match options.jobs {
        Some(threads) => rayon::ThreadPoolBuilder::new()
            .num_threads(threads.max(1))
            .build()
            .expect("thread pool")
            .install(|| jobs.par_iter().map(work).collect()),
        None => jobs.par_iter().map(work).collect(),
    };
    bar.finish_and_clear();

    let mut packings = Vec::new();
    let mut failures = Vec::new();
    let mut reused = 0;
    for r in results {
        match r {
            Ok((f, was_reused)) => {
                reused += usize::from(was_reused);
                packings.push(f);
            }
            Err(e) => failures.push(e),
        }
    }
    let groups = group_by_point(experiment, &points, &jobs, &packings);
    record::write_atomic(
        &options.out.join("results.csv"),
        record::results_csv(&packings).as_bytes(),
    )?;
    record::write_atomic(
        &options.out.join("summary.csv"),
        record::summary_csv(&groups).as_bytes(),
    )?;
    let summaries = record::summarize_points(&groups);
    Ok(RunReport {
        packings,
        reused,
        failures,
        summaries,
    })
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
            (p.label(&experiment.family, experiment.dim), members)
        })
        .filter(|(_, m): &(String, Vec<&PackingFile>)| !m.is_empty())
        .collect()
}

/// Everything that shapes one packing, for the resume check.
pub fn settings(experiment: &Experiment, point: &Point, job: &Job) -> serde_json::Value {
    let e = experiment;
    serde_json::json!({
        "dim": e.dim,
        "family": e.family,
        "params": point.params,
        "particles": point.particles,
        "seed": job.seed,
        "sizes": e.sizes,
        "protocol": e.protocol,
        "minimizer": e.minimizer,
        "potential": e.potential,
        "rattlers": e.rattlers,
        "observables": e.observables,
        "engine": e.engine,
        "output": e.output,
    })
}

/// Make one packing.
pub fn run_job(
    experiment: &Experiment,
    point: &Point,
    job: &Job,
) -> Result<PackingFile, ExperimentError> {
    let visitor = SampleVisitor {
        experiment,
        point,
        job,
    };
    registry::dispatch(&experiment.family, experiment.dim, &point.params, visitor)?
}

struct SampleVisitor<'a> {
    experiment: &'a Experiment,
    point: &'a Point,
    job: &'a Job,
}

impl SceneVisitor for SampleVisitor<'_> {
    type Output = Result<PackingFile, ExperimentError>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output {
        let (e, job) = (self.experiment, self.job);
        let sample_err = |source| ExperimentError::Sample {
            sample: job.id.clone(),
            source,
        };
        let start = Instant::now();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(job.seed);
        let sizes = e.sizes.sample(self.point.particles, &mut rng);
        let min_reach = sizes
            .iter()
            .map(|&s| shape.bounding_radius(s))
            .fold(f64::INFINITY, f64::min);
        let packing = Packing::<D, S>::random(shape, sizes, e.protocol.phi_start(), &mut rng)
            .map_err(sample_err)?;
        let mut scene = Scene::new(packing, e.potential, e.engine.skin * min_reach);
        let mut fire = Fire::new(e.minimizer.clone());
        let outcome = match e.protocol {
            Protocol::Jam {
                eps,
                energy_low,
                energy_high,
                max_density_steps,
                ..
            } => jam(
                &mut scene,
                &mut fire,
                &JamParams {
                    eps,
                    energy_low,
                    energy_high,
                    max_density_steps,
                },
            ),
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
        }
        .map_err(sample_err)?;

        let threshold = e
            .rattlers
            .min_contacts
            .unwrap_or_else(|| scene.packing().shape.rattler_threshold());
        let contacts = e
            .observables
            .contains(&Observable::Contacts)
            .then(|| summarize(&mut scene, threshold));
        let pressure = e
            .observables
            .contains(&Observable::Pressure)
            .then(|| scene.pressure());
        let expects_iso = scene.packing().shape.expects_isostatic();
        let mut flags = scene.packing().shape.warnings();
        if let (Some(s), Protocol::Jam { .. }, true) = (&contacts, &e.protocol, expects_iso)
            && s.iso_margin < 1
        {
            flags.push(format!(
                "hypostatic: iso_margin = {} < 1; some contact is likely not closed (the minimisation stopped early) or the packing is not rigid",
                s.iso_margin
            ));
        }
        let flag = flags.join("; ");
        let measures = Measures {
            phi: outcome.phi,
            energy_per_particle: outcome.energy_per_particle,
            n_contacts: contacts.as_ref().map(|s| s.n_contacts),
            n_rattlers: contacts.as_ref().map(|s| s.n_rattlers),
            z_j: contacts.as_ref().map(|s| s.z_j),
            iso_margin: contacts.as_ref().map(|s| s.iso_margin),
            pressure,
            fire_steps: outcome.fire_steps,
            minimizations: outcome.minimizations,
            wall_s: start.elapsed().as_secs_f64(),
            flag,
        };
        let p = scene.packing();
        let write = e.output.packings;
        Ok(PackingFile {
            id: job.id.clone(),
            experiment: e.name.clone(),
            family: e.family.clone(),
            params: serde_json::to_value(&self.point.params).expect("params serialise"),
            dim: D,
            particles: p.len(),
            seed: job.seed,
            protocol: e.protocol.name().to_string(),
            settings: settings(e, self.point, job),
            phi: outcome.phi,
            energy_per_particle: outcome.energy_per_particle,
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
            rattler: contacts.map(|s| s.rattler).unwrap_or_default(),
            spheres: if write { sphere_rows(p) } else { Vec::new() },
        })
    }
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
