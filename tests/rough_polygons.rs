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
use polygon::{Polygon, support_points};

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
    let s = near_disk(n, delta, GapModel::Exact);
    assert!(!s.is_convex());
    let sizes: Vec<f64> = (0..particles)
        .map(|k| if k % 2 == 0 { 0.5 } else { 0.7 })
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let skin = 0.4 * s.bounding_radius(0.5);
    let packing = Packing::random_overlapping(s.clone(), sizes, phi, &mut rng).unwrap();
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
    compare(&s, &mut scene)
}

/// The pairs of a packing whose bounding circles overlap: `i < j`, the
/// pair, and the two bodies as polygons of 8192 vertices (body `i`'s
/// centre at the origin, body `j`'s at `r_ij`).
fn near_pairs(
    p: &Packing<2, NearDisk>,
) -> Vec<(
    usize,
    usize,
    Pair<2, jamkit_fourier::Angle>,
    Polygon,
    Polygon,
)> {
    let s = &p.shape;
    let mut out = Vec::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
            let (si, sj) = (p.sizes[i], p.sizes[j]);
            if d.norm() > s.bounding_radius(si) + s.bounding_radius(sj) {
                continue;
            }
            let pair = Pair::new(si, p.orientations[i], sj, p.orientations[j], d);
            let theta = |k: usize| p.orientations[k].theta();
            let pi = Polygon::new(s, si, theta(i), [0.0, 0.0], 8192);
            let pj = Polygon::new(s, sj, theta(j), [d[0], d[1]], 8192);
            out.push((i, j, pair, pi, pj));
        }
    }
    out
}

