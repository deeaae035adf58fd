//! The plan of a run: an experiment made ready to run, once.
//!
//! [`Plan::new`] takes the experiment file's way to the samples in one
//! pass: it validates the experiment, sets the paper's fields when it asks
//! for `paper_path` (`paper` module), expands its grid ([`grid::points`]),
//! builds each point's shape (the one place where the family's parameters
//! are read into the family's type), checks what needs the shape (the
//! family's second derivatives when an observable needs the Hessian, the
//! dense eigen-solves against the machine's memory), fills in the family's
//! minimiser defaults, and lists every packing to make with the settings
//! its file records ([`grid::jobs`]). The runner executes a plan; every
//! sample of a point is made and measured on that point's shape.

use crate::error::ExperimentError;
use crate::grid::{self, Job, Point, Shard};
use crate::memory;
use crate::sample::{self, Jammed, Sampler};
use crate::schema::{Experiment, Protocol};
use jamkit_core::{BodyOrientation, Pair, Shape, Vector};
use jamkit_engine::{FireParams, Progress};
use jamkit_format::PackingFile;
use jamkit_registry::{self as registry, SceneVisitor};
use std::sync::Arc;

/// An experiment ready to run: its points, each with its shape, and its
/// jobs, in grid order.
pub struct Plan {
    /// The experiment, validated, on its path (`paper_path: true` written
    /// into the minimiser and the protocol), as `experiment.ron` records it.
    pub experiment: Experiment,
    /// Its grid points, the family's minimiser defaults filled in.
    pub points: Vec<Point>,
    /// Every packing to make (or, after [`Plan::keep_part`], this part's).
    pub jobs: Vec<Job>,
    /// Each point's shape, in the order of `points`.
    samplers: Vec<Box<dyn Sampler>>,
}

impl Plan {
    /// The plan of `experiment`; a bad field, parameter or dimension, an
    /// observable the family cannot give, or a dense eigen-solve larger
    /// than the machine's memory is an error naming it.
    pub fn new(experiment: &Experiment) -> Result<Self, ExperimentError> {
        experiment.validate()?;
        crate::paper::check(experiment)?;
        let experiment = crate::paper::apply(experiment.clone());
        let mut points = grid::points(&experiment)?;
        // The spectrum and the moduli both need the Hessian.
        let hessian = if experiment.spectrum().is_some() {
            Some("Spectrum")
        } else if experiment.moduli().is_some() {
            Some("Moduli")
        } else {
            None
        };
        let machine = memory::machine_memory();
        let mut samplers = Vec::with_capacity(points.len());
        for point in &mut points {
            let build = Build {
                hessian,
                minimizer: &point.minimizer,
                protocol: &point.protocol,
            };
            let built = registry::dispatch(&experiment.family, point.dim, &point.params, build)??;
            memory::check_point(
                &experiment,
                (point.dim, point.particles, built.rot_dof),
                machine,
            )?;
            point.minimizer = built.minimizer;
            samplers.push(built.sampler);
        }
        let jobs = grid::jobs(&experiment, &points);
        Ok(Self {
            experiment,
            points,
            jobs,
            samplers,
        })
    }

    /// Keep only the jobs of one part (`--shard I/K`).
    pub fn keep_part(&mut self, shard: Shard) {
        let jobs = std::mem::take(&mut self.jobs);
        self.jobs = jobs
            .into_iter()
            .enumerate()
            .filter(|(j, _)| shard.owns(*j))
            .map(|(_, job)| job)
            .collect();
    }

    /// The point of `job`.
    pub fn point(&self, job: &Job) -> &Point {
        &self.points[job.point]
    }

    /// The packing of `job` at the end of its protocol, unmeasured
    /// ([`Plan::measure`] measures it); its minimiser reports to
    /// `progress` (a batch log's view: the packing is the same bits).
    pub fn jam(
        &self,
        job: &Job,
        progress: Option<Arc<Progress>>,
    ) -> Result<Jammed, ExperimentError> {
        self.samplers[job.point].jam(&self.experiment, self.point(job), job, progress)
    }

    /// The experiment's observables measured on a jammed packing (as its
    /// file records it), with the eigenvalue table when asked for.
    pub fn measure(
        &self,
        jammed: Jammed,
    ) -> Result<(PackingFile, Option<String>), ExperimentError> {
        sample::measure_jammed(
            &self.experiment,
            self.samplers[jammed.point()].as_ref(),
            jammed,
        )
    }

    /// The observables of `experiment` (this plan's, with other
    /// observables) measured on the saved packing `file` of `job`.
    pub(crate) fn remeasure(
        &self,
        experiment: &Experiment,
        job: &Job,
        file: PackingFile,
    ) -> Result<(PackingFile, Option<String>), ExperimentError> {
        sample::remeasure(experiment, Some(self.samplers[job.point].as_ref()), file)
    }

    /// The protocol of this plan's one point run from the configuration of
    /// `file` instead of a random start, then its observables, as a
    /// sample's: the packing file of the result, with the id and seed of
    /// `file`, and the eigenvalue table if asked for. `file`'s family,
    /// parameters, dimension and body count must be the experiment's.
    pub fn run_from_file(
        &self,
        file: &PackingFile,
    ) -> Result<(PackingFile, Option<String>), ExperimentError> {
        let [point] = &self.points[..] else {
            return Err(ExperimentError::invalid(
                "experiment",
                format!("{} grid points", self.points.len()),
                "must be one point (no lists) to run from a packing",
            ));
        };
        let job = Job {
            point: 0,
            sample: 0,
            seed: file.seed,
            id: file.id.clone(),
            settings: grid::settings(&self.experiment, point, file.seed),
        };
        let jammed = self.samplers[0].jam_from(&self.experiment, point, &job, file)?;
        self.measure(jammed)
    }

    /// Make and measure the packing of `job` (the runner saves it in
    /// between; this is the two halves at once).
    pub fn run_job(&self, job: &Job) -> Result<(PackingFile, Option<String>), ExperimentError> {
        self.measure(self.jam(job, None)?)
    }
}

/// What building a point's shape gives the plan.
struct Built {
    minimizer: FireParams,
    rot_dof: usize,
    sampler: Box<dyn Sampler>,
}

/// Builds the family's shape (which checks its parameters) and, when an
/// observable (`hessian` names it) needs the Hessian, checks that the
/// family gives the second derivatives of its gap.
struct Build<'a> {
    hessian: Option<&'static str>,
    minimizer: &'a FireParams,
    protocol: &'a Protocol,
}

impl SceneVisitor for Build<'_> {
    type Output = Result<Built, ExperimentError>;
    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output {
        if let Some(observable) = self.hessian {
            let o = S::Orientation::reference();
            let apart = Vector::<D>::from_fn(|a, _| if a == 0 { 4.0 } else { 0.0 });
            shape
                .gap_hessians(&Pair::new(1.0, o, 1.0, o, apart), f64::INFINITY, |_| {})
                .map_err(|e| ExperimentError::invalid("observables", observable, e.to_string()))?;
        }
        Ok(Built {
            minimizer: self.minimizer.for_family(&shape),
            rot_dof: shape.rot_dof(),
            sampler: sample::sampler(shape, self.protocol),
        })
    }
}
