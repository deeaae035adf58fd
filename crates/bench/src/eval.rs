//! `jamkit bench eval`: the time of one energy-and-gradient evaluation of
//! binary disks at φ = 0.84, against N.

use crate::output::Print;
use crate::packing::random_scene;
use anyhow::{Result, bail};
use jamkit_engine::Objective;
use jamkit_sphere::Sphere;
use std::time::Instant;

/// What `jamkit bench eval` was asked for.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Particle numbers.
    #[arg(long, value_delimiter = ',', default_value = "256,1024,4096,16384")]
    pub particles: Vec<usize>,
}

/// Print a header and one line per particle number.
pub fn run(o: &Options, print: Print) -> Result<()> {
    print("particles,pairs,us_per_eval,ns_per_particle");
    for &n in &o.particles {
        if n == 0 {
            bail!("--particles 0: must be at least 1");
        }
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
        if !sink.is_finite() {
            bail!("N = {n}: the energy is {sink}");
        }
        print(&format!(
            "{n},{},{us:.3},{:.2}",
            scene.neighbor_pairs(),
            us * 1e3 / n as f64
        ));
    }
    Ok(())
}
