//! `jamkit bench`: timings of the engine, for docs/performance.md.
//!
//! * `packing`: one binary-disk packing with the paper's protocol, one thread;
//! * `eval`: time per energy-and-gradient evaluation against N;
//! * `spectrum`: Hessian assembly and eigensolvers (`bench_spectrum.rs`).

use anyhow::Result;
use clap::Subcommand;
use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Fire, FireParams, JamParams, Objective, Scene, jam};
use jamkit_observe::summarize;
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::time::Instant;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Time whole jammed packings (paper's protocol, binary disks, one thread).
    Packing {
        /// Number of disks.
        #[arg(long, default_value_t = 1024)]
        particles: usize,
        /// Seeds to run (one packing each).
        #[arg(long, value_delimiter = ',', default_value = "1")]
        seeds: Vec<u64>,
        /// Dimension (2 or 3).
        #[arg(long, default_value_t = 2)]
        dim: usize,
    },
    /// Time one energy+gradient evaluation of binary disks at phi = 0.84.
    Eval {
        /// Particle numbers.
        #[arg(long, value_delimiter = ',', default_value = "256,1024,4096,16384")]
        particles: Vec<usize>,
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
        BenchCommand::Spectrum {
            particles,
            nalgebra,
        } => crate::bench_spectrum::run(&particles, nalgebra),
        BenchCommand::Packing {
            particles,
            seeds,
            dim,
        } => {
            out!("dim,particles,seed,phi_j,z_j,iso_margin,fire_steps,wall_s,us_per_step");
            for seed in seeds {
                match dim {
                    2 => bench_packing::<2>(particles, seed)?,
                    3 => bench_packing::<3>(particles, seed)?,
                    _ => anyhow::bail!("--dim {dim}: must be 2 or 3"),
                }
            }
            Ok(())
        }
        BenchCommand::Eval { particles } => {
            out!("particles,pairs,us_per_eval,ns_per_particle");
            for n in particles {
                let mut scene = random_scene::<2>(n, 1, 0.84)?;
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

fn random_scene<const D: usize>(n: usize, seed: u64, phi: f64) -> Result<Scene<D, Sphere>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let packing = Packing::<D, Sphere>::random(Sphere, sizes, phi, &mut rng)?;
    Ok(Scene::new(packing, Potential::Harmonic, 0.4 * 0.5))
}

fn bench_packing<const D: usize>(n: usize, seed: u64) -> Result<()> {
    let mut scene = random_scene::<D>(n, seed, 0.1)?;
    let mut fire = Fire::new(FireParams::default());
    let t = Instant::now();
    let out = jam(&mut scene, &mut fire, &JamParams::default())?;
    let wall = t.elapsed().as_secs_f64();
    let s = summarize(&mut scene, D + 1);
    out!(
        "{D},{n},{seed},{:.6},{:.4},{},{},{wall:.2},{:.2}",
        out.phi,
        s.z_j,
        s.iso_margin,
        out.fire_steps,
        wall * 1e6 / out.fire_steps as f64
    );
    Ok(())
}
