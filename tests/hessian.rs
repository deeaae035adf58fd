//! The analytic Hessian against central differences of the analytic
//! gradient, for every family that provides second derivatives, on dense
//! random configurations (many overlaps, so that the stress part `T` is
//! exercised as much as the stiffness part `K`).

use jamkit_core::Shape;
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_lobed::{LobedParams, lobed};
use jamkit_nmer::{Nmer, NmerParams, SphereSpec};
use jamkit_sphere::Sphere;

use crate::common;

/// The kit's Hessian check (`jamkit_kit::check_hessian_at`: 1e-6 of the
/// largest entry, with the reason in `crates/kit`) on `n` bodies for each
/// seed.
fn check<const D: usize, S: Shape<D>>(shape: S, n: usize, seeds: std::ops::RangeInclusive<u64>) {
    for seed in seeds {
        assert!(
            jamkit_kit::check_hessian_at::<D, S>(&shape, n, seed),
            "{shape:?} gives no second derivatives"
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
        let shape = lobed(&LobedParams {
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
