//! Packings of non-convex near-disks (the exact gap beyond the convex
//! limit) against their outlines as fine polygons: every pair the model
//! calls overlapping overlaps as polygons, and the reverse, as deep.

use jamkit_core::{Packing, Pair, Potential, Shape};
use jamkit_engine::{Fire, FireParams, Objective, Scene};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_planar::gap2d::GapModel;
use rand::SeedableRng;

#[path = "../shapes/fourier/tests/support/polygon.rs"]
mod polygon;
use polygon::Polygon;

/// `particles` near-disks (n, Δ) with the exact gap from a random start
/// at `phi` (deep overlaps), relaxed by `steps` FIRE steps (jamming to
/// the default window does not finish in a test's time:
/// `docs/explanation/non-convex-gap.md#status`), compared pair by pair
/// with polygons of 8192 vertices (edges ~8e-4 R⁰; a chord leaves the
/// outline by ≲ 1e-6 R⁰ at the sharpest tip, the nearest vertex to the
/// deepest point is within ~1e-5 R⁰ of its depth). Pairs whose inscribed
/// disks are in contact (the core, not an outline's contact) are counted
/// and left out. On the others a pair overlaps as polygons by more than
/// 2e-5 exactly when the model has a contact with h < −2e-5, and the
/// deepest vertex inside the other polygon is as deep as the model's
/// deepest contact, to 2e-5. Returns the pairs compared in contact, those
/// with several contacts, and those left to the core.
fn check(n: u32, delta: f64, phi: f64, particles: usize, steps: u64) -> (usize, usize, usize) {
    let s = NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap: GapModel::Exact,
    })
    .unwrap();
    assert!(!s.is_convex());
    let sizes: Vec<f64> = (0..particles)
        .map(|k| if k % 2 == 0 { 0.5 } else { 0.7 })
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let skin = 0.4 * s.bounding_radius(0.5);
    let packing = Packing::random(s.clone(), sizes, phi, &mut rng).unwrap();
    let mut scene = Scene::new(packing, Potential::Harmonic, skin);
    let mut fire = Fire::new(
        FireParams {
            max_steps: steps,
            energy_tol: 1e-30,
            force_tol: 1e-30,
            ..FireParams::default()
        }
        .for_family(&s),
    );
    // Capped: the state reached is the one compared.
    let _ = fire.minimize(&mut scene);
    let p = scene.packing();
    let (mut touching, mut several, mut cores) = (0, 0, 0);
    for i in 0..particles {
        for j in i + 1..particles {
            let d = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
            let (si, sj) = (p.sizes[i], p.sizes[j]);
            if d.norm() > s.bounding_radius(si) + s.bounding_radius(sj) {
                continue;
            }
            let pair = Pair::new(si, p.orientations[i], sj, p.orientations[j], d);
            if s.profiled().core_contact(&pair).is_some() {
                cores += 1;
                continue;
            }
            // The depth of each contact's common normal (a contact that
            // meets a saddle reports its prominence as its gap).
            let mut gaps = Vec::new();
            s.profiled()
                .arc_contacts(&pair, 0.0, None, &mut |c| gaps.push(c.exact.gap));
            let model = gaps.iter().fold(0.0f64, |m, g| m.max(-g));
            let theta = |k: usize| p.orientations[k].theta();
            let pi = Polygon::new(&s, si, theta(i), [0.0, 0.0], 8192);
            let pj = Polygon::new(&s, sj, theta(j), [d[0], d[1]], 8192);
            let depth = pi.depth_of(&pj).max(pj.depth_of(&pi));
            if depth.max(model) < 2e-5 {
                continue;
            }
            assert!(
                (depth - model).abs() < 2e-5,
                "n = {n}, bodies {i} and {j}: polygons overlap by {depth}, the model by {model} ({gaps:?})"
            );
            touching += 1;
            several += usize::from(gaps.iter().filter(|g| **g < 0.0).count() > 1);
        }
    }
    let mut g = vec![0.0; Objective::dof(&scene)];
    let e = scene.energy_gradient(&mut g) / particles as f64;
    eprintln!(
        "n = {n}, Δ = {delta}: φ = {:.4}, V/N = {e:.3e}, {touching} pairs in contact, {several} with several contacts, {cores} left to the core",
        scene.phi()
    );
    (touching, several, cores)
}

/// n = 8, Δ = 0.2 and n = 16, Δ = 0.1 (Δ(n + 1/n) = 1.6, beyond the
/// convex limit 1) at φ = 0.86 and 0.83, N = 12, 2000 FIRE steps: at least 5 pairs in contact
/// compared, all of them as the polygons say.
#[test]
fn relaxed_non_convex_packings_agree_with_fine_polygons() {
    for &(n, delta, phi) in &[(8u32, 0.2, 0.86), (16, 0.1, 0.83)] {
        let (touching, _, _) = check(n, delta, phi, 12, 2000);
        assert!(touching >= 5, "n = {n}: {touching} pairs in contact");
    }
}