/// The pairs of `scene` against polygons of 8192 vertices ([`check`]):
/// the pairs compared in contact, those with several contacts, and those
/// left to the core.
fn compare(s: &NearDisk, scene: &mut Scene<2, NearDisk>) -> (usize, usize, usize) {
    let n = s.profiled().profile().modes()[0].n;
    let p = scene.packing();
    let particles = p.len();
    let (mut touching, mut several, mut cores) = (0, 0, 0);
    for (i, j, pair, pi, pj) in near_pairs(p) {
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
    let mut g = vec![0.0; Objective::dof(&*scene)];
    let e = scene.energy_gradient(&mut g) / particles as f64;
    eprintln!(
        "n = {n}, Δ = {}: φ = {:.4}, V/N = {e:.3e}, {touching} pairs in contact, {several} with several contacts, {cores} left to the core",
        s.delta(),
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

/// A jammed packing of `tests/inputs/rough/` (a line `box Lx Ly`, then a
/// line `body x y θ R⁰` per body), as jammed by `cargo run --release
/// --example trace_fire -- jam N_MODE DELTA PARTICLES SEED MAX_STEPS
/// SECONDS` (the file's header says which).
fn jammed(n: u32, delta: f64, file: &str) -> Scene<2, NearDisk> {
    let s = near_disk(n, delta, GapModel::Exact);
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/inputs/rough")
            .join(file),
    )
    .unwrap();
    // A packing of the family whose box and bodies the file's replace.
    let mut packing = Packing::random_overlapping(
        s.clone(),
        vec![0.5; 12],
        0.5,
        &mut rand_chacha::ChaCha8Rng::seed_from_u64(1),
    )
    .unwrap();
    let (mut positions, mut orientations, mut sizes) = (Vec::new(), Vec::new(), Vec::new());
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let x = |k: usize| w[k].parse::<f64>().unwrap();
        match w.first() {
            Some(&"box") => {
                packing.bbox =
                    jamkit_core::PeriodicBox::new(jamkit_core::Vector::<2>::new(x(1), x(2)))
            }
            Some(&"body") => {
                positions.push(jamkit_core::Vector::<2>::new(x(1), x(2)));
                orientations.push(jamkit_core::Rotation2::new(x(3)));
                sizes.push(x(4));
            }
            _ => {}
        }
    }
    packing.positions = positions;
    packing.orientations = orientations;
    packing.sizes = sizes;
    let skin = 0.4 * s.bounding_radius(0.5);
    Scene::new(packing, Potential::Harmonic, skin)
}

/// The jammed packings of `tests/inputs/rough/` with their mode number:
/// n = 8, Δ = 0.15 (12 bodies) and n = 16, Δ = 0.1 (32 bodies).
fn jammed_inputs() -> impl Iterator<Item = (u32, Scene<2, NearDisk>)> {
    [
        (8u32, 0.15, "n8_d0.15_N12.txt"),
        (16, 0.1, "n16_d0.1_N32.txt"),
    ]
    .into_iter()
    .map(|(n, delta, file)| (n, jammed(n, delta, file)))
}

/// Jammed packings, n = 8 at Δ = 0.15 (12 bodies) and n = 16 at Δ = 0.1
/// (32 bodies) (Δ(n + 1/n) = 1.22 and 1.6, beyond the convex limit 1): the
/// energy is in the jamming window, 10⁻¹⁶ < V/N < 2·10⁻¹⁶ (a change of the
/// model that moves the packing off it fails here), so the model's
/// overlaps are ~10⁻⁸, below what polygons of 8192 vertices resolve
/// (2·10⁻⁵, [`check`]). Against them: no pair overlaps as polygons by
/// more than 2·10⁻⁵ and none is left to the core, and every contact with
/// h < 2·10⁻⁵ touches them: its support points a distance |h| apart along
/// its normal (to 10⁻⁶: near an inflection point, ρ ~ 4·10³, the
/// refinement of the normal leaves them ~10⁻⁷ apart sideways; the gap
/// errs by k δψ², far less), each on the other body's polygon to 2·10⁻⁵. At least 12
/// contacts are checked for each.
#[test]
fn jammed_non_convex_packings_agree_with_fine_polygons() {
    for (n, mut scene) in jammed_inputs() {
        let mut g = vec![0.0; Objective::dof(&scene)];
        let particles = scene.packing().len();
        let e = scene.energy_gradient(&mut g) / particles as f64;
        assert!(e > 1e-16 && e < 2e-16, "n = {n}: V/N = {e:e}");
        let s = scene.packing().shape.clone();
        let p = scene.packing();
        let mut touching = 0;
        for (i, j, pair, pi, pj) in near_pairs(p) {
            let d = pair.r_ij;
            assert!(
                s.profiled().core_contact(&pair).is_none(),
                "n = {n}: {i}, {j}"
            );
            let depth = pi.depth_of(&pj).max(pj.depth_of(&pi));
            assert!(
                depth < 2e-5,
                "n = {n}, bodies {i} and {j}: polygons overlap by {depth}"
            );
            s.profiled().arc_contacts(&pair, 2e-5, None, &mut |c| {
                let e = c.exact;
                let (a, b) = support_points(&e, [d[0], d[1]]);
                let (cs, sn) = e.normal;
                let off = (b[0] - a[0] - e.gap * cs).hypot(b[1] - a[1] - e.gap * sn);
                assert!(off < 1e-6, "{off:e}: {e:?}");
                assert!(
                    pj.distance(a) < 2e-5 && pi.distance(b) < 2e-5,
                    "n = {n}, bodies {i} and {j}: {e:?}"
                );
                touching += 1;
            });
        }
        eprintln!("n = {n}: {touching} contacts touch the polygons");
        assert!(touching >= 12, "n = {n}: {touching} contacts");
    }
}

/// Counting on the jammed packings of
/// [`jammed_non_convex_packings_agree_with_fine_polygons`]: every contact
/// is a constraint of its own, so a pair touching at k points counts k in
/// `N_c`, `z_J` and the isostatic margin. The observable's network holds
/// exactly the model's contacts (each pair's `h < 0` contacts), and
/// some pairs touch at two points. The contacts are independent but for
/// one state of self-stress, the contact forces: the `N_c × 3N` matrix `J`
/// of their gap gradients (each body's `x, y, θ`) satisfies `Jᵀ h ≈ 0`
/// (force balance: `∂V/∂q = Jᵀ h`, below the force test at a jammed
/// state), so `J Jᵀ` has one eigenvalue near zero, `|Jᵀ ĥ|² ~ 10⁻¹¹` of
/// the largest, with eigenvector `ĥ = h/|h|` (to 10⁻⁶ in the cosine), and
/// every other eigenvalue above 10⁻⁵ of the largest (measured 5.7·10⁻⁴ at
/// n = 8, 6.9·10⁻⁵ at n = 16; the near-zero one 3.5·10⁻¹³ and 1.8·10⁻¹³).
/// A contact counted twice would add a second eigenvalue at round-off,
/// with an eigenvector of mixed signs; a contact missed would leave the
/// forces out of balance.
#[test]
fn the_contacts_of_non_convex_pairs_carry_one_state_of_self_stress() {
    use jamkit_observe::contacts::{ContactNetwork, contact_rows};
    for (n, mut scene) in jammed_inputs() {
        let network = ContactNetwork::of_scene(&mut scene);
        let rows = contact_rows(&mut scene);
        let mut gaps = Vec::new();
        scene.for_each_contact(0.0, |_, _, _, c| {
            if c.gap < 0.0 {
                gaps.push(c.gap);
            }
        });
        let s = scene.packing().shape.clone();
        let p = scene.packing();
        // The model's contacts pair by pair.
        let (mut model, mut several) = (0, 0);
        for (i, j, pair, _, _) in near_pairs(p) {
            let mut k = 0;
            s.profiled().arc_contacts(&pair, 0.0, None, &mut |c| {
                k += usize::from(c.exact.gap < 0.0);
            });
            let counted = network
                .contacts
                .iter()
                .filter(|&&(a, b)| (a as usize, b as usize) == (i, j))
                .count();
            assert_eq!(counted, k, "n = {n}, bodies {i} and {j}");
            model += k;
            several += usize::from(k > 1);
        }
        assert_eq!(network.contacts.len(), model, "n = {n}");
        assert!(several >= 1, "n = {n}: no pair with several contacts");
        // J Jᵀ from the rows (body i's 3 coordinates, then body j's).
        let m = rows.len();
        let mut jjt = faer::Mat::<f64>::zeros(m, m);
        for (a, (&(ia, ja), ra)) in network.contacts.iter().zip(&rows).enumerate() {
            for (b, (&(ib, jb), rb)) in network.contacts.iter().zip(&rows).enumerate() {
                let mut dot = 0.0;
                for (ba, xa) in [(ia, &ra[0]), (ja, &ra[1])] {
                    for (bb, xb) in [(ib, &rb[0]), (jb, &rb[1])] {
                        if ba == bb {
                            dot += xa.iter().zip(xb.iter()).map(|(u, v)| u * v).sum::<f64>();
                        }
                    }
                }
                jjt[(a, b)] = dot;
            }
        }
        let evd = jjt.self_adjoint_eigen(faer::Side::Lower).unwrap();
        let (low, next, high) = (evd.S()[0], evd.S()[1], evd.S()[m - 1]);
        let norm = gaps.iter().map(|h| h * h).sum::<f64>().sqrt();
        let cos: f64 = (0..m).map(|a| evd.U()[(a, 0)] * gaps[a] / norm).sum();
        eprintln!(
            "n = {n}: {m} contacts, {several} pairs with several; J Jᵀ: {low:.3e}, {next:.3e} … {high:.3e}; cosine with the forces {cos}"
        );
        assert!(low < 1e-9 * high, "n = {n}: {low:e} against {high:e}");
        assert!(next > 1e-5 * high, "n = {n}: {next:e} against {high:e}");
        assert!(cos.abs() > 1.0 - 1e-6, "n = {n}: {cos}");
    }
}

/// Near-disks `(n, Δ)` of the paper's inertia with the gap model `gap`.
fn near_disk(n: u32, delta: f64, gap: GapModel) -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap,
    })
    .unwrap()
}

