//! Finite-difference checks of the energy gradient for spheres in 2D and 3D,
//! with both potentials, on dense random configurations (many overlaps).

use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Scene, check::gradient_error};
use jamkit_sphere::Sphere;
use rand::SeedableRng;

fn dense_scene<const D: usize>(potential: Potential, seed: u64) -> Scene<D, Sphere> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::Uniform { min: 0.4, max: 0.8 }.sample(40, &mut rng);
    let packing = Packing::<D, Sphere>::random(Sphere, sizes, 0.9, &mut rng).unwrap();
    Scene::new(packing, potential, 0.2)
}

/// Central differences with ε = 1e-6 have truncation error ~ε² V''' ~ 1e-12
/// and round-off ~1e-16 V/ε ~ 1e-9 for V ~ 10; a relative error of 1e-6 of
/// the largest gradient component leaves three orders of margin and still
/// catches any wrong sign, factor or missing term (all O(1)). Random overlaps
/// avoid the kink of v at h = 0 except with probability ~1e-6 per pair.
fn check<const D: usize>() {
    for potential in [Potential::Harmonic, Potential::Hertzian] {
        for seed in 1..=3 {
            let scene = dense_scene::<D>(potential, seed);
            let (err, scale) = gradient_error(&scene, 1e-6);
            assert!(scale > 1e-2, "configuration should overlap");
            assert!(
                err < 1e-6 * scale,
                "D={D} {potential:?} seed {seed}: error {err:e} vs gradient {scale:e}"
            );
        }
    }
}

#[test]
fn sphere_gradient_matches_finite_differences_2d() {
    check::<2>();
}

#[test]
fn sphere_gradient_matches_finite_differences_3d() {
    check::<3>();
}
