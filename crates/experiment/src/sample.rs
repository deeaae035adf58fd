//! One sample, from start to end: the family's shape for its point, the
//! random start from its seed, the protocol (the engine's `jam`,
//! `compress_to_phi`, `compress_to_pressure` or `above_jam`, with the saddle
//! escape after `jam` unless it is turned off), the observables (contacts and rattlers, pressure,
//! spectrum, gaps), and the packing file that records it all. The
//! observables are measured on the configuration as its file records it
//! (`measure_saved`), by the same code as the re-measurement of a saved
//! packing (`remeasure`), so the two agree bit for bit. The parallel,
//! resumable loop over samples is the runner's (`runner`); nothing here
//! knows about threads, locks or other samples, so a sample is the same
//! bits whoever runs it.

use crate::error::ExperimentError;
use crate::grid::{Job, Point};
use crate::reload::{PackingVisitor, reload};
use crate::schema::{Experiment, Observable, Protocol, SpectrumRequest};
use jamkit_core::BodyOrientation;
use jamkit_core::{Packing, Shape};
use jamkit_engine::saddle::{self, SaddleParams};
use jamkit_engine::{
    AboveJamParams, Fire, JamParams, PressureParams, Progress, Scene, above_jam, compress_to_phi,
    compress_to_pressure, jam,
};
use jamkit_format::{
    JamPoint, Measures, ModuliMeasures, PackingFile, SoftestMode, SpectrumMeasures,
};
use jamkit_observe::gaps::{CountGaps, GapCounts};
use jamkit_observe::spectrum::{self, Spectrum};
use jamkit_observe::{JammingSummary, RattlerRule, summarize, summarize_with};
use rand::SeedableRng;
use std::sync::Arc;
use std::time::Instant;

/// The observables of `experiment`, as stored with each packing.
pub(crate) fn observables_value(experiment: &Experiment) -> serde_json::Value {
    serde_json::to_value(&experiment.observables).expect("observables serialise")
}

/// A point's shape, built once by the plan (`Plan::new`): it makes the
/// point's packings and measures them.
pub(crate) trait Sampler: Send + Sync {
    /// The packing of `job` at the end of its protocol, unmeasured.
    fn jam(
        &self,
        e: &Experiment,
        point: &Point,
        job: &Job,
        progress: Option<Arc<Progress>>,
    ) -> Result<Jammed, ExperimentError>;

    /// The protocol of `point` run from the configuration of `file` (on
    /// this shape) instead of a random start, as the packing of `job`.
    fn jam_from(
        &self,
        e: &Experiment,
        point: &Point,
        job: &Job,
        file: &PackingFile,
    ) -> Result<Jammed, ExperimentError>;

    /// The observables of `e` measured on the configuration of `file` on
    /// this shape, with the point's protocol ([`measure_scene`]).
    fn measure(
        &self,
        e: &Experiment,
        file: PackingFile,
        run: Protocolled,
    ) -> Result<(PackingFile, Observed), ExperimentError>;
}

/// The sampler of a point whose shape is `shape` and protocol `protocol`.
pub(crate) fn sampler<const D: usize, S: Shape<D>>(
    shape: S,
    protocol: &Protocol,
) -> Box<dyn Sampler> {
    Box::new(OfShape::<D, S> {
        shape,
        protocol: protocol.clone(),
    })
}

struct OfShape<const D: usize, S> {
    shape: S,
    protocol: Protocol,
}

impl<const D: usize, S: Shape<D>> Sampler for OfShape<D, S> {
    fn jam(
        &self,
        experiment: &Experiment,
        point: &Point,
        job: &Job,
        progress: Option<Arc<Progress>>,
    ) -> Result<Jammed, ExperimentError> {
        let sample = Sample {
            experiment,
            point,
            job,
        };
        sample.jam::<D, S>(self.shape.clone(), progress)
    }

