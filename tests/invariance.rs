//! Symmetries of the energy: translation, periodic wrapping, no overlap.

use jamkit_core::{Packing, Potential, SizeDistribution, Vector};
use jamkit_engine::{Objective, Scene};
use jamkit_sphere::Sphere;
use rand::{RngExt, SeedableRng};

fn random_packing<const D: usize>(phi: f64, seed: u64) -> Packing<D, Sphere> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(200, &mut rng);
    Packing::<D, Sphere>::random(Sphere, sizes, phi, &mut rng).unwrap()
}

fn energy<const D: usize>(p: Packing<D, Sphere>) -> f64 {
    let mut scene = Scene::new(p, Potential::Harmonic, 0.2);
    let mut g = vec![0.0; scene.dof()];
    scene.energy_gradient(&mut g)
}

/// Shifting every centre by the same vector, or by whole box edges one body
/// at a time, changes only round-off: relative 1e-12 allows for the
/// re-rounding of ~10³ overlaps of size ~0.1 (each exact to ~1e-16).
fn check_translation_and_wrapping<const D: usize>() {
    let p = random_packing::<D>(0.8, 3);
    let e0 = energy(p.clone());
    assert!(e0 > 0.0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let shift = Vector::<D>::from_fn(|_, _| 10.0 * rng.random::<f64>() - 5.0);
    let mut moved = p.clone();
    for r in &mut moved.positions {
        *r += shift;
    }
    let e1 = energy(moved);
    let mut wrapped = p.clone();
    let edges = *p.bbox.edges();
    for (i, r) in wrapped.positions.iter_mut().enumerate() {
        let k = (i % 5) as f64 - 2.0;
        *r += edges * k;
    }
    let e2 = energy(wrapped);
    assert!((e1 - e0).abs() < 1e-12 * e0, "translation: {e0} vs {e1}");
    assert!((e2 - e0).abs() < 1e-12 * e0, "wrapping: {e0} vs {e2}");
}

#[test]
fn energy_is_invariant_under_translation_and_wrapping_2d() {
    check_translation_and_wrapping::<2>();
}

#[test]
fn energy_is_invariant_under_translation_and_wrapping_3d() {
    check_translation_and_wrapping::<3>();
}

/// On a simple lattice with spacing 1.5 > 2 R_max = 1.4 nothing touches:
/// energy and every gradient component are exactly zero.
fn check_no_overlap<const D: usize>() {
    let side = 6usize;
    let n = side.pow(D as u32);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let mut p = Packing::<D, Sphere>::random(Sphere, sizes, 0.1, &mut rng).unwrap();
    p.bbox = jamkit_core::PeriodicBox::cubic(1.5 * side as f64);
    for (i, r) in p.positions.iter_mut().enumerate() {
        let mut rest = i;
        for a in 0..D {
            r[a] = 1.5 * (rest % side) as f64;
            rest /= side;
        }
    }
    let mut scene = Scene::new(p, Potential::Harmonic, 0.2);
    let mut g = vec![1.0; scene.dof()];
    assert_eq!(scene.energy_gradient(&mut g), 0.0);
    assert!(g.iter().all(|&x| x == 0.0));
}

#[test]
fn no_overlap_means_zero_energy_2d() {
    check_no_overlap::<2>();
}

#[test]
fn no_overlap_means_zero_energy_3d() {
    check_no_overlap::<3>();
}
