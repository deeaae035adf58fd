//! `jamkit bench`: timings of the engine, for docs/reports/performance.md.
//!
//! * `packing`: one packing with the paper's protocol per seed, one thread:
//!   binary disks (default) or near-disks (`--family fourier --n 2 --delta 0.1`,
//!   with `--gap first-order|second-order|exact`);
//! * `eval`: time per energy-and-gradient evaluation against N;
//! * `accuracy`: speed against error of the gap models and tolerances
//!   (`bench_accuracy.rs`, which chains `pair`, two experiment files and
//!   their report);
//! * `pair`: time and error of one pair evaluation per gap model
//!   (`bench_pair.rs`);
//! * `spectrum`: Hessian assembly and eigensolvers (`bench_spectrum.rs`).
//!
//! Each packing line ends with a hash of the final state (box, centres,
//! orientations, bit for bit), so that two builds can be checked to give
//! identical packings.

use anyhow::Result;
use clap::{Subcommand, ValueEnum};
use jamkit_core::BodyOrientation;
use jamkit_core::{Packing, Potential, Shape, SizeDistribution};
use jamkit_engine::{
    Fire, FireParams, FireVariant, ForceCriterion, JamParams, JamSearch, LbfgsChoice, LbfgsParams,
    Masses, Objective, PreconParams, Scene, jam,
};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_observe::summarize;
use jamkit_planar::gap2d::GapModel;
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::io::Write;
use std::time::Instant;

/// The gap model of near-disks on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum GapArg {
    /// The paper's first-order gap.
    #[default]
    FirstOrder,
    /// With its O(Δ²) correction.
    SecondOrder,
    /// The exact gap along the common normal (convex outlines only).
    Exact,
}

impl From<GapArg> for GapModel {
    fn from(g: GapArg) -> Self {
        match g {
            GapArg::FirstOrder => GapModel::FirstOrder,
            GapArg::SecondOrder => GapModel::SecondOrder,
            GapArg::Exact => GapModel::Exact,
        }
    }
}

/// The minimiser of `bench packing`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum MinimizerArg {
    /// The paper's FIRE, as jamkit ran it before the Newton finish
    /// (`FireParams::paper()`, bit for bit).
    Paper,
    /// FIRE 2.0 (Guénolé et al. 2020).
    Fire2,
    /// FIRE with the Newton finish.
    #[default]
    Newton,
    /// FIRE 2.0 with the Newton finish.
    Fire2Newton,
}

/// The force criterion of `bench packing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CriterionArg {
    /// Σ g² (the paper as written).
    Sum,
    /// Σ g² / N (the author's code).
    PerBody,
    /// max g².
    Max,
}

impl MinimizerArg {
    /// The parameters, with `criterion` and the Newton interval `after`.
    pub fn params(self, criterion: Option<CriterionArg>, after: Option<u64>) -> FireParams {
        let mut p = match self {
            MinimizerArg::Paper => FireParams::paper(),
            MinimizerArg::Fire2 => FireParams {
                variant: FireVariant::Fire2,
                ..FireParams::paper()
            },
            MinimizerArg::Newton => FireParams::fire_newton(),
            MinimizerArg::Fire2Newton => FireParams {
                variant: FireVariant::Fire2,
                ..FireParams::fire_newton()
            },
        };
        if let Some(c) = criterion {
            p.force_criterion = match c {
                CriterionArg::Sum => ForceCriterion::Sum,
                CriterionArg::PerBody => ForceCriterion::PerBody,
                CriterionArg::Max => ForceCriterion::Max,
            };
        }
        if let (Some(a), Some(nw)) = (after, p.newton.as_mut()) {
            nw.after = a;
        }
        p
    }
}

/// The jamming search in `bench packing`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum SearchArg {
    /// The paper's halved steps.
    Bisection,
    /// The decompression the pressure predicts.
    Extrapolated,
}

/// FIRE's masses in `bench packing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MassesArg {
    /// The family's default (`masses: Family`, as in experiment files):
    /// `blocks-jammed` for bodies made of spheres (`nmer`) in 3D, `plain`
    /// otherwise.
    Family,
    /// The bodies' own masses (the paper).
    Plain,
    /// Each body's own stiffness block (block-preconditioned FIRE).
    Blocks,
    /// The blocks only where a minimisation starts from a decompressed
    /// jammed state (`masses: Blocks((jammed_only: true))`).
    BlocksJammed,
}