    fn jam_from(
        &self,
        experiment: &Experiment,
        point: &Point,
        job: &Job,
        file: &PackingFile,
    ) -> Result<Jammed, ExperimentError> {
        let start = Instant::now();
        let scene = crate::reload::scene_of::<D, S>(self.shape.clone(), file)?;
        let sample = Sample {
            experiment,
            point,
            job,
        };
        sample.protocol(scene, start, None)
    }

    fn measure(
        &self,
        e: &Experiment,
        file: PackingFile,
        run: Protocolled,
    ) -> Result<(PackingFile, Observed), ExperimentError> {
        let id = file.id.clone();
        crate::reload::scene_of::<D, S>(self.shape.clone(), &file)
            .and_then(|scene| measure_scene(e, &self.protocol, scene, file, run))
            .map_err(|err| in_packing(&id, err))
    }
}

/// A packing at the end of its protocol, before its observables: `file`
/// holds its configuration and the protocol's figures, and no observable
/// (`observables` is empty), so a rerun that finds it saved measures them
/// on it instead of taking it for finished. The runner saves it as soon as
/// the protocol ends, so a measurement that fails (or a process killed
/// while measuring) leaves the packing on disk.
pub struct Jammed {
    /// The packing file without observables.
    pub file: PackingFile,
    /// The protocol's figures, for the measures.
    run: Protocolled,
    /// Its grid point.
    point: usize,
}

impl Jammed {
    /// The index of its grid point.
    pub fn point(&self) -> usize {
        self.point
    }
}

/// One sample: its experiment, grid point and job.
struct Sample<'a> {
    experiment: &'a Experiment,
    point: &'a Point,
    job: &'a Job,
}

