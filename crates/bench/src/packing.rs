//! `jamkit bench packing`: whole jammed packings with the paper's protocol,
//! one per seed, one thread: binary disks (default), near-disks
//! (`--family fourier --n 2 --delta 0.1`, with `--gap
//! first-order|second-order|exact`) or rigid dimers (`--family nmer`).
//!
//! Each line ends with a hash of the final state (box, centres,
//! orientations, bit for bit), so that two builds can be checked to give
//! identical packings.

use crate::output::Print;
use anyhow::Result;
use clap::ValueEnum;
use jamkit_core::{BodyOrientation, Packing, Potential, Shape, SizeDistribution};
use jamkit_engine::{
    Fire, FireParams, FireVariant, ForceCriterion, JamParams, JamSearch, LbfgsChoice, LbfgsParams,
    Masses, PreconParams, Scene, jam,
    saddle::{self, SaddleParams},
};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_observe::summarize;
use jamkit_planar::gap2d::GapModel;
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::io::Write;
use std::time::Instant;

/// The header of the lines [`run`] prints, one per packing.
pub const HEADER: &str = "family,dim,particles,seed,phi_j,z_j,iso_margin,fire_steps,wall_s,us_per_step,packing_hash,newton_iterations,cpu_s,lbfgs_evals,saddle_escapes,plateau_escapes,dt_cuts";
/// The header of the step trace (`--trace`).
pub const TRACE_HEADER: &str = "seed,phi,fire_steps,newton_iterations,reason,energy_per_particle,force_sq,lbfgs_evals,plateau_escapes,dt_cuts";

/// The gap model of near-disks on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum GapArg {
    /// The paper's first-order gap.
    #[default]
    FirstOrder,
    /// With its O(Δ²) correction.
    SecondOrder,
    /// The exact gap along the common normals (several contacts per pair on
    /// a non-convex outline).
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
    /// The predicted decompression, and a compression step that grows
    /// again where the jamming point has moved up (the default).
    Adaptive,
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

