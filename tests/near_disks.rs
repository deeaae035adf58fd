//! The `fourier` and `fourier_sum` families in the engine: finite-difference
//! forces and torques, rotation invariance, and Δ = 0 as disks.

use jamkit_core::{Packing, Potential, SizeDistribution, Vector};
use jamkit_engine::{Objective, Scene, check::gradient_error};
use jamkit_experiment::Experiment;
use jamkit_experiment::runner::{RunOptions, run};
use jamkit_fourier::{FourierParams, NearDisk};
use rand::SeedableRng;

mod common;
use common::multi_mode;

fn fourier(n: u32, delta: f64) -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap()
}

fn dense(shape: NearDisk, seed: u64) -> Scene<2, NearDisk> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(40, &mut rng);
    let packing = Packing::<2, NearDisk>::random(shape, sizes, 0.9, &mut rng).unwrap();
    Scene::new(packing, Potential::Harmonic, 0.2)
}

/// Forces and torques against central differences (ε = 1e-6; truncation
/// ~ε²·|V'''| ~ 1e-12 and round-off ~1e-16·V/ε ~ 1e-9 relative to gradients
/// of order 1: a relative bound of 1e-6 catches any wrong term).
#[test]
fn forces_and_torques_match_finite_differences() {
    let mut shapes: Vec<NearDisk> = (2..=5).map(|n| fourier(n, 0.2)).collect();
    shapes.push(multi_mode());
    for shape in shapes {
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

/// Two bodies placed so that θ_ij is within 1e-9 of ±π (the branch cut of
/// atan2): the gradient is still right on both sides of the cut.
#[test]
fn derivatives_are_smooth_across_theta_ij_equal_pi() {
    for shape in [fourier(3, 0.2), multi_mode()] {
        for dy in [1e-9, -1e-9, 0.0] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
            let mut p =
                Packing::<2, NearDisk>::random(shape.clone(), vec![0.5, 0.7], 0.05, &mut rng)
                    .unwrap();
            let c = *p.bbox.edges() * 0.5;
            p.positions[0] = c;
            p.positions[1] = c + Vector::<2>::new(-1.1, dy); // j to the left of i: θ_ij ≈ π
            let scene = Scene::new(p, Potential::Harmonic, 0.2);
            let (err, scale) = gradient_error(&scene, 1e-7);
            assert!(scale > 1e-3, "the pair must overlap");
            assert!(err < 1e-6 * scale, "dy = {dy}: {err:e} vs {scale:e}");
        }
    }
}

/// Rotating the whole configuration (centres about the box centre, and
/// every θ_i) by any angle leaves V unchanged. Periodic images break the
/// symmetry, so the test uses a cluster well inside a large box.
#[test]
fn energy_is_invariant_under_global_rotation() {
    for shape in [fourier(2, 0.3), fourier(5, 0.1), multi_mode()] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let sizes = SizeDistribution::default().sample(30, &mut rng);
        let mut p = Packing::<2, NearDisk>::random(shape.clone(), sizes, 0.02, &mut rng).unwrap();
        let centre = *p.bbox.edges() * 0.5;
        for (k, r) in p.positions.iter_mut().enumerate() {
            // A compact, overlapping cluster of radius ~3 around the centre.
            let a = k as f64 * 2.399;
            *r = centre + Vector::<2>::new(a.cos(), a.sin()) * (0.55 * (k as f64).sqrt());
        }
        let energy = |p: Packing<2, NearDisk>| {
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
                *o = jamkit_fourier::Angle::new(o.theta() + alpha);
            }
            let e1 = energy(q);
            assert!((e1 - e0).abs() < 1e-12 * e0, "alpha {alpha}: {e0} vs {e1}");
        }
    }
}

/// Δ = 0 is the sphere family: the same packings for the same seeds.
#[test]
fn delta_zero_reproduces_the_sphere_packing() {
    let run_with = |family_and_params: &str| {
        let text = format!(
            r#"(name: "z", family: {family_and_params}, particles: 32, samples: 2, seed: 4)"#
        );
        let dir = tempfile::tempdir().unwrap();
        let e = Experiment::from_ron(&text, "inline").unwrap();
        run(
            &e,
            &RunOptions {
                out: dir.path().to_path_buf(),
                jobs: Some(1),
                progress: false,
            },
        )
        .unwrap()
        .packings
    };
    let disks = run_with(r#""sphere""#);
    let near = run_with(r#""fourier", params: {"n": 3, "delta": 0.0}"#);
    assert_eq!(disks.len(), 2);
    for (a, b) in disks.iter().zip(&near) {
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.phi.to_bits(), b.phi.to_bits());
    }
}

/// The engine's lane pass for near-disks (`Shape::contacts_lanes`, chosen
/// by `Shape::LANE_CONTACTS`; AVX2 where the CPU has it) gives the energy
/// and gradient of the generic pass through `Shape::contacts` bit for bit:
/// n = 2..5, sums of modes (with and without phases), both potentials, and
/// lists whose length is no multiple of the chunk.
#[test]
fn lane_pass_matches_the_generic_pass_bit_for_bit() {
    let mut shapes: Vec<NearDisk> = (2..=5).map(|n| fourier(n, 0.2)).collect();
    shapes.push(multi_mode());
    shapes.push(
        NearDisk::fourier_sum(&jamkit_fourier::FourierSumParams {
            modes: vec![
                jamkit_fourier::Mode {
                    n: 2,
                    a: 0.3,
                    b: 0.0,
                },
                jamkit_fourier::Mode {
                    n: 4,
                    a: 0.1,
                    b: 0.0,
                },
            ],
            delta: 0.15,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap(),
    );
    let bits = |g: &[f64]| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for shape in shapes {
        for (n, phi, seed) in [(301, 0.86, 1), (97, 0.6, 2), (40, 0.9, 3)] {
            for potential in [Potential::Harmonic, Potential::Hertzian] {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let sizes = SizeDistribution::default().sample(n, &mut rng);
                let packing =
                    Packing::<2, NearDisk>::random(shape.clone(), sizes, phi, &mut rng).unwrap();
                let mut scene = Scene::new(packing, potential, 0.2);
                let (mut fast, mut generic) = (vec![0.0; scene.dof()], vec![0.0; scene.dof()]);
                let e_fast = scene.energy_gradient(&mut fast);
                let e_generic = scene.energy_gradient_generic(&mut generic);
                assert!(e_fast > 0.0);
                let what = format!("{shape:?}, N = {n}, {potential:?}");
                assert_eq!(e_fast.to_bits(), e_generic.to_bits(), "{what}");
                assert_eq!(bits(&fast), bits(&generic), "{what}");
            }
        }
    }
}