impl Sample<'_> {
    /// The packing of the job on `shape` at the end of its protocol, its
    /// minimiser reporting to `progress`.
    fn jam<const D: usize, S: Shape<D>>(
        &self,
        shape: S,
        progress: Option<Arc<Progress>>,
    ) -> Result<Jammed, ExperimentError> {
        let (e, job) = (self.experiment, self.job);
        let sample_err = |source| ExperimentError::sample(job.id.clone(), source);
        let start = Instant::now();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(job.seed);
        let sizes = e.sizes.sample(self.point.particles, &mut rng);
        let min_reach = sizes
            .iter()
            .map(|&s| shape.bounding_radius(s))
            .fold(f64::INFINITY, f64::min);
        let protocol = &self.point.protocol;
        let packing = Packing::<D, S>::random(shape, sizes, protocol.phi_start(), &mut rng)
            .map_err(sample_err)?;
        let scene = Scene::new(packing, e.potential, e.engine.skin * min_reach);
        self.protocol(scene, start, progress)
    }

    /// The protocol of the sample's point from the configuration of
    /// `scene` (a random start, or a packing given by the caller), `start`
    /// the sample's start time, its minimiser reporting to `progress`.
    fn protocol<const D: usize, S: Shape<D>>(
        &self,
        mut scene: Scene<D, S>,
        start: Instant,
        progress: Option<Arc<Progress>>,
    ) -> Result<Jammed, ExperimentError> {
        let (e, job) = (self.experiment, self.job);
        let minimizer = self.point.minimizer.clone();
        let protocol = &self.point.protocol;
        let mut fire = Fire::new(minimizer);
        if let Some(p) = progress {
            fire.watch(p);
        }
        let mut saddle_escapes = None;
        let mut jam_point = None;
        // A grid point's protocol has one target (`Protocol::targets`).
        let target = |t: &crate::schema::OneOrMany<f64>| t.first().unwrap_or(f64::NAN);
        let outcome: Result<_, jamkit_core::Error> = match *protocol {
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
                            .unwrap_or_else(|| scene.packing().shape.policy().rattler_threshold);
                        let s = saddle::escape_saddles(
                            &mut scene,
                            &mut fire,
                            &params,
                            &SaddleParams::default(),
                            |scene| summarize(scene, threshold).rattler,
                        )?;
                        outcome.phi = s.phi;
                        outcome.energy_per_particle = s.energy_per_particle;
                        outcome.work += s.work;
                        saddle_escapes = Some(s.rounds);
                    }
                    Ok(outcome)
                })
            }
            Protocol::AboveJam {
                eps,
                energy_low,
                energy_high,
                max_density_steps,
                search,
                ref delta_phi,
                compress_eps,
                rejams,
                ..
            } => {
                let params = AboveJamParams {
                    jam: JamParams {
                        eps,
                        energy_low,
                        energy_high,
                        max_density_steps,
                        search,
                    },
                    delta_phi: target(delta_phi),
                    compress_eps,
                    rejams,
                };
                above_jam(&mut scene, &mut fire, &params, |scene, jammed, left| {
                    // The jamming point's contacts, before the compression
                    // (reading them moves no body: same packing after).
                    let at_jam = e.needs_contacts().then(|| {
                        let rule = rattler_rule(e, scene.packing());
                        summarize_with(scene, rule)
                    });
                    jam_point = Some(JamPoint {
                        phi: jammed.phi,
                        z: at_jam.as_ref().map(|s| s.z_j),
                        n_rattlers: at_jam.as_ref().map(|s| s.n_rattlers),
                        iso_margin: at_jam.as_ref().map(|s| s.iso_margin),
                        left: left.to_vec(),
                    });
                })
                .map(|o| o.above)
            }
            Protocol::Phi { ref phi, eps, .. } => {
                compress_to_phi(&mut scene, &mut fire, target(phi), eps)
            }
            Protocol::Pressure {
                ref pressure,
                tol,
                eps,
                max_density_steps,
                ..
            } => compress_to_pressure(
                &mut scene,
                &mut fire,
                &PressureParams {
                    pressure: target(pressure),
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
                    observable: None,
                    kept: None,
                });
            }
        };

        // The observables are measured on the configuration as the packing
        // file records it and `reload` gives it back (centres wrapped into
        // the box, orientations through the family's coordinates), not on
        // the scene in memory: a planar near-disk's `e^{iθ}` is stored as
        // `θ` and comes back a bit or two off, which a soft Hessian
        // amplifies (`tests/observables.rs`,
        // `remeasured_near_disk_moduli_equal_the_run_bit_for_bit`).
        // So a re-measure of the saved file gives these measures bit for bit.
        let run = Protocolled {
            phi: outcome.phi,
            energy_per_particle: outcome.energy_per_particle,
            fire_steps: outcome.work.fire_steps,
            lbfgs_evaluations: self
                .point
                .minimizer
                .lbfgs
                .params()
                .map(|_| outcome.work.lbfgs_evaluations),
            minimizations: outcome.work.minimizations,
            plateau_escapes: Some(outcome.work.plateau_escapes).filter(|&n| n > 0),
            dt_cuts: Some(outcome.work.dt_cuts).filter(|&n| n > 0),
            wall_s: start.elapsed().as_secs_f64(),
            saddle_escapes,
            jam_point,
        };
        let shape = &scene.packing().shape;
        let unmeasured = Observed::unmeasured().measures(&self.point.protocol, run.clone(), shape);
        let mut file = self.file(scene.packing(), true, unmeasured);
        file.observables = serde_json::json!([]);
        Ok(Jammed {
            file,
            run,
            point: self.point.index,
        })
    }
}