/// What `jamkit bench packing` was asked for.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Number of bodies.
    #[arg(long, default_value_t = 1024)]
    pub particles: usize,
    /// Seeds to run (one packing each).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// Dimension (2 or 3; near-disks are 2D only).
    #[arg(long, default_value_t = 2)]
    pub dim: usize,
    /// Shape family.
    #[arg(long, value_enum, default_value_t = BenchFamily::Sphere)]
    pub family: BenchFamily,
    /// Mode number of the near-disks.
    #[arg(long, default_value_t = 2)]
    pub n: u32,
    /// Δ of the near-disks.
    #[arg(long, default_value_t = 0.1)]
    pub delta: f64,
    /// Aspect ratio of the dimers (`--family nmer`).
    #[arg(long, default_value_t = 1.1)]
    pub alpha: f64,
    /// Moment of inertia of the near-disks (default: the paper's I = Δ).
    #[arg(long)]
    pub inertia: Option<f64>,
    /// Gap model of the near-disks.
    #[arg(long, value_enum, default_value_t = GapArg::FirstOrder)]
    pub gap: GapArg,
    /// Verlet skin in units of the smallest bounding radius (as
    /// `engine.skin` in an experiment file).
    #[arg(long, default_value_t = 0.4)]
    pub skin: f64,
    /// Minimiser [default: `newton`, as in experiment files; `paper` is
    /// the paper's FIRE].
    #[arg(long, value_enum, default_value_t = MinimizerArg::default())]
    pub minimizer: MinimizerArg,
    /// Force criterion [default: the minimiser's].
    #[arg(long, value_enum)]
    pub force_criterion: Option<CriterionArg>,
    /// FIRE steps before the Newton finish [default: the minimiser's].
    #[arg(long)]
    pub newton_after: Option<u64>,
    /// No Newton finish (`minimizer.newton: None`), whatever the
    /// minimiser.
    #[arg(long)]
    pub no_newton: bool,
    /// L-BFGS (`minimizer.lbfgs`) after this many FIRE steps of a
    /// minimisation without convergence (`0`: L-BFGS from the start,
    /// FIRE only where it gives up) [default: the family's, as in
    /// experiment files: `--lbfgs-after 0 --lbfgs-blocks` for n-mers
    /// in 3D with FIRE, none otherwise; none with `--minimizer paper`].
    #[arg(long, conflicts_with = "no_lbfgs")]
    pub lbfgs_after: Option<u64>,
    /// No L-BFGS (`minimizer.lbfgs: None`), whatever the family.
    #[arg(long)]
    pub no_lbfgs: bool,
    /// Pairs L-BFGS keeps (`minimizer.lbfgs.memory`) [default: 8].
    #[arg(long, requires = "lbfgs_after")]
    pub lbfgs_memory: Option<u32>,
    /// L-BFGS's largest change of a coordinate per iteration
    /// (`minimizer.lbfgs.max_step`) [default: 0.05].
    #[arg(long, requires = "lbfgs_after")]
    pub lbfgs_max_step: Option<f64>,
    /// L-BFGS only in the minimisations that start from a decompressed
    /// jammed state (`minimizer.lbfgs.jammed_only: true`).
    #[arg(long, requires = "lbfgs_after")]
    pub lbfgs_jammed_only: bool,
    /// L-BFGS's `H₀` from each body's stiffness block
    /// (`minimizer.lbfgs.blocks: true`).
    #[arg(long, requires = "lbfgs_after")]
    pub lbfgs_blocks: bool,
    /// FIRE's masses (`minimizer.masses`): the family's default
    /// (`family`), the bodies' own (`plain`, the paper) or each body's
    /// stiffness block (`blocks`: block-preconditioned FIRE) [default:
    /// `family`, as in experiment files; `plain` with `--minimizer
    /// paper`, so that it is the paper's FIRE bit for bit].
    #[arg(long, value_enum)]
    pub masses: Option<MassesArg>,
    /// The block preconditioner's floor `c` [default: 0.25].
    #[arg(long)]
    pub precon_floor: Option<f64>,
    /// FIRE steps between rebuilds of the blocks [default: 100].
    #[arg(long)]
    pub precon_refresh: Option<u64>,
    /// FIRE's largest time step [default: the family's].
    #[arg(long)]
    pub dt_max: Option<f64>,
    /// How the jamming search moves between compressions and
    /// decompressions (`protocol.search`)
    /// [default: `bisection` with `--minimizer paper`, so that it is the
    /// paper's path bit for bit; `adaptive` otherwise, as in experiment
    /// files].
    #[arg(long, value_enum)]
    pub search: Option<SearchArg>,
    /// No saddle escape after the search (`protocol.escape_saddles:
    /// false`) [default: the escape, as in experiment files; none with
    /// `--minimizer paper`, so that it is the paper's path bit for bit].
    #[arg(long)]
    pub no_saddle_escape: bool,
    /// No plateau escape in the Newton finish (`minimizer.escape_plateaus:
    /// false`) [default: the escape, as in experiment files; none with
    /// `--minimizer paper`, which has no Newton finish].
    #[arg(long)]
    pub no_plateau_escape: bool,
    /// Write every minimisation (φ, FIRE steps, Newton iterations, why it
    /// stopped, V/N, Σ g², L-BFGS evaluations, plateau escapes) of every packing to this
    /// CSV (a step trace).
    #[arg(long, value_name = "FILE")]
    pub trace: Option<std::path::PathBuf>,
}

impl Options {
    /// The jamming search: `--search`, else the paper's bisection with
    /// `--minimizer paper` and the default otherwise.
    pub fn jam_params(&self) -> JamParams {
        JamParams {
            search: match self.search {
                Some(SearchArg::Bisection) => JamSearch::Bisection,
                Some(SearchArg::Extrapolated) => JamSearch::Extrapolated,
                Some(SearchArg::Adaptive) => JamSearch::Adaptive,
                None if self.minimizer == MinimizerArg::Paper => JamSearch::Bisection,
                None => JamSearch::default(),
            },
            ..JamParams::default()
        }
    }