/// Near-disks of n = 4, Δ = 0.3 (non-convex).
fn lobed(gap: GapModel) -> NearDisk {
    near_disk(4, 0.3, gap)
}

/// Why a non-convex exact start is placed free of overlaps: two bodies
/// (R⁰ = 0.7, n = 4, Δ = 0.3) dropped 0.15 apart, nearly aligned, lobes in
/// lobes (a pair of a random start at φ = 0.1), sit on a jump of the
/// energy: at overlaps deeper than two lobes the arcs' contacts come and
/// go with their energy (docs/explanation/non-convex-gap.md, "What it does
/// not guarantee"). A step of 10⁻⁷ along −∇V lowers V by about 1 where the
/// gradient predicts 6·10⁻⁸, and FIRE, pushed back onto the jump from
/// both sides, leaves V where it was after 20 000 steps.
#[test]
fn a_lobed_pair_dropped_onto_itself_is_held_on_a_jump_of_the_energy() {
    let s = lobed(GapModel::Exact);
    let mut packing = Packing::random_overlapping(
        s.clone(),
        vec![0.7, 0.7],
        0.05,
        &mut rand_chacha::ChaCha8Rng::seed_from_u64(1),
    )
    .unwrap();
    let c = packing.bbox.edges()[0] / 2.0;
    packing.positions = vec![
        jamkit_core::Vector::<2>::new(c, c),
        jamkit_core::Vector::<2>::new(c + 0.15233512761867196, c - 0.001921833206900203),
    ];
    packing.orientations = vec![
        jamkit_core::Rotation2::new(-0.42990798571621824),
        jamkit_core::Rotation2::new(-0.4343467024509405),
    ];
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.4 * s.bounding_radius(0.5));
    let mut g = vec![0.0; 6];
    let start = scene.energy_gradient(&mut g);
    let eps = 1e-7;
    let dq: Vec<f64> = g.iter().map(|x| -eps * x).collect();
    scene.displace(&dq);
    let stepped = scene.energy();
    scene.displace(&dq.iter().map(|x| -x).collect::<Vec<_>>());
    let predicted = eps * g.iter().map(|x| x * x).sum::<f64>();
    let mut fire = Fire::new(
        FireParams {
            max_steps: 20_000,
            ..FireParams::default()
        }
        .for_family(&s),
    );
    let outcome = fire.minimize(&mut scene);
    let end = scene.energy();
    eprintln!(
        "V = {start:.4}; after a step of {eps:e} along -grad V: {stepped:.4} (predicted fall {predicted:.1e}); after FIRE {end:.4} ({})",
        if outcome.is_ok() {
            "converged"
        } else {
            "not converged"
        }
    );
    assert!(start - stepped > 0.1, "no jump: {start} → {stepped}");
    assert!(predicted < 1e-6);
    assert!(end > 0.5 * start, "V = {end:e}: the deep pair came apart");
}