/// The second half of [`run_job_watched`]: the observables of `experiment`
/// measured on the jammed packing (as its file records it), and the
/// eigenvalue table if asked for. A failed shear stabilisation is an error
/// carrying the fixed-box packing as its `state` (the runner keeps it as
/// `<id>.failed.json`).
pub(crate) fn measure_jammed(
    experiment: &Experiment,
    sampler: &dyn Sampler,
    jammed: Jammed,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let e = experiment;
    let Jammed { file, run, .. } = jammed;
    let id = file.id.clone();
    let (mut file, mut observed) = sampler.measure(e, file, run)?;
    if let Some(source) = observed.stabilisation_failed.take() {
        // The packing the stabilisation started from, with its
        // fixed-box measures, kept as `<id>.failed.json` (the runner's
        // convention for failed samples); the runner removes the packing
        // it saved before its observables, so a rerun (with other
        // `protocol.stabilise` settings too) tries the sample again.
        let why = format!(
            "shear stabilisation failed: {source}; this is the fixed-box packing it started from, with the fixed box's moduli"
        );
        let measures = &mut file.measures;
        measures.flag = if measures.flag.is_empty() {
            why
        } else {
            format!("{}; {why}", measures.flag)
        };
        return Err(ExperimentError::Sample {
            sample: id,
            source: Box::new(source),
            state: Some(Box::new(file)),
            saved: None,
            observable: Some("Moduli".into()),
            kept: None,
        });
    }
    if !e.output.packings {
        // The rattler flags stay, as in every file.
        file = PackingFile {
            rattler: std::mem::take(&mut file.rattler),
            ..jamkit_format::without_configuration(&file)
        };
    }
    Ok((file, observed.eigenvalue_table))
}

impl Sample<'_> {
    /// The packing file of `p` with `measures` (the configuration only when
    /// `write`).
    fn file<const D: usize, S: Shape<D>>(
        &self,
        p: &Packing<D, S>,
        write: bool,
        measures: Measures,
    ) -> PackingFile {
        let (e, job) = (self.experiment, self.job);
        let (jamkit_version, git_commit) = jamkit_format::provenance::stamp();
        PackingFile {
            id: job.id.clone(),
            experiment: e.name.clone(),
            family: e.family.clone(),
            params: serde_json::to_value(&self.point.record).expect("params serialise"),
            dim: D,
            particles: p.len(),
            seed: job.seed,
            protocol: e.protocol.name().to_string(),
            settings: job.settings.clone(),
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
                p.orientations.iter().map(|o| o.to_coords()).collect()
            } else {
                Vec::new()
            },
            rattler: Vec::new(),
            spheres: if write { sphere_rows(p) } else { Vec::new() },
            jamkit_version,
            git_commit,
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
            fire_steps: steps,
            wall_s: start.elapsed().as_secs_f64(),
            flag: error.to_string(),
            ..Measures::bare(scene.packing().phi(), energy / bodies)
        };
        Some(self.file(scene.packing(), true, measures))
    }
}

/// What the protocol ended with, as stored.
#[derive(Clone)]
pub(crate) struct Protocolled {
    phi: f64,
    energy_per_particle: f64,
    fire_steps: u64,
    /// L-BFGS evaluations, when the minimiser ran L-BFGS.
    lbfgs_evaluations: Option<u64>,
    minimizations: u64,
    /// The minimiser's plateau escapes and `Δt_max` cuts, when it made any.
    plateau_escapes: Option<u64>,
    dt_cuts: Option<u64>,
    wall_s: f64,
    saddle_escapes: Option<u32>,
    /// `AboveJam`'s jamming point.
    jam_point: Option<JamPoint>,
}

/// The observables of one packing.
pub(crate) struct Observed {
    contacts: Option<JammingSummary>,
    pressure: Option<f64>,
    spectrum: Option<SpectrumMeasures>,
    eigenvalue_table: Option<String>,
    gaps: Option<GapCounts>,
    moduli: Option<ModuliMeasures>,
    /// `protocol.shear_stabilised`: why the stabilisation failed (`moduli`
    /// then holds the fixed box's, without `stabilisation`).
    stabilisation_failed: Option<jamkit_core::Error>,
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
        None => RattlerRule::Count(p.shape.policy().rattler_threshold),
    }
}

