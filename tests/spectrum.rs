//! The spectrum of jammed packings: eigenvalues non-negative up to
//! round-off, zero modes where the counting of degrees of freedom puts them.

use jamkit_core::{Packing, Potential, Shape, SizeDistribution};
use jamkit_engine::{Fire, FireParams, JamParams, Scene, jam};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_observe::hessian::{Hessian, HessianOptions};
use jamkit_observe::spectrum::{eigenvalues, frequency};
use jamkit_observe::summarize;
use jamkit_sphere::Sphere;
use rand::SeedableRng;

fn jammed<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64) -> Scene<D, S> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let packing = Packing::<D, S>::random(shape, sizes, 0.1, &mut rng).unwrap();
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.2);
    jam(
        &mut scene,
        &mut Fire::new(FireParams::default()),
        &JamParams::default(),
    )
    .unwrap();
    scene
}

fn zero_modes(l: &[f64]) -> usize {
    l.iter().filter(|&&x| frequency(x) <= 1e-5).count()
}

/// Largest |λ| below zero relative to λ_max: the dense solver is backward
/// stable, so round-off gives |λ| ≲ n ε λ_max ~ 1e-13 for n ~ 200; a
/// negative eigenvalue of a minimised packing beyond 1e-12 λ_max would mean
/// a saddle or a wrong Hessian.
fn assert_non_negative(l: &[f64], what: &str) {
    let max = l.last().copied().unwrap_or(0.0);
    assert!(
        l[0] > -1e-12 * max,
        "{what}: λ_min = {:e}, λ_max = {max:e}",
        l[0]
    );
}

/// Jammed binary disks, N = 64: the full Hessian (K + T) is positive
/// semi-definite; with rattlers removed its only zero modes are the D global
/// translations (the non-rattler network is rigid); with rattlers kept (and
/// decoupled, see `hessian`), each adds D more. The threshold ω ≤ 1e-5 of the
/// paper separates round-off (|λ| ~ 1e-15, ω ~ 3e-8) from the softest true
/// modes of these packings (λ ≳ 1e-4).
#[test]
fn disk_zero_modes_are_translations_and_rattlers() {
    for seed in 1..=4 {
        let mut scene = jammed::<2, _>(Sphere, 64, seed);
        let s = summarize(&mut scene, 3);
        for remove_rattlers in [false, true] {
            let options = HessianOptions {
                stiffness_only: false,
                remove_rattlers,
            };
            let h = Hessian::of_scene(&mut scene, &s.rattler, options).unwrap();
            let l = eigenvalues(&h).unwrap();
            assert_non_negative(&l, &format!("seed {seed}"));
            let expected = 2 + if remove_rattlers { 0 } else { 2 * s.n_rattlers };
            assert_eq!(zero_modes(&l), expected, "seed {seed} {options:?}");
        }
    }
}

/// The same for 3D spheres (N = 64): D = 3 translations, 3 per rattler.
#[test]
fn sphere_zero_modes_are_translations_and_rattlers_3d() {
    for seed in 1..=2 {
        let mut scene = jammed::<3, _>(Sphere, 64, seed);
        let s = summarize(&mut scene, 4);
        let h = Hessian::of_scene(&mut scene, &s.rattler, HessianOptions::default()).unwrap();
        let l = eigenvalues(&h).unwrap();
        assert_non_negative(&l, &format!("3D seed {seed}"));
        assert_eq!(zero_modes(&l), 3 + 3 * s.n_rattlers, "3D seed {seed}");
    }
}

/// Near-disks jam hypostatic: the stiffness matrix K = JᵀJ of the N_c × N_f
/// contact Jacobian has N_f − rank J zero modes, and rank J = N_c − 1 when
/// the contact forces carry exactly one state of self-stress (the
/// pressure). So the zero modes, the quartic ones included, number
/// N_f − N_c + 1 among the non-rattlers: not merely close to N_f − N_c,
/// this is the exact count.
#[test]
fn near_disk_zero_modes_count_the_missing_contacts() {
    for (delta, seed) in [(0.01, 1), (0.1, 1), (0.1, 2)] {
        let shape = NearDisk::fourier(&FourierParams {
            n: 2,
            delta,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        let mut scene = jammed::<2, _>(shape, 64, seed);
        let s = summarize(&mut scene, 3);
        let options = HessianOptions {
            stiffness_only: true,
            remove_rattlers: true,
        };
        let h = Hessian::of_scene(&mut scene, &s.rattler, options).unwrap();
        let l = eigenvalues(&h).unwrap();
        assert_non_negative(&l, &format!("Δ = {delta}"));
        let n_f = 3 * (64 - s.n_rattlers);
        assert!(n_f > s.n_contacts, "near-disks should jam hypostatic");
        assert_eq!(
            zero_modes(&l),
            n_f - s.n_contacts + 1,
            "Δ = {delta}, seed {seed}: N_f = {n_f}, N_c = {}",
            s.n_contacts
        );
    }
}
