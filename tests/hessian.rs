//! The analytic Hessian against central differences of the analytic
//! gradient, for every family that provides second derivatives, on dense
//! random configurations (many overlaps, so that the stress part `T` is
//! exercised as much as the stiffness part `K`).

use jamkit_core::{Packing, Potential, Shape, SizeDistribution};
use jamkit_engine::Scene;
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_lobed::{Lobed, LobedParams};
use jamkit_nmer::{Nmer, NmerParams, SphereSpec};
use jamkit_sphere::Sphere;
use rand::SeedableRng;

mod common;

fn dense<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64) -> Scene<D, S> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    // Bodies made of spheres start overlap-free (`overlap_free_start`), so
    // every family starts dilute and is compressed affinely.
    let mut packing = Packing::<D, S>::random(shape, sizes, 0.1, &mut rng).unwrap();
    packing.set_phi(0.9);
    Scene::new(packing, Potential::Harmonic, 0.2)
}

/// Largest entry-wise difference between the analytic and the
/// finite-difference Hessian, relative to the largest entry.
///
/// Tolerance 1e-6: with ε = 1e-6 the truncation error is ~ε² V'''' ~ 1e-12
/// and the round-off ~1e-16 |∇V| / ε ~ 1e-10 relative to entries of order 1,
/// so 1e-6 leaves four orders of margin yet catches any wrong term, sign or
/// factor (all O(1) or O(Δ) ≥ 1e-2 here). A pair whose gap crosses 0 within
/// ε would break the check (v'' jumps there): with random overlaps that has
/// probability ~1e-6 per pair.
fn check<const D: usize, S: Shape<D>>(shape: S, n: usize, seeds: std::ops::RangeInclusive<u64>) {
    for seed in seeds {
        let mut scene = dense::<D, S>(shape.clone(), n, seed);
        let (err, scale) = common::hessian_fd_error(&mut scene);
        assert!(scale > 0.5, "configuration should overlap");
        assert!(
            err < 1e-6 * scale,
            "{shape:?} D={D} seed {seed}: error {err:e} vs scale {scale:e}"
        );
    }
}

#[test]
fn sphere_hessian_matches_finite_differences_2d_and_3d() {
    check::<2, _>(Sphere, 30, 1..=2);
    check::<3, _>(Sphere, 30, 1..=2);
}

#[test]
fn near_disk_hessian_matches_finite_differences() {
    for n in 2..=5 {
        let shape = NearDisk::fourier(&FourierParams {
            n,
            delta: 0.2,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        check::<2, _>(shape, 24, 1..=2);
    }
    let sum = common::multi_mode();
    check::<2, _>(sum, 24, 1..=2);
}

/// The tutorial's family gets its Hessian from the shared first-order
/// formula and its own `G''`: sharp lobes (κ = 4) make `G''` large, which is
/// where a wrong curvature term would show.
#[test]
fn lobed_hessian_matches_finite_differences() {
    for kappa in [0.5, 4.0] {
        let shape = Lobed::new(&LobedParams {
            delta: 0.15,
            kappa,
            inertia: None,
        })
        .unwrap();
        check::<2, _>(shape, 24, 1..=2);
    }
}

/// Rigid bodies made of spheres: dimers in 2D and 3D (two rotational
/// coordinates in 3D, about axes perpendicular to the body) and a bent
/// trimer in 3D (three), where the rotational blocks see the
/// non-commuting quaternion increments. Several sphere pairs of two bodies
/// overlap at once in these dense configurations.
#[test]
fn nmer_hessian_matches_finite_differences_2d_and_3d() {
    let dimer = |alpha: f64| NmerParams {
        alpha: Some(alpha),
        spheres: None,
        inertia: None,
    };
    for alpha in [1.5, 2.0] {
        check::<2, _>(Nmer::<2>::new(&dimer(alpha)).unwrap(), 16, 1..=2);
        check::<3, _>(Nmer::<3>::new(&dimer(alpha)).unwrap(), 16, 1..=2);
    }
    let trimer = NmerParams {
        alpha: None,
        spheres: Some(
            [
                ([0.0, 0.0, 0.0], 1.0),
                ([1.2, 0.3, 0.0], 0.7),
                ([-0.4, 1.1, 0.2], 0.8),
            ]
            .iter()
            .map(|(o, r)| SphereSpec {
                offset: o.to_vec(),
                radius: *r,
            })
            .collect(),
        ),
        inertia: None,
    };
    check::<3, _>(Nmer::<3>::new(&trimer).unwrap(), 16, 1..=2);
}