/// The rattler count rule of a shear stabilisation: the cell has no rank
/// rule, so a family whose rattlers go by rank needs
/// `rattlers.min_contacts`.
fn stabilisation_threshold<const D: usize, S: Shape<D>>(
    e: &Experiment,
    p: &Packing<D, S>,
) -> jamkit_core::Result<usize> {
    match rattler_rule(e, p) {
        RattlerRule::Count(t) => Ok(t),
        RattlerRule::Rank => Err(jamkit_core::Error::Unsupported(
            "protocol.shear_stabilised = true finds the stabilised cell's rattlers by count; this family's rattlers go by rank: set rattlers.min_contacts".into(),
        )),
    }
}

/// `protocol.shear_stabilised`: the packing of `scene` shear-stabilised
/// (the engine's `stabilise` with `protocol.stabilise`, the deformation
/// check's minimiser and the linear-response stiffness of
/// `jamkit_observe::moduli::cell_stiffness`) and the moduli of the
/// stabilised cell,
/// with the fixed box's `fixed_box` kept beside them. Rattlers by count
/// (`threshold`).
fn stabilised_moduli<const D: usize, S: Shape<D>>(
    protocol: &Protocol,
    scene: &mut Scene<D, S>,
    threshold: usize,
    fixed_box: jamkit_observe::moduli::Moduli,
    params: jamkit_observe::moduli::ModuliParams,
) -> jamkit_core::Result<ModuliMeasures> {
    use jamkit_observe::moduli::{self, CellContacts};
    let start = Instant::now();
    // At the packing's own pressure (`Pressure`: its target, to the
    // protocol's tolerance), as Dagois-Bohy et al.: at fixed volume a
    // packing near jamming can unjam as its cell relaxes (the 2D disks of
    // `tests/moduli.rs`), which fixed pressure rules out.
    let ensemble = moduli::Ensemble::Pressure(scene.pressure());
    let stabilise = moduli::StabiliseParams {
        moduli: params.clone(),
        ..protocol.stabilise().cloned().unwrap_or_default()
    };
    let mut s = jamkit_engine::stabilise::stabilise(
        scene,
        ensemble,
        &stabilise,
        &moduli::deformation_minimizer(),
        moduli::cell_stiffness(threshold, &params),
    )?;
    let stabilise_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let stabilised = moduli::measure_strained(&mut s.cell, &s.rattler, &params)?;
    let bodies = scene.packing().len().max(1) as f64;
    let count = s.cell.contact_count(&s.rattler);
    let fallbacks = std::mem::take(&mut s.dense_fallbacks);
    Ok(ModuliMeasures {
        moduli: stabilised,
        params,
        wall_s: start.elapsed().as_secs_f64(),
        stabilisation: Some(jamkit_format::Stabilisation {
            deformation: (0..D)
                .map(|a| (0..D).map(|b| s.deformation[(a, b)]).collect())
                .collect(),
            residual: s.residual,
            residual_before: s.residual_before,
            energy_before: s.energy_before / bodies,
            energy_after: s.energy_after / bodies,
            pressure_before: s.pressure_before,
            pressure_after: s.pressure_after,
            iterations: s.iterations,
            stiffness_min: s.stiffness_min,
            fixed_box,
            wall_s: stabilise_s,
            dense_fallbacks: (!fallbacks.is_empty()).then_some(fallbacks.len() as u32),
            dense_fallback_reasons: (!fallbacks.is_empty()).then_some(fallbacks),
            contacts: Some(jamkit_format::CellContacts {
                n_contacts: count.n_contacts,
                n_rattlers: count.n_rattlers,
                z: count.z,
                iso_margin: count.iso_margin,
            }),
        }),
    })
}