/// Which bodies `bench packing` jams.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchFamily {
    /// Binary disks (spheres in `--dim 3`).
    Sphere,
    /// The paper's near-disks `R0 [1 + Δ sin(nθ)/n]` (2D only).
    Fourier,
    /// Rigid dimers of aspect ratio `--alpha` (2D and 3D).
    Nmer,
}

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Time whole jammed packings (paper's protocol, one thread).
    Packing {
        /// Number of bodies.
        #[arg(long, default_value_t = 1024)]
        particles: usize,
        /// Seeds to run (one packing each).
        #[arg(long, value_delimiter = ',', default_value = "1")]
        seeds: Vec<u64>,
        /// Dimension (2 or 3; near-disks are 2D only).
        #[arg(long, default_value_t = 2)]
        dim: usize,
        /// Shape family.
        #[arg(long, value_enum, default_value_t = BenchFamily::Sphere)]
        family: BenchFamily,
        /// Mode number of the near-disks.
        #[arg(long, default_value_t = 2)]
        n: u32,
        /// Δ of the near-disks.
        #[arg(long, default_value_t = 0.1)]
        delta: f64,
        /// Aspect ratio of the dimers (`--family nmer`).
        #[arg(long, default_value_t = 1.1)]
        alpha: f64,
        /// Moment of inertia of the near-disks (default: the paper's I = Δ).
        #[arg(long)]
        inertia: Option<f64>,
        /// Gap model of the near-disks.
        #[arg(long, value_enum, default_value_t = GapArg::FirstOrder)]
        gap: GapArg,
        /// Verlet skin in units of the smallest bounding radius (as
        /// `engine.skin` in an experiment file).
        #[arg(long, default_value_t = 0.4)]
        skin: f64,
        /// Minimiser [default: `newton`, as in experiment files; `paper` is
        /// the paper's FIRE].
        #[arg(long, value_enum, default_value_t = MinimizerArg::default())]
        minimizer: MinimizerArg,
        /// Force criterion [default: the minimiser's].
        #[arg(long, value_enum)]
        force_criterion: Option<CriterionArg>,
        /// FIRE steps before the Newton finish [default: the minimiser's].
        #[arg(long)]
        newton_after: Option<u64>,
        /// No Newton finish (`minimizer.newton: None`), whatever the
        /// minimiser.
        #[arg(long)]
        no_newton: bool,
        /// L-BFGS (`minimizer.lbfgs`) after this many FIRE steps of a
        /// minimisation without convergence (`0`: L-BFGS from the start,
        /// FIRE only where it gives up) [default: the family's, as in
        /// experiment files: `--lbfgs-after 0 --lbfgs-blocks` for n-mers
        /// in 3D with FIRE, none otherwise; none with `--minimizer paper`].
        #[arg(long, conflicts_with = "no_lbfgs")]
        lbfgs_after: Option<u64>,
        /// No L-BFGS (`minimizer.lbfgs: None`), whatever the family.
        #[arg(long)]
        no_lbfgs: bool,
        /// Pairs L-BFGS keeps (`minimizer.lbfgs.memory`) [default: 8].
        #[arg(long, requires = "lbfgs_after")]
        lbfgs_memory: Option<u32>,
        /// L-BFGS's largest change of a coordinate per iteration
        /// (`minimizer.lbfgs.max_step`) [default: 0.05].
        #[arg(long, requires = "lbfgs_after")]
        lbfgs_max_step: Option<f64>,
        /// L-BFGS only in the minimisations that start from a decompressed
        /// jammed state (`minimizer.lbfgs.jammed_only: true`).
        #[arg(long, requires = "lbfgs_after")]
        lbfgs_jammed_only: bool,
        /// L-BFGS's `H₀` from each body's stiffness block
        /// (`minimizer.lbfgs.blocks: true`).
        #[arg(long, requires = "lbfgs_after")]
        lbfgs_blocks: bool,
        /// FIRE's masses (`minimizer.masses`): the family's default
        /// (`family`), the bodies' own (`plain`, the paper) or each body's
        /// stiffness block (`blocks`: block-preconditioned FIRE) [default:
        /// `family`, as in experiment files; `plain` with `--minimizer
        /// paper`, so that it is the paper's FIRE bit for bit].
        #[arg(long, value_enum)]
        masses: Option<MassesArg>,
        /// The block preconditioner's floor `c` [default: 0.25].
        #[arg(long)]
        precon_floor: Option<f64>,
        /// FIRE steps between rebuilds of the blocks [default: 100].
        #[arg(long)]
        precon_refresh: Option<u64>,
        /// FIRE's largest time step [default: the family's].
        #[arg(long)]
        dt_max: Option<f64>,
        /// How the jamming search decompresses a jammed state
        /// (`protocol.search`): the step its pressure predicts
        /// (`extrapolated`) or the paper's halved steps (`bisection`)
        /// [default: `bisection` with `--minimizer paper`, so that it is the
        /// paper's path bit for bit; `extrapolated` otherwise].
        #[arg(long, value_enum)]
        search: Option<SearchArg>,
        /// Write every minimisation (φ, FIRE steps, Newton iterations, why it
        /// stopped, V/N, Σ g², L-BFGS evaluations) of every packing to this
        /// CSV (a step trace).
        #[arg(long, value_name = "FILE")]
        trace: Option<std::path::PathBuf>,
    },
    /// Time one energy+gradient evaluation of binary disks at phi = 0.84.
    Eval {
        /// Particle numbers.
        #[arg(long, value_delimiter = ',', default_value = "256,1024,4096,16384")]
        particles: Vec<usize>,
    },
    /// Speed against error of the near-disk gap models and of FIRE's
    /// tolerances: CSV, figures and tables.md (docs/reports/speed-vs-error.md).
    Accuracy {
        /// Output directory; the default also rewrites the generated block
        /// of docs/reports/speed-vs-error.md.
        #[arg(short, long, value_name = "DIR", default_value = crate::bench_accuracy::DEFAULT_OUT)]
        out: std::path::PathBuf,
        /// Directory of the runner's runs of experiments/accuracy/*.ron
        /// (the gap models and the tolerances); a rerun into it resumes,
        /// reading back every packing it holds.
        #[arg(long, value_name = "DIR", default_value = crate::bench_accuracy::DEFAULT_RUNS)]
        runs: std::path::PathBuf,
        /// Small sizes, for a smoke test (seconds): fewer pairs, and the
        /// files with --set particles=10 samples=1 params.delta=0.1 (gap
        /// models) and particles=12 samples=2 (tolerances).
        #[arg(long)]
        quick: bool,
        /// Override a field of experiments/accuracy/gap_models.ron, as
        /// `jamkit run --set` does: --set-gap-models samples=1.
        #[arg(long = "set-gap-models", value_name = "KEY=VALUE")]
        set_gap_models: Vec<String>,
        /// Override a field of experiments/accuracy/tolerances.ron (every
        /// setting of the ladder): --set-tolerances particles=64.
        #[arg(long = "set-tolerances", value_name = "KEY=VALUE")]
        set_tolerances: Vec<String>,
        /// Worker threads of the runs (packings in parallel; 1 keeps the
        /// wall times of one core). Results do not depend on it.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
    },
    /// Time and error of one pair evaluation (gap and gradient) of the
    /// near-disk gap models: pairs.csv, slopes.csv, figures and pairs.md
    /// (the pair benchmark of `bench accuracy`, on its own).
    Pair {
        /// Output directory.
        #[arg(short, long, value_name = "DIR", default_value = crate::bench_pair::DEFAULT_OUT)]
        out: std::path::PathBuf,
        /// Fewer pairs and shorter timings, for a smoke test (seconds).
        #[arg(long)]
        quick: bool,
    },
    /// Time Hessian assembly and eigenvalues of near-disks (n = 2, Δ = 0.1).
    Spectrum {
        /// Particle numbers (3 coordinates each).
        #[arg(long, value_delimiter = ',', default_value = "256,512,1024")]
        particles: Vec<usize>,
        /// Also time nalgebra's symmetric eigensolver (slow at N = 1024).
        #[arg(long)]
        nalgebra: bool,
    },
}