    /// Whether the saddle escape follows the search: not with
    /// `--no-saddle-escape` or `--minimizer paper`.
    pub fn escape_saddles(&self) -> bool {
        !self.no_saddle_escape && self.minimizer != MinimizerArg::Paper
    }

    /// The minimiser's parameters the flags describe, checked.
    pub fn fire_params(&self) -> Result<FireParams> {
        let mut fire = self
            .minimizer
            .params(self.force_criterion, self.newton_after);
        let d = PreconParams::default();
        let blocks = PreconParams {
            floor: self.precon_floor.unwrap_or(d.floor),
            refresh: self.precon_refresh.unwrap_or(d.refresh),
            ..d
        };
        fire.masses = match self.masses {
            None if self.minimizer == MinimizerArg::Paper => Masses::Plain,
            None | Some(MassesArg::Family) => Masses::Family,
            Some(MassesArg::Plain) => Masses::Plain,
            Some(MassesArg::Blocks) => Masses::Blocks(blocks),
            Some(MassesArg::BlocksJammed) => Masses::Blocks(PreconParams {
                jammed_only: true,
                ..blocks
            }),
        };
        fire.dt_max = self.dt_max.or(fire.dt_max);
        if self.no_newton {
            fire.newton = None;
        }
        if self.no_plateau_escape {
            fire.escape_plateaus = false;
        }
        fire.lbfgs = match self.lbfgs_after {
            Some(after) => {
                let d = LbfgsParams::default();
                LbfgsChoice::On(LbfgsParams {
                    after,
                    memory: self.lbfgs_memory.unwrap_or(d.memory),
                    max_step: self.lbfgs_max_step.unwrap_or(d.max_step),
                    jammed_only: self.lbfgs_jammed_only,
                    blocks: self.lbfgs_blocks,
                    ..d
                })
            }
            None if self.no_lbfgs || self.minimizer == MinimizerArg::Paper => LbfgsChoice::Off,
            None => LbfgsChoice::Family,
        };
        fire.validate("minimizer")?;
        Ok(fire)
    }
}