/// Measure what `e` asks for on a relaxed scene. A failure names the
/// observable being measured (`Spectrum`, `Moduli`).
fn observe<const D: usize, S: Shape<D>>(
    e: &Experiment,
    protocol: &Protocol,
    scene: &mut Scene<D, S>,
) -> Result<Observed, (&'static str, jamkit_core::Error)> {
    let contacts = e
        .needs_contacts()
        .then(|| summarize_with(scene, rattler_rule(e, scene.packing())));
    let pressure = e.wants(&Observable::Pressure).then(|| scene.pressure());
    let rattler = contacts.as_ref().map_or(&[][..], |s| &s.rattler[..]);
    let (spectrum, eigenvalue_table) = match e.spectrum() {
        Some(request) => {
            let (m, table) =
                measure_spectrum(scene, rattler, &request).map_err(|err| ("Spectrum", err))?;
            (Some(m), table)
        }
        None => (None, None),
    };
    let gaps = e
        .gaps()
        .map(|params| GapCounts::of_scene(scene, rattler, &params));
    let mut stabilisation_failed = None;
    let moduli = match e.moduli() {
        Some(params) => {
            let start = Instant::now();
            let moduli = jamkit_observe::moduli::measure(scene, rattler, &params)
                .map_err(|err| ("Moduli", err))?;
            let wall_s = start.elapsed().as_secs_f64();
            let fixed_box = |moduli| ModuliMeasures {
                moduli,
                params: params.clone(),
                wall_s,
                stabilisation: None,
            };
            if protocol.shear_stabilised() {
                let threshold =
                    stabilisation_threshold(e, scene.packing()).map_err(|err| ("Moduli", err))?;
                match stabilised_moduli(protocol, scene, threshold, moduli.clone(), params.clone())
                {
                    Ok(m) => Some(m),
                    // The fixed box's moduli, and the failure for the
                    // caller to keep (`Observed::stabilisation_failed`).
                    Err(failure) => {
                        stabilisation_failed = Some(failure);
                        Some(fixed_box(moduli))
                    }
                }
            } else {
                Some(fixed_box(moduli))
            }
        }
        None => None,
    };
    Ok(Observed {
        contacts,
        pressure,
        spectrum,
        eigenvalue_table,
        gaps,
        moduli,
        stabilisation_failed,
    })
}

impl Observed {
    /// Nothing measured (the measures of a file before its observables).
    fn unmeasured() -> Self {
        Self {
            contacts: None,
            pressure: None,
            spectrum: None,
            eigenvalue_table: None,
            gaps: None,
            moduli: None,
            stabilisation_failed: None,
        }
    }

    fn measures<const D: usize, S: Shape<D>>(
        &self,
        protocol: &Protocol,
        run: Protocolled,
        shape: &S,
    ) -> Measures {
        let contacts = self.contacts.as_ref();
        let policy = shape.policy();
        let mut flags = policy.warnings;
        if let (Some(s), Protocol::Jam { .. }, true) =
            (contacts, protocol, policy.expects_isostatic)
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
            lbfgs_evaluations: run.lbfgs_evaluations,
            minimizations: run.minimizations,
            plateau_escapes: run.plateau_escapes,
            dt_cuts: run.dt_cuts,
            wall_s: run.wall_s,
            flag: flags.join("; "),
            saddle_escapes: run.saddle_escapes,
            spectrum: self.spectrum.clone(),
            gaps: self.gaps.clone(),
            n_rot_rattlers: contacts.map(|s| s.n_rot_rattlers),
            free_rotations: contacts.map(|s| s.free_rotations),
            moduli: self.moduli.clone(),
            jam_point: run.jam_point,
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
/// other observables), on the point's shape `on` or, `None`, the shape
/// its file names; the protocol's own figures are kept, and the measuring
/// time is added to `wall_s`.
/// [`remeasure`] on the shape the file names: the observables of `e`
/// measured on the packing of `file` as its arrays are (a packing of
/// another code, or one edited since).
pub fn measure_file(
    e: &Experiment,
    file: PackingFile,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    remeasure(e, None, file)
}

pub(crate) fn remeasure(
    e: &Experiment,
    on: Option<&dyn Sampler>,
    file: PackingFile,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let old = &file.measures;
    let run = Protocolled {
        phi: old.phi,
        energy_per_particle: old.energy_per_particle,
        fire_steps: old.fire_steps,
        lbfgs_evaluations: old.lbfgs_evaluations,
        minimizations: old.minimizations,
        plateau_escapes: old.plateau_escapes,
        dt_cuts: old.dt_cuts,
        wall_s: old.wall_s,
        saddle_escapes: old.saddle_escapes,
        jam_point: old.jam_point.clone(),
    };
    let id = file.id.clone();
    let (file, observed) = match on {
        Some(sampler) => sampler.measure(e, file, run)?,
        None => measure_saved(e, file, run)?,
    };
    // The saved packing stays as it was.
    if let Some(source) = observed.stabilisation_failed {
        return Err(ExperimentError::measuring(id, "Moduli", source));
    }
    Ok((file, observed.eigenvalue_table))
}

/// The observables of `e` measured on the configuration of `file` as
/// `reload` gives it back (the shape its file names), with the protocol's
/// figures `run`: [`measure_scene`].
fn measure_saved(
    e: &Experiment,
    file: PackingFile,
    run: Protocolled,
) -> Result<(PackingFile, Observed), ExperimentError> {
    struct Measure<'a> {
        e: &'a Experiment,
        file: PackingFile,
        run: Protocolled,
    }
    impl PackingVisitor for Measure<'_> {
        type Output = Result<(PackingFile, Observed), ExperimentError>;
        fn visit<const D: usize, S: Shape<D>>(self, scene: Scene<D, S>) -> Self::Output {
            measure_scene(self.e, &self.e.protocol, scene, self.file, self.run)
        }
    }
    let id = file.id.clone();
    reload(&file.clone(), Measure { e, file, run })
        .and_then(|r| r)
        .map_err(|err| in_packing(&id, err))
}

