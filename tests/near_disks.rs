//! The `fourier` and `fourier_sum` families in the engine: the conformance
//! kit's checks for n = 2…5 and a three-mode sum, the derivatives across
//! the branch cut of atan2, Δ = 0 as disks, and the lane kernel against the
//! generic pass on awkward list lengths and both potentials.

use jamkit_core::{Packing, Potential, SizeDistribution, Vector};
use jamkit_engine::{Objective, Scene, check::gradient_error};
use jamkit_experiment::Experiment;
use jamkit_fourier::{FourierParams, NearDisk};
use rand::SeedableRng;

use crate::common;
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

/// The kit's forces and torques (finite differences), `h_ij = h_ji` and
/// rotation invariance for every mode number and a sum of modes with
/// phases (tolerances and their reasons in `crates/kit`).
#[test]
fn near_disks_pass_the_kit_checks() {
    let mut shapes: Vec<NearDisk> = (2..=5).map(|n| fourier(n, 0.2)).collect();
    shapes.push(fourier(2, 0.3));
    shapes.push(multi_mode());
    for shape in shapes {
        jamkit_kit::check_gradient::<2, _>(&shape);
        jamkit_kit::check_symmetry::<2, _>(&shape);
        assert!(jamkit_kit::check_rotation::<2, _>(&shape));
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

/// Δ = 0 is the sphere family: the same packings for the same seeds.
#[test]
fn delta_zero_reproduces_the_sphere_packing() {
    let run_with = |family_and_params: &str| {
        let text = format!(
            r#"(name: "z", family: {family_and_params}, particles: 32, samples: 2, seed: 4)"#
        );
        let dir = tempfile::tempdir().unwrap();
        let e = Experiment::from_ron(&text, "inline").unwrap();
        common::run_ok(&e, dir.path(), 1).packings
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

/// With the exact gap, the scene's warm lanes
/// (`FastContacts::contacts_warm_lanes`) give the generic pass's energy
/// and gradient bit for bit along a path of moves and jumps
/// (`common::assert_lanes_match_the_generic_pass`): n = 2 (Δ = 0.1, 0.3),
/// n = 3 and a sum of modes with phases.
#[test]
fn warm_lanes_match_the_generic_pass_bit_for_bit() {
    let exact = |n: u32, delta: f64| {
        NearDisk::fourier(&FourierParams {
            n,
            delta,
            inertia: None,
            gap: jamkit_planar::gap2d::GapModel::Exact,
        })
        .unwrap()
    };
    let sum = NearDisk::fourier_sum(&jamkit_fourier::FourierSumParams {
        modes: vec![
            jamkit_fourier::Mode {
                n: 2,
                a: 0.4,
                b: 0.3,
            },
            jamkit_fourier::Mode {
                n: 3,
                a: 0.2,
                b: -1.0,
            },
        ],
        delta: 0.15,
        inertia: None,
        gap: jamkit_planar::gap2d::GapModel::Exact,
    })
    .unwrap();
    for shape in [exact(2, 0.1), exact(2, 0.3), exact(3, 0.2), sum] {
        let what = format!("{shape:?}");
        common::assert_lanes_match_the_generic_pass(shape, &what);
    }
}