/// Make one packing per seed, printing [`HEADER`] and then one line per
/// packing as it is done; with `--trace` write the step trace too.
pub fn run(o: &Options, print: Print) -> Result<()> {
    let jam_params = o.jam_params();
    let fire = o.fire_params()?;
    let mut trace_out = match &o.trace {
        Some(path) => {
            let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
            writeln!(f, "{TRACE_HEADER}")?;
            Some(f)
        }
        None => None,
    };
    print(HEADER);
    for &seed in &o.seeds {
        // One packing of `shape` in `D` dimensions with this seed.
        macro_rules! bench {
            ($d:literal, $shape:expr) => {
                bench_packing::<$d, _>(
                    $shape,
                    o.particles,
                    seed,
                    o.skin,
                    &fire,
                    (&jam_params, o.escape_saddles()),
                    trace_out.as_mut(),
                )?
            };
        }
        let line = match (o.family, o.dim) {
            (BenchFamily::Sphere, 2) => bench!(2, Sphere),
            (BenchFamily::Sphere, 3) => bench!(3, Sphere),
            (BenchFamily::Fourier, 2) => {
                let shape = NearDisk::fourier(&FourierParams {
                    n: o.n,
                    delta: o.delta,
                    inertia: o.inertia,
                    gap: o.gap.into(),
                })
                .map_err(|e| anyhow::anyhow!("{e}"))?;
                bench!(2, shape)
            }
            (BenchFamily::Nmer, 2) => bench!(2, dimer::<2>(o.alpha)?),
            (BenchFamily::Nmer, 3) => bench!(3, dimer::<3>(o.alpha)?),
            (_, dim) => anyhow::bail!("--dim {dim}: must be 2 or 3 (2 for near-disks)"),
        };
        print(&line);
    }
    Ok(())
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
pub fn random_scene<const D: usize, S: Shape<D>>(
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
pub fn packing_hash<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> u64 {
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

/// Jam one packing (the search of `jam_params`, then the saddle escape if
/// `escape`); its line of the table (see [`HEADER`]).
fn bench_packing<const D: usize, S: Shape<D>>(
    shape: S,
    n: usize,
    seed: u64,
    skin: f64,
    params: &FireParams,
    (jam_params, escape): (&JamParams, bool),
    trace: Option<&mut std::io::BufWriter<std::fs::File>>,
) -> Result<String> {
    let family = shape.family();
    // The family's time step, as `jamkit run` resolves it.
    let mut fire = Fire::new(params.for_family(&shape));
    let mut scene = random_scene::<D, S>(shape, n, seed, 0.1, skin)?;
    if trace.is_some() {
        fire.record();
    }
    let cpu = cpu_seconds();
    let t = Instant::now();
    let mut out = jam(&mut scene, &mut fire, jam_params)?;
    let threshold = scene.packing().shape.policy().rattler_threshold;
    let mut escapes = String::new();
    if escape {
        let s = saddle::escape_saddles(
            &mut scene,
            &mut fire,
            jam_params,
            &SaddleParams::default(),
            |scene| summarize(scene, threshold).rattler,
        )?;
        out.phi = s.phi;
        out.work += s.work;
        escapes = s.rounds.to_string();
    }
    let wall = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu;
    if let Some(f) = trace {
        for (phi, m) in fire.take_trace() {
            writeln!(
                f,
                "{seed},{phi:.15},{},{},{:?},{:e},{:e},{},{},{}",
                m.steps,
                m.newton_iterations,
                m.reason,
                m.energy / n as f64,
                m.force_sq,
                m.lbfgs_evaluations,
                m.plateau_escapes,
                m.dt_cuts
            )?;
        }
        f.flush()?;
    }
    let s = summarize(&mut scene, threshold);
    let w = out.work;
    Ok(format!(
        "{family},{D},{n},{seed},{:.6},{:.4},{},{},{wall:.2},{:.2},{:016x},{},{cpu:.2},{},{escapes},{},{}",
        out.phi,
        s.z_j,
        s.iso_margin,
        w.fire_steps,
        // Per energy-and-gradient evaluation: FIRE's steps and L-BFGS's.
        wall * 1e6 / (w.fire_steps + w.lbfgs_evaluations).max(1) as f64,
        packing_hash(scene.packing()),
        w.newton_iterations,
        w.lbfgs_evaluations,
        w.plateau_escapes,
        w.dt_cuts
    ))
}

/// CPU time of this thread so far (user + system), in seconds; NaN where
/// it cannot be read.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/stat")
        .map(|s| cpu_seconds_of(&s))
        .unwrap_or(f64::NAN)
}

/// User + system time of a `/proc/…/stat` line (fields 14 and 15, in clock
/// ticks of 1/100 s); NaN where they are not there.
fn cpu_seconds_of(stat: &str) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        options: Options,
    }

    fn options(args: &[&str]) -> Options {
        let argv = std::iter::once("packing").chain(args.iter().copied());
        Cli::try_parse_from(argv).unwrap().options
    }

    #[test]
    fn the_paper_minimiser_is_the_papers_fire_and_bisection() {
        let o = options(&["--minimizer", "paper"]);
        assert_eq!(o.fire_params().unwrap(), FireParams::paper());
        assert_eq!(o.jam_params().search, JamSearch::Bisection);
        // Asked for explicitly, the family's masses replace the paper's.
        let o = options(&["--minimizer", "paper", "--masses", "family"]);
        assert_eq!(o.fire_params().unwrap().masses, Masses::Family);
    }

    #[test]
    fn the_default_minimiser_is_that_of_experiment_files() {
        let o = options(&[]);
        let fire = o.fire_params().unwrap();
        assert_eq!(fire.newton, FireParams::fire_newton().newton);
        assert!(fire.newton.is_some());
        assert_eq!(fire.masses, Masses::Family);
        assert_eq!(fire.lbfgs, LbfgsChoice::Family);
        assert_eq!(o.jam_params().search, JamSearch::default());
        assert_eq!(o.seeds, vec![1]);
        assert_eq!(
            (o.particles, o.dim, o.family),
            (1024, 2, BenchFamily::Sphere)
        );
    }

    #[test]
    fn lbfgs_and_block_flags_reach_the_parameters() {
        let o = options(&[
            "--lbfgs-after",
            "0",
            "--lbfgs-memory",
            "4",
            "--lbfgs-blocks",
            "--masses",
            "blocks-jammed",
            "--precon-floor",
            "0.5",
            "--no-newton",
            "--force-criterion",
            "max",
        ]);
        let fire = o.fire_params().unwrap();
        let LbfgsChoice::On(l) = &fire.lbfgs else {
            panic!("{:?}", fire.lbfgs)
        };
        assert_eq!((l.after, l.memory, l.blocks), (0, 4, true));
        assert_eq!(l.max_step, LbfgsParams::default().max_step);
        let Masses::Blocks(p) = &fire.masses else {
            panic!("{:?}", fire.masses)
        };
        assert!(p.jammed_only && p.floor == 0.5);
        assert_eq!(fire.newton, None);
        assert_eq!(fire.force_criterion, ForceCriterion::Max);
        assert_eq!(
            options(&["--no-lbfgs"]).fire_params().unwrap().lbfgs,
            LbfgsChoice::Off
        );
    }

    #[test]
    fn inconsistent_flags_are_refused() {
        // L-BFGS's settings without L-BFGS, and both on and off.
        let argv = ["packing", "--lbfgs-memory", "4"];
        assert!(Cli::try_parse_from(argv).is_err());
        let argv = ["packing", "--lbfgs-after", "1", "--no-lbfgs"];
        assert!(Cli::try_parse_from(argv).is_err());
        // A time step the minimiser cannot take: an error, not a panic.
        let o = options(&["--dt-max=-1"]);
        let err = o.fire_params().unwrap_err().to_string();
        assert!(err.contains("minimizer"), "{err}");
    }

    #[test]
    fn a_dimension_without_bodies_is_an_error_after_the_header() {
        let mut lines = Vec::new();
        let err = run(&options(&["--dim", "4"]), &mut |l| {
            lines.push(l.to_string())
        })
        .unwrap_err()
        .to_string();
        assert!(err.contains("--dim 4: must be 2 or 3"), "{err}");
        assert_eq!(lines, vec![HEADER.to_string()]);
        let o = options(&["--dim", "3", "--family", "fourier"]);
        assert!(run(&o, &mut |_| {}).is_err());
    }

    #[test]
    fn the_hash_sees_every_bit_of_the_state() {
        let scene = random_scene::<2, _>(Sphere, 16, 3, 0.5, 0.4).unwrap();
        let p = scene.packing().clone();
        let h = packing_hash(&p);
        assert_eq!(
            h,
            packing_hash(
                random_scene::<2, _>(Sphere, 16, 3, 0.5, 0.4)
                    .unwrap()
                    .packing()
            )
        );
        let mut q = p.clone();
        q.positions[7][1] = f64::from_bits(q.positions[7][1].to_bits() ^ 1);
        assert_ne!(packing_hash(&q), h);
        assert_ne!(
            packing_hash(
                random_scene::<2, _>(Sphere, 16, 4, 0.5, 0.4)
                    .unwrap()
                    .packing()
            ),
            h
        );
    }

    #[test]
    fn cpu_time_is_user_plus_system_ticks() {
        // The command name may hold spaces and parentheses.
        let stat = "42 (a (b) c) S 1 1 1 0 -1 4194560 100 0 0 0 250 50 0 0 20 0 1 0";
        assert_eq!(cpu_seconds_of(stat), 3.0);
        assert!(cpu_seconds_of("42 (x) S 1").is_nan());
        assert!(cpu_seconds_of("no parenthesis").is_nan());
    }
}