/// The observables of `e` measured on `scene`, the configuration of
/// `file` as its file records it, made by `protocol` (the grid point's:
/// a scan may set its stabilisation), with the protocol's figures `run` (the
/// measuring time added to its `wall_s`): `file` with those measures, its
/// rattler flags and observables, and what was observed. A sample's own
/// measures and a re-measure of its saved packing both come from here, so
/// they are the same bits. A failed stabilisation is left in
/// `Observed::stabilisation_failed` for the caller.
fn measure_scene<const D: usize, S: Shape<D>>(
    e: &Experiment,
    protocol: &Protocol,
    mut scene: Scene<D, S>,
    mut file: PackingFile,
    mut run: Protocolled,
) -> Result<(PackingFile, Observed), ExperimentError> {
    let start = Instant::now();
    let observed = observe(e, protocol, &mut scene).map_err(|(observable, source)| {
        ExperimentError::measuring(file.id.clone(), observable, source)
    })?;
    run.wall_s += start.elapsed().as_secs_f64();
    file.measures = observed.measures(protocol, run, &scene.packing().shape);
    file.phi = file.measures.phi;
    file.energy_per_particle = file.measures.energy_per_particle;
    file.rattler = observed.rattler();
    file.observables = observables_value(e);
    Ok((file, observed))
}

/// An error of the packing `id` that is not a sample's own, named as the
/// packing's.
fn in_packing(id: &str, err: ExperimentError) -> ExperimentError {
    match err {
        ExperimentError::Sample { .. } => err,
        other => ExperimentError::invalid(format!("packing {id}"), "…", other.to_string()),
    }
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
    let softest = s.softest(request.dos.omega_zero).map(|(n, m)| SoftestMode {
        omega: spectrum::frequency(s.eigenvalues[n]),
        participation: m.participation,
        rotational_share: m.rotational_share,
    });
    let measures = SpectrumMeasures {
        coordinates: s.eigenvalues.len(),
        zero_modes: s.zero,
        lambda_min: s.eigenvalues.first().copied().unwrap_or(f64::NAN),
        lambda_max: s.eigenvalues.last().copied().unwrap_or(f64::NAN),
        histogram: s.histogram,
        dos: request.dos.clone(),
        wall_s: start.elapsed().as_secs_f64(),
        softest,
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
pub fn sphere_rows<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> Vec<Vec<f64>> {
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