pub fn run(what: BenchCommand) -> Result<()> {
    match what {
        BenchCommand::Accuracy {
            out,
            runs,
            quick,
            set_gap_models,
            set_tolerances,
            jobs,
        } => crate::bench_accuracy::run(&crate::bench_accuracy::Options {
            out,
            runs,
            quick,
            set_gap_models,
            set_tolerances,
            jobs,
        }),
        BenchCommand::Pair { out, quick } => {
            crate::bench_pair::run(&crate::bench_pair::Options { out, quick })
        }
        BenchCommand::Spectrum {
            particles,
            nalgebra,
        } => crate::bench_spectrum::run(&particles, nalgebra),
        BenchCommand::Packing {
            particles,
            seeds,
            dim,
            family,
            n,
            delta,
            inertia,
            gap,
            skin,
            alpha,
            minimizer,
            force_criterion,
            newton_after,
            no_newton,
            lbfgs_after,
            no_lbfgs,
            lbfgs_memory,
            lbfgs_max_step,
            lbfgs_jammed_only,
            lbfgs_blocks,
            masses,
            precon_floor,
            precon_refresh,
            dt_max,
            search,
            trace,
        } => {
            let jam_params = JamParams {
                search: match search {
                    Some(SearchArg::Bisection) => JamSearch::Bisection,
                    Some(SearchArg::Extrapolated) => JamSearch::Extrapolated,
                    None if minimizer == MinimizerArg::Paper => JamSearch::Bisection,
                    None => JamSearch::default(),
                },
                ..JamParams::default()
            };
            let mut fire = minimizer.params(force_criterion, newton_after);
            let d = PreconParams::default();
            let blocks = PreconParams {
                floor: precon_floor.unwrap_or(d.floor),
                refresh: precon_refresh.unwrap_or(d.refresh),
                ..d
            };
            fire.masses = match masses {
                None if minimizer == MinimizerArg::Paper => Masses::Plain,
                None | Some(MassesArg::Family) => Masses::Family,
                Some(MassesArg::Plain) => Masses::Plain,
                Some(MassesArg::Blocks) => Masses::Blocks(blocks),
                Some(MassesArg::BlocksJammed) => Masses::Blocks(PreconParams {
                    jammed_only: true,
                    ..blocks
                }),
            };
            fire.dt_max = dt_max.or(fire.dt_max);
            if no_newton {
                fire.newton = None;
            }
            fire.lbfgs = match lbfgs_after {
                Some(after) => {
                    let d = LbfgsParams::default();
                    LbfgsChoice::On(LbfgsParams {
                        after,
                        memory: lbfgs_memory.unwrap_or(d.memory),
                        max_step: lbfgs_max_step.unwrap_or(d.max_step),
                        jammed_only: lbfgs_jammed_only,
                        blocks: lbfgs_blocks,
                        ..d
                    })
                }
                None if no_lbfgs || minimizer == MinimizerArg::Paper => LbfgsChoice::Off,
                None => LbfgsChoice::Family,
            };
            fire.validate("minimizer")?;
            let mut trace_out = match &trace {
                Some(path) => {
                    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
                    writeln!(
                        f,
                        "seed,phi,fire_steps,newton_iterations,reason,energy_per_particle,force_sq,lbfgs_evals"
                    )?;
                    Some(f)
                }
                None => None,
            };
            out!(
                "family,dim,particles,seed,phi_j,z_j,iso_margin,fire_steps,wall_s,us_per_step,packing_hash,newton_iterations,cpu_s,lbfgs_evals"
            );
            for seed in seeds {
                // One packing of `shape` in `D` dimensions with this seed.
                macro_rules! bench {
                    ($d:literal, $shape:expr) => {
                        bench_packing::<$d, _>(
                            $shape,
                            particles,
                            seed,
                            skin,
                            &fire,
                            &jam_params,
                            trace_out.as_mut(),
                        )?
                    };
                }
                match (family, dim) {
                    (BenchFamily::Sphere, 2) => bench!(2, Sphere),
                    (BenchFamily::Sphere, 3) => bench!(3, Sphere),
                    (BenchFamily::Fourier, 2) => {
                        let shape = NearDisk::fourier(&FourierParams {
                            n,
                            delta,
                            inertia,
                            gap: gap.into(),
                        })
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                        bench!(2, shape)
                    }
                    (BenchFamily::Nmer, 2) => bench!(2, dimer::<2>(alpha)?),
                    (BenchFamily::Nmer, 3) => bench!(3, dimer::<3>(alpha)?),
                    _ => anyhow::bail!("--dim {dim}: must be 2 or 3 (2 for near-disks)"),
                }
            }
            Ok(())
        }
        BenchCommand::Eval { particles } => {
            out!("particles,pairs,us_per_eval,ns_per_particle");
            for n in particles {
                let mut scene = random_scene::<2, _>(Sphere, n, 1, 0.84, 0.4)?;
                let mut g = vec![0.0; scene.dof()];
                let reps = (20_000_000 / n).max(10);
                scene.energy_gradient(&mut g);
                let t = Instant::now();
                let mut sink = 0.0;
                for _ in 0..reps {
                    sink += scene.energy_gradient(&mut g);
                }
                let us = t.elapsed().as_secs_f64() * 1e6 / reps as f64;
                assert!(sink.is_finite());
                out!(
                    "{n},{},{us:.3},{:.2}",
                    scene.neighbor_pairs(),
                    us * 1e3 / n as f64
                );
            }
            Ok(())
        }
    }
}

