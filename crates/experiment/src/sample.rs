//! One sample, from start to end: the family's shape for its point, the
//! random start from its seed, the protocol (the engine's `jam`,
//! `compress_to_phi`, `compress_to_pressure` or `above_jam`, with the saddle
//! escape when asked), the observables (contacts and rattlers, pressure,
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
    AboveJamParams, Fire, FireParams, JamParams, PressureParams, Progress, Scene, above_jam,
    compress_to_phi, compress_to_pressure, jam,
};
use jamkit_format::{JamPoint, Measures, ModuliMeasures, PackingFile, SpectrumMeasures};
use jamkit_observe::gaps::{CountGaps, GapCounts};
use jamkit_observe::spectrum::{self, Spectrum};
use jamkit_observe::{JammingSummary, RattlerRule, summarize, summarize_with};
use jamkit_registry::{self as registry, SceneVisitor};
use rand::SeedableRng;
use std::sync::Arc;
use std::time::Instant;

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
        "protocol": protocol_settings(&point.protocol),
        "minimizer": minimizer_settings(minimizer),
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

/// The minimiser as a packing records it: as resolved for the family
/// (`FireParams::for_family`), except that `lbfgs: None` is left out.
/// Packings made before the field existed ran without L-BFGS and record
/// none, so they still resume under an explicit `lbfgs: None`; where the
/// family's default is L-BFGS it is always written, so no packing of one
/// minimiser is ever taken for the other's.
fn minimizer_settings(minimizer: &FireParams) -> serde_json::Value {
    let mut value = serde_json::to_value(minimizer).expect("minimizer serialises");
    if let Some(m) = value.as_object_mut()
        && m.get("lbfgs") == Some(&serde_json::Value::Null)
    {
        m.remove("lbfgs");
    }
    value
}

/// The observables of `experiment`, as stored with each packing.
pub(crate) fn observables_value(experiment: &Experiment) -> serde_json::Value {
    serde_json::to_value(&experiment.observables).expect("observables serialise")
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
    let jammed = jam_job_watched(experiment, point, job, progress)?;
    measure_jammed(experiment, jammed)
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
}

/// The first half of [`run_job_watched`]: the packing of `job` at the end
/// of its protocol, unmeasured ([`measure_jammed`] measures it).
pub fn jam_job_watched(
    experiment: &Experiment,
    point: &Point,
    job: &Job,
    progress: Option<Arc<Progress>>,
) -> Result<Jammed, ExperimentError> {
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
    type Output = Result<Jammed, ExperimentError>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Self::Output {
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
        self.protocol(scene, start)
    }
}

impl SampleVisitor<'_> {
    /// The protocol of the sample's point from the configuration of
    /// `scene` (a random start, or a packing given by the caller), `start`
    /// the sample's start time.
    fn protocol<const D: usize, S: Shape<D>>(
        &self,
        mut scene: Scene<D, S>,
        start: Instant,
    ) -> Result<Jammed, ExperimentError> {
        let (e, job) = (self.experiment, self.job);
        let minimizer = self.point.minimizer.clone();
        let protocol = &self.point.protocol;
        let mut fire = Fire::new(minimizer);
        if let Some(p) = &self.progress {
            fire.watch(p.clone());
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
                        outcome.fire_steps += s.fire_steps;
                        outcome.lbfgs_evaluations += s.lbfgs_evaluations;
                        outcome.minimizations += s.minimizations;
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
            fire_steps: outcome.fire_steps,
            lbfgs_evaluations: self
                .point
                .minimizer
                .lbfgs
                .params()
                .map(|_| outcome.lbfgs_evaluations),
            minimizations: outcome.minimizations,
            wall_s: start.elapsed().as_secs_f64(),
            saddle_escapes,
            jam_point,
        };
        let shape = &scene.packing().shape;
        let unmeasured = Observed::unmeasured().measures(e, run.clone(), shape);
        let mut file = self.file(scene.packing(), true, unmeasured);
        file.observables = serde_json::json!([]);
        Ok(Jammed { file, run })
    }
}

/// The protocol of `experiment` (a single grid point: no lists) run from
/// the configuration of `file` instead of a random start, then its
/// observables, as a sample's: the packing file of the result, with the
/// id and seed of `file`, and the eigenvalue table if asked for. `file`'s
/// family, parameters, dimension and body count must be the experiment's.
pub fn run_from_file(
    experiment: &Experiment,
    file: &PackingFile,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let points = crate::grid::points(experiment)?;
    let [point] = &points[..] else {
        return Err(ExperimentError::invalid(
            "experiment",
            format!("{} grid points", points.len()),
            "must be one point (no lists) to run from a packing",
        ));
    };
    let job = Job {
        point: 0,
        sample: 0,
        seed: file.seed,
        id: file.id.clone(),
    };
    struct FromFile<'a>(SampleVisitor<'a>);
    impl PackingVisitor for FromFile<'_> {
        type Output = Result<Jammed, ExperimentError>;
        fn visit<const D: usize, S: Shape<D>>(self, scene: Scene<D, S>) -> Self::Output {
            self.0.protocol(scene, Instant::now())
        }
    }
    let visitor = SampleVisitor {
        experiment,
        point,
        job: &job,
        progress: None,
    };
    let jammed = reload(file, FromFile(visitor))??;
    measure_jammed(experiment, jammed)
}

