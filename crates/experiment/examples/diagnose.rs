//! Why did a minimisation stall? Load a packing file (typically the
//! `packings/<id>.failed.json` a capped minimisation leaves) and print:
//!
//! * `V/N` and `Σ (∂V/∂q)²`, the contacts nearest to `h = 0`, and the
//!   bodies that carry most of the residual force;
//! * `ω_max²`, the largest eigenvalue of `M^{-1/2} H M^{-1/2}`, against
//!   the `dt_max` the file was made with: FIRE's Euler step is stable
//!   below `2/ω_max` and crawls well before it;
//! * how the residual gradient spreads over the Hessian's eigenvalues
//!   (negative: a saddle; tiny: soft modes; large: a stiff mode that FIRE
//!   does not damp), and the modes that carry most of it;
//! * optionally, FIRE continued from there in rounds of 10⁴ steps with a
//!   chosen `dt_max`.
//!
//! ```sh
//! cargo run --release --example diagnose -- out/x/packings/ID.failed.json [STEPS [DT_MAX]]
//! ```
//!
//! Dense eigendecomposition: fine up to a few thousand coordinates.

use jamkit_core::Shape;
use jamkit_engine::{Fire, FireParams, Objective, Scene};
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_format::PackingFile;
use jamkit_observe::hessian::{Hessian, HessianOptions};
use jamkit_observe::spectrum::omega_max_sq;

struct Diagnose {
    /// `dt_max` the file was made with.
    recorded_dt_max: Option<f64>,
    /// FIRE steps to continue with, and the `dt_max` to use.
    resume: Option<(u64, f64)>,
}

impl PackingVisitor for Diagnose {
    type Output = ();
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) {
        let n = scene.packing().len();
        let stride = D + scene.packing().shape.rot_dof();
        let mut g = vec![0.0; n * stride];
        let energy = scene.energy_gradient(&mut g);
        let force_sq: f64 = g.iter().map(|x| x * x).sum();
        println!(
            "N = {n}, D = {D}, {stride} coordinates per body, φ = {:.12}, V/N = {:.3e}, Σ(∂V/∂q)² = {force_sq:.3e}",
            scene.phi(),
            energy / n as f64
        );

        let mut near = Vec::new();
        let mut contacts = 0;
        scene.for_each_contact(1e-6, |i, j, _, c| {
            contacts += usize::from(c.gap < 0.0);
            if c.gap.abs() < 1e-6 {
                near.push((c.gap, i, j));
            }
        });
        near.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        println!(
            "{contacts} contacts; {} with |h| < 1e-6, nearest:",
            near.len()
        );
        for (gap, i, j) in near.iter().take(6) {
            println!("  h = {gap:+.3e} between bodies {i} and {j}");
        }
        println!("smallest open gaps (a contact about to close):");
        for (gap, i, j) in near.iter().filter(|x| x.0 >= 0.0).take(3) {
            println!("  h = {gap:+.3e} between bodies {i} and {j}");
        }
        let mut per_body: Vec<(f64, usize)> = g
            .chunks(stride)
            .map(|c| c.iter().map(|x| x * x).sum::<f64>())
            .zip(0..)
            .collect();
        per_body.sort_by(|a, b| b.0.total_cmp(&a.0));
        println!("bodies carrying the residual:");
        for (w, b) in per_body.iter().take(4) {
            println!(
                "  body {b}: {:.1} %, largest |∂V/∂q| {:.2e}",
                100.0 * w / force_sq,
                g[b * stride..(b + 1) * stride]
                    .iter()
                    .fold(0.0f64, |m, x| m.max(x.abs()))
            );
        }

        let h = Hessian::of_scene(&mut scene, &[], HessianOptions::default()).unwrap();
        let m = h.size;
        let omega_sq = omega_max_sq(&h, scene.inverse_masses()).unwrap();
        let omega_max = omega_sq.max(0.0).sqrt();
        print!(
            "ω_max² = {omega_sq:.3}, stability limit 2/ω_max = {:.4}",
            2.0 / omega_max
        );
        match self.recorded_dt_max {
            Some(dt) => println!("; dt_max = {dt} is {:.2} of it", dt * omega_max / 2.0),
            None => println!(),
        }

        let evd = h.dense().self_adjoint_eigen(faer::Side::Lower).unwrap();
        let (u, s) = (evd.U(), evd.S());
        let modes: Vec<(f64, f64, usize)> = (0..m)
            .map(|a| {
                let c: f64 = (0..m).map(|r| u[(r, a)] * g[r]).sum();
                (c * c, s[a], a)
            })
            .collect();
        println!("residual gradient by Hessian eigenvalue λ:");
        let bands = [f64::NEG_INFINITY, -1e-12, 1e-12, 1e-6, 1e-3, f64::INFINITY];
        for b in bands.windows(2) {
            let (count, share) = modes
                .iter()
                .filter(|x| x.1 >= b[0] && x.1 < b[1])
                .fold((0, 0.0), |(k, sh), x| (k + 1, sh + x.0));
            println!(
                "  λ in [{:e}, {:e}): {count} modes, {:.3e} of Σ(∂V/∂q)²",
                b[0],
                b[1],
                share / force_sq
            );
        }
        let mut by_share = modes.clone();
        by_share.sort_by(|a, b| b.0.total_cmp(&a.0));
        for (c2, lambda, a) in by_share.iter().take(5) {
            let (mut top, mut rot) = ((0.0, 0), 0.0);
            for r in 0..m {
                let x = u[(r, *a)] * u[(r, *a)];
                if x > top.0 {
                    top = (x, r / stride);
                }
                if r % stride >= D {
                    rot += x;
                }
            }
            println!(
                "  mode λ = {lambda:+.3e}: {:.3} of the residual, distance to its minimum {:.2e}, largest on body {} ({:.2}), rotational {rot:.2}",
                c2 / force_sq,
                c2.sqrt() / lambda.abs(),
                top.1,
                top.0
            );
        }

        if let Some((steps, dt_max)) = self.resume {
            let mut fire = Fire::new(FireParams {
                max_steps: 10_000,
                dt_max: Some(dt_max),
                ..FireParams::default()
            });
            for round in 0..steps.div_ceil(10_000) {
                let outcome = fire.minimize(&mut scene);
                let energy = scene.energy_gradient(&mut g);
                let f: f64 = g.iter().map(|x| x * x).sum();
                let state = match &outcome {
                    Ok(o) => format!("converged after {} steps", o.steps),
                    Err(_) => "10⁴ steps".into(),
                };
                println!(
                    "dt_max {dt_max}, round {round}: {state}, V/N = {:.4e}, Σ(∂V/∂q)² = {f:.3e}",
                    energy / n as f64
                );
                if outcome.is_ok() {
                    break;
                }
            }
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: diagnose PACKING.json [STEPS [DT_MAX]]");
        std::process::exit(2);
    };
    let file = PackingFile::load_checked(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let number = |i: usize| args.get(i).map(|s| s.parse::<f64>().expect("a number"));
    let recorded_dt_max = file.settings["minimizer"]["dt_max"].as_f64();
    let resume = number(2).map(|steps| {
        (
            steps as u64,
            number(3)
                .or(recorded_dt_max)
                .unwrap_or(jamkit_engine::fire::DEFAULT_DT_MAX),
        )
    });
    reload(
        &file,
        Diagnose {
            recorded_dt_max,
            resume,
        },
    )
    .unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
}
