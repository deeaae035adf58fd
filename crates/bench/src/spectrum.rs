//! `jamkit bench spectrum`: Hessian assembly and dense eigensolvers for
//! near-disks (n = 2, Δ = 0.1) at N = 256 … 1024, one thread.
//!
//! The configuration is random at φ = 0.88 (overlapping, not relaxed): the
//! cost of a dense eigensolver depends on the matrix size, not on where the
//! bodies sit, and the stress part T is then exercised too.

use crate::output::Print;
use anyhow::Result;
use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::Scene;
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_observe::hessian::{Hessian, HessianOptions};
use jamkit_observe::spectrum::{eigenmodes, eigenvalues};
use rand::SeedableRng;
use std::time::Instant;

/// What `jamkit bench spectrum` was asked for.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Particle numbers (3 coordinates each).
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024")]
    pub particles: Vec<usize>,
    /// Also time nalgebra's symmetric eigensolver (slow at N = 1024).
    #[arg(long)]
    pub nalgebra: bool,
}

/// Time each stage, a header and one line per particle number; with
/// `nalgebra`, nalgebra's own symmetric eigensolver too.
pub fn run(o: &Options, print: Print) -> Result<()> {
    print(
        "particles,coordinates,assembly_s,faer_values_s,faer_vectors_s,nalgebra_values_s,max_rel_diff",
    );
    for &n in &o.particles {
        let shape = NearDisk::fourier(&FourierParams {
            n: 2,
            delta: 0.1,
            inertia: None,
            gap: Default::default(),
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let sizes = SizeDistribution::default().sample(n, &mut rng);
        let packing = Packing::<2, NearDisk>::random(shape, sizes, 0.88, &mut rng)?;
        let mut scene = Scene::new(packing, Potential::Harmonic, 0.2);

        let t = Instant::now();
        let h = Hessian::of_scene(&mut scene, &[], HessianOptions::default())?;
        let assembly = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let values = eigenvalues(&h)?;
        let faer_values = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (with_vectors, _) = eigenmodes(&h)?;
        let faer_vectors = t.elapsed().as_secs_f64();
        let scale = values.last().copied().unwrap_or(1.0).abs();
        let mut diff = values
            .iter()
            .zip(&with_vectors)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let nalgebra_values = if o.nalgebra {
            let dense = h.dense();
            let m = nalgebra::DMatrix::from_fn(h.size, h.size, |i, j| dense[(i, j)]);
            let t = Instant::now();
            let mut l: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
            let s = t.elapsed().as_secs_f64();
            l.sort_by(f64::total_cmp);
            diff = values
                .iter()
                .zip(&l)
                .fold(diff, |m, (a, b)| m.max((a - b).abs()));
            format!("{s:.3}")
        } else {
            String::new()
        };
        print(&format!(
            "{n},{},{assembly:.4},{faer_values:.3},{faer_vectors:.3},{nalgebra_values},{:.1e}",
            h.size,
            diff / scale
        ));
    }
    Ok(())
}
