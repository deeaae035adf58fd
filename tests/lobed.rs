//! The `lobed` family (the example of `docs/adding-a-shape.md`) in the
//! engine: finite-difference forces and torques, rotation invariance, and
//! its example experiment end to end.

use jamkit_core::{Packing, Potential, SizeDistribution, Vector};
use jamkit_engine::{Objective, Scene, check::gradient_error};
use jamkit_experiment::runner::{RunOptions, run};
use jamkit_experiment::{Experiment, overrides};
use jamkit_lobed::{Angle, Lobed, LobedParams};
use rand::SeedableRng;
use std::path::Path;

fn lobed(delta: f64, kappa: f64) -> Lobed {
    Lobed::new(&LobedParams {
        delta,
        kappa,
        inertia: None,
    })
    .unwrap()
}

/// Blunt, medium and sharp lobes.
fn shapes() -> Vec<Lobed> {
    vec![
        lobed(0.3, 0.3),
        lobed(0.2, 1.0),
        lobed(0.1, 5.0),
        lobed(0.05, 20.0),
    ]
}

/// 40 binary bodies at φ = 0.9: most pairs overlap.
fn dense(shape: Lobed, seed: u64) -> Scene<2, Lobed> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(40, &mut rng);
    let packing = Packing::<2, Lobed>::random(shape, sizes, 0.9, &mut rng).unwrap();
    Scene::new(packing, Potential::Harmonic, 0.2)
}

/// Forces and torques against central differences of the energy in every
/// coordinate (ε = 1e-6). The truncation error is ~ε²|V'''|/6; V''' carries
/// G''' ~ (4κ)^{3/2}·Δ R⁰ ≲ 10² at κ = 20, so ≲ 1e-10. Round-off is
/// ~1e-16·V/ε ≲ 1e-9. The harmonic v'' jumps at h = 0, which costs ~ε/4 only
/// for a pair within ε of touching. All far below a relative bound of 1e-6
/// on gradients of order 0.1–1, which any wrong or missing term exceeds.
#[test]
fn forces_and_torques_match_finite_differences() {
    for shape in shapes() {
        for seed in 1..=2 {
            let scene = dense(shape.clone(), seed);
            let (err, scale) = gradient_error(&scene, 1e-6);
            assert!(scale > 1e-2);
            assert!(
                err < 1e-6 * scale,
                "{shape:?} seed {seed}: {err:e} vs {scale:e}"
            );
        }
    }
}

/// Rotating the whole configuration (centres about the box centre, and
/// every θ_i) by any angle leaves V unchanged. Periodic images break the
/// symmetry, so the test uses a compact cluster well inside a large box.
#[test]
fn energy_is_invariant_under_global_rotation() {
    for shape in shapes() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let sizes = SizeDistribution::default().sample(30, &mut rng);
        let mut p = Packing::<2, Lobed>::random(shape.clone(), sizes, 0.02, &mut rng).unwrap();
        let centre = *p.bbox.edges() * 0.5;
        for (k, r) in p.positions.iter_mut().enumerate() {
            let a = k as f64 * 2.399;
            *r = centre + Vector::<2>::new(a.cos(), a.sin()) * (0.55 * (k as f64).sqrt());
        }
        let energy = |p: Packing<2, Lobed>| {
            let mut s = Scene::new(p, Potential::Harmonic, 0.2);
            let mut g = vec![0.0; s.dof()];
            s.energy_gradient(&mut g)
        };
        let e0 = energy(p.clone());
        assert!(e0 > 1e-3);
        for alpha in [0.3, 1.7, std::f64::consts::PI, -2.9] {
            let (sa, ca) = f64::sin_cos(alpha);
            let mut q = p.clone();
            for (r, o) in q.positions.iter_mut().zip(q.orientations.iter_mut()) {
                let d = *r - centre;
                *r = centre + Vector::<2>::new(ca * d[0] - sa * d[1], sa * d[0] + ca * d[1]);
                *o = Angle::new(o.theta + alpha);
            }
            let e1 = energy(q);
            assert!(
                (e1 - e0).abs() < 1e-12 * e0,
                "{shape:?} alpha {alpha}: {e0} vs {e1}"
            );
        }
    }
}

/// `experiments/examples/lobed.ron`, shrunk to N = 32 and one sample per Δ,
/// jams every packing into the paper's window 1e-16 < V/N < 2e-16.
#[test]
fn example_experiment_jams() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/examples/lobed.ron");
    let e = Experiment::from_file(&file).unwrap();
    let e = overrides::apply(&e, &["particles=32".into(), "samples=1".into()]).unwrap();
    e.validate().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = run(
        &e,
        &RunOptions {
            out: dir.path().to_path_buf(),
            jobs: Some(2),
            progress: false,
        },
    )
    .unwrap();
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    assert_eq!(report.packings.len(), 2, "one packing per Δ");
    for p in &report.packings {
        assert_eq!(p.family, "lobed");
        assert!(
            p.energy_per_particle > 1e-16 && p.energy_per_particle < 2e-16,
            "{}: V/N = {}",
            p.id,
            p.energy_per_particle
        );
        assert!(p.orientations.iter().all(|o| o.len() == 1));
    }
}

/// `--set params.inertia=0.5` (a bare number, no `Some`) reaches the family,
/// and a κ out of range is refused with the field named.
#[test]
fn parameters_can_be_set_from_the_command_line() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/examples/lobed.ron");
    let e = Experiment::from_file(&file).unwrap();
    for set in ["params.inertia=0.5", "params.inertia=Some(0.5)"] {
        let e = overrides::apply(&e, &[set.into()]).unwrap();
        e.validate().unwrap();
        jamkit_experiment::grid::points(&e).unwrap_or_else(|err| panic!("{set}: {err}"));
    }
    let e = overrides::apply(&e, &["params.kappa=0.05".into()]).unwrap();
    let err = jamkit_experiment::grid::points(&e).unwrap_err().to_string();
    assert!(err.contains("params.kappa"), "{err}");
}