/// The random start of a non-convex exact outline has no overlapping
/// pair (every contact's h ≥ 0, 64 bodies at φ = 0.1, five seeds), while
/// the paper's first-order gap on the same outline keeps the plain random
/// start (the same draws as `random_overlapping`), which overlaps.
#[test]
fn a_non_convex_exact_start_is_free_of_overlaps() {
    let sizes: Vec<f64> = (0..64)
        .map(|k| if k % 2 == 0 { 0.5 } else { 0.7 })
        .collect();
    // The deepest contact of a start, over the scene's listed pairs.
    let deepest = |p: Packing<2, NearDisk>| {
        let skin = 0.4 * p.shape.bounding_radius(0.5);
        let mut deepest = 0.0f64;
        Scene::new(p, Potential::Harmonic, skin)
            .for_each_contact(0.0, |_, _, _, c| deepest = deepest.min(c.gap));
        deepest
    };
    let mut overlapping = 0;
    for seed in 1..=5 {
        let rng = || rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let exact =
            Packing::random(lobed(GapModel::Exact), sizes.clone(), 0.1, &mut rng()).unwrap();
        assert_eq!(deepest(exact), 0.0, "seed {seed}");
        let first = lobed(GapModel::FirstOrder);
        let paper = Packing::random(first.clone(), sizes.clone(), 0.1, &mut rng()).unwrap();
        let plain = Packing::random_overlapping(first, sizes.clone(), 0.1, &mut rng()).unwrap();
        assert_eq!(paper.positions, plain.positions, "seed {seed}");
        overlapping += usize::from(deepest(paper) < 0.0);
    }
    assert!(overlapping >= 3, "{overlapping} of 5 plain starts overlap");
}