/// A rigid dimer of aspect ratio `alpha`.
fn dimer<const D: usize>(alpha: f64) -> Result<jamkit_nmer::Nmer<D>>
where
    jamkit_nmer::Nmer<D>: Shape<D>,
{
    jamkit_nmer::Nmer::<D>::new(&jamkit_nmer::NmerParams {
        alpha: Some(alpha),
        spheres: None,
        inertia: None,
    })
    .map_err(|e| anyhow::anyhow!("{e}"))
}

/// A random scene as `jamkit run` builds it: sizes, then centres, then
/// orientations from one stream, skin `skin` × the smallest bounding radius.
pub(crate) fn random_scene<const D: usize, S: Shape<D>>(
    shape: S,
    n: usize,
    seed: u64,
    phi: f64,
    skin: f64,
) -> Result<Scene<D, S>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let min_reach = sizes
        .iter()
        .map(|&s| shape.bounding_radius(s))
        .fold(f64::INFINITY, f64::min);
    let packing = Packing::<D, S>::random(shape, sizes, phi, &mut rng)?;
    Ok(Scene::new(packing, Potential::Harmonic, skin * min_reach))
}

/// FNV-1a over the bits of the box edges, centres and orientation coordinates.
pub(crate) fn packing_hash<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for b in x.to_bits().to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    };
    p.bbox.edges().iter().for_each(|&x| eat(x));
    for (r, o) in p.positions.iter().zip(&p.orientations) {
        r.iter().for_each(|&x| eat(x));
        o.to_coords().into_iter().for_each(&mut eat);
    }
    h
}