/// The second half of [`run_job_watched`]: the observables of `experiment`
/// measured on the jammed packing (as its file records it), and the
/// eigenvalue table if asked for. A failed shear stabilisation is an error
/// carrying the fixed-box packing as its `state` (the runner keeps it as
/// `<id>.failed.json`).
pub fn measure_jammed(
    experiment: &Experiment,
    jammed: Jammed,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let e = experiment;
    let Jammed { file, run } = jammed;
    let id = file.id.clone();
    let (mut file, mut observed) = measure_saved(e, file, run)?;
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
        let (jamkit_version, git_commit) = jamkit_format::provenance::stamp();
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
            lbfgs_evaluations: None,
            minimizations: 0,
            wall_s: start.elapsed().as_secs_f64(),
            flag: error.to_string(),
            saddle_escapes: None,
            spectrum: None,
            gaps: None,
            moduli: None,
            jam_point: None,
        };
        Some(self.file(scene.packing(), true, measures))
    }
}

/// What the protocol ended with, as stored.
#[derive(Clone)]
struct Protocolled {
    phi: f64,
    energy_per_particle: f64,
    fire_steps: u64,
    /// L-BFGS evaluations, when the minimiser ran L-BFGS.
    lbfgs_evaluations: Option<u64>,
    minimizations: u64,
    wall_s: f64,
    saddle_escapes: Option<u32>,
    /// `AboveJam`'s jamming point.
    jam_point: Option<JamPoint>,
}

/// The observables of one packing.
struct Observed {
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
    e: &Experiment,
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
        ..e.protocol.stabilise().cloned().unwrap_or_default()
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
            if e.protocol.shear_stabilised() {
                let threshold =
                    stabilisation_threshold(e, scene.packing()).map_err(|err| ("Moduli", err))?;
                match stabilised_moduli(e, scene, threshold, moduli.clone(), params.clone()) {
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
        e: &Experiment,
        run: Protocolled,
        shape: &S,
    ) -> Measures {
        let contacts = self.contacts.as_ref();
        let policy = shape.policy();
        let mut flags = policy.warnings;
        if let (Some(s), Protocol::Jam { .. }, true) =
            (contacts, &e.protocol, policy.expects_isostatic)
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
/// other observables); the protocol's own figures are kept, and the
/// measuring time is added to `wall_s`.
pub fn remeasure(
    e: &Experiment,
    file: PackingFile,
) -> Result<(PackingFile, Option<String>), ExperimentError> {
    let old = &file.measures;
    let run = Protocolled {
        phi: old.phi,
        energy_per_particle: old.energy_per_particle,
        fire_steps: old.fire_steps,
        lbfgs_evaluations: old.lbfgs_evaluations,
        minimizations: old.minimizations,
        wall_s: old.wall_s,
        saddle_escapes: old.saddle_escapes,
        jam_point: old.jam_point.clone(),
    };
    let id = file.id.clone();
    let (file, observed) = measure_saved(e, file, run)?;
    // The saved packing stays as it was.
    if let Some(source) = observed.stabilisation_failed {
        return Err(ExperimentError::measuring(id, "Moduli", source));
    }
    Ok((file, observed.eigenvalue_table))
}

/// The observables of `e` measured on the configuration of `file` as
/// `reload` gives it back, with the protocol's figures `run` (the
/// measuring time added to its `wall_s`): `file` with those measures,
/// its rattler flags and observables, and what was observed. A sample's
/// own measures and a re-measure of its saved packing both come from
/// here, so they are the same bits. A failed stabilisation is left in
/// `Observed::stabilisation_failed` for the caller.
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
        fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
            let (e, mut file, mut run) = (self.e, self.file, self.run);
            let start = Instant::now();
            let observed = observe(e, &mut scene).map_err(|(observable, source)| {
                ExperimentError::measuring(file.id.clone(), observable, source)
            })?;
            run.wall_s += start.elapsed().as_secs_f64();
            file.measures = observed.measures(e, run, &scene.packing().shape);
            file.phi = file.measures.phi;
            file.energy_per_particle = file.measures.energy_per_particle;
            file.rattler = observed.rattler();
            file.observables = observables_value(e);
            Ok((file, observed))
        }
    }
    let id = file.id.clone();
    reload(&file.clone(), Measure { e, file, run })
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