fn bench_packing<const D: usize, S: Shape<D>>(
    shape: S,
    n: usize,
    seed: u64,
    skin: f64,
    params: &FireParams,
    jam_params: &JamParams,
    trace: Option<&mut std::io::BufWriter<std::fs::File>>,
) -> Result<()> {
    let family = shape.family();
    // The family's time step, as `jamkit run` resolves it.
    let mut fire = Fire::new(params.for_family(&shape));
    let mut scene = random_scene::<D, S>(shape, n, seed, 0.1, skin)?;
    if trace.is_some() {
        fire.record();
    }
    let cpu = cpu_seconds();
    let t = Instant::now();
    let out = jam(&mut scene, &mut fire, jam_params)?;
    let wall = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu;
    if let Some(f) = trace {
        for (phi, m) in fire.take_trace() {
            writeln!(
                f,
                "{seed},{phi:.15},{},{},{:?},{:e},{:e},{}",
                m.steps,
                m.newton_iterations,
                m.reason,
                m.energy / n as f64,
                m.force_sq,
                m.lbfgs_evaluations
            )?;
        }
        f.flush()?;
    }
    let threshold = scene.packing().shape.policy().rattler_threshold;
    let s = summarize(&mut scene, threshold);
    out!(
        "{family},{D},{n},{seed},{:.6},{:.4},{},{},{wall:.2},{:.2},{:016x},{},{cpu:.2},{}",
        out.phi,
        s.z_j,
        s.iso_margin,
        out.fire_steps,
        // Per energy-and-gradient evaluation: FIRE's steps and L-BFGS's.
        wall * 1e6 / (out.fire_steps + out.lbfgs_evaluations).max(1) as f64,
        packing_hash(scene.packing()),
        out.newton_iterations,
        out.lbfgs_evaluations
    );
    Ok(())
}

/// CPU time of this thread so far (user + system), in seconds; NaN where
/// it cannot be read.
fn cpu_seconds() -> f64 {
    // /proc/thread-self/stat fields 14 and 15: utime and stime in clock ticks.
    let Ok(stat) = std::fs::read_to_string("/proc/thread-self/stat") else {
        return f64::NAN;
    };
    let Some(after) = stat.rsplit_once(')').map(|(_, a)| a) else {
        return f64::NAN;
    };
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok());
    match (ticks(11), ticks(12)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}
