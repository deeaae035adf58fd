//! # The conformance kit: one check that a family meets the `Shape` contract
//!
//! Every family is tested the same way, in every dimension it claims, by
//! one generic call, [`check_family`]. What it checks, each with the
//! tolerance and the reason for it beside the check:
//!
//! * **forces and torques** against central differences of the energy in
//!   every generalised coordinate, rotations included (through the
//!   family's own `rotate`), on a dense overlapping configuration;
//! * **second derivatives**, where the family gives them
//!   (`Shape::gap_hessians`): the Hessian against central differences of
//!   the analytic gradient;
//! * **`h_ij = h_ji`**: the gaps of a pair seen from either body agree;
//! * **translation invariance**: shifting every centre by one vector leaves
//!   the energy unchanged;
//! * **rotation invariance**: turning a compact cluster (centres about its
//!   middle, in the plane of the first two axes, and every body's
//!   orientation by the same angle) leaves the energy unchanged, where the
//!   family's rotational coordinates allow turning a body about that axis
//!   (none, one angle in 2D, three world-frame angles in 3D);
//! * **smooth in the orientation**: the gap's slope, swept over a full
//!   turn of one body on two grids, has no jump (a profile with a corner
//!   fails, with its angle named);
//! * **lanes = generic pass bit for bit**, for families with lane kernels
//!   (`FastContacts::LANES`) and contact slots (`FastContacts::contact_slots`);
//! * **a small jamming run**: 16 bodies or more (as many as the box
//!   needs to hold twice the interaction range) compressed from φ = 0.1 to the
//!   paper's window `10⁻¹⁶ < V/N < 2·10⁻¹⁶`;
//! * and, through the registry, **bad parameters** refused with the field
//!   named ([`check_bad_params`]).
//!
//! A new family's test file is one call per dimension, plus what is
//! special to it (its gap against a formula written out, its area against
//! quadrature).

pub mod warm;

use jamkit_core::{
    BodyOrientation, Contact, Kernel, Packing, Potential, Shape, SizeDistribution, Vector,
};
use jamkit_core::{Pair, ShapeExt};
use jamkit_engine::check::gradient_error;
use jamkit_engine::hessian::{Hessian, HessianOptions, finite_difference};
use jamkit_engine::{Fire, FireParams, JamParams, Objective, Scene, jam};
use jamkit_registry as registry;
use rand::SeedableRng;

/// What [`check_family`] checked: the names of the checks it ran and of
/// those that do not apply to the family (with the reason).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Checked {
    /// The checks that ran and passed.
    pub ran: Vec<&'static str>,
    /// The checks that do not apply, with why.
    pub skipped: Vec<(&'static str, &'static str)>,
}

/// Bodies of the dense configurations.
const BODIES: usize = 24;

/// A dense configuration: `n` binary bodies placed at φ = 0.1 (overlap-free
/// for families that need it) and compressed affinely to φ = 0.9, so that
/// most pairs overlap.
pub fn dense<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64) -> Scene<D, S> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let mut packing = Packing::<D, S>::random(shape, sizes, 0.1, &mut rng).unwrap();
    packing.set_phi(0.9);
    Scene::new(packing, Potential::Harmonic, 0.2)
}

/// `fourier in D = 2 (NearDisk { … })`, for messages.
fn describe<const D: usize, S: Shape<D>>(shape: &S) -> String {
    format!("{} in D = {D} ({shape:?})", shape.family())
}

fn energy<const D: usize, S: Shape<D>>(p: Packing<D, S>) -> f64 {
    let mut s = Scene::new(p, Potential::Harmonic, 0.2);
    let mut g = vec![0.0; s.dof()];
    s.energy_gradient(&mut g)
}

/// Run every check of the kit on `shape` in dimension `D`; panics with the
/// family, the check and the numbers on the first failure.
pub fn check_family<const D: usize, S: Shape<D>>(shape: S) -> Checked {
    let mut done = Checked::default();
    check_gradient(&shape);
    done.ran.push("gradient");
    if check_hessian(&shape) {
        done.ran.push("hessian");
    } else {
        done.skipped
            .push(("hessian", "the family gives no second derivatives"));
    }
    check_symmetry(&shape);
    done.ran.push("symmetry");
    check_translation(&shape);
    done.ran.push("translation");
    if check_rotation(&shape) {
        done.ran.push("rotation");
    } else {
        done.skipped.push((
            "rotation",
            "its rotational coordinates cannot turn a body about a fixed world axis",
        ));
    }
    if check_smooth(&shape) {
        done.ran.push("smooth");
    } else {
        done.skipped
            .push(("smooth", "the bodies have no rotational coordinate"));
    }
    if matches!(shape.kernel(), Kernel::Lanes | Kernel::Slots(_)) {
        check_lanes(&shape);
        done.ran.push("lanes");
    } else {
        done.skipped.push(("lanes", "no lane kernel"));
    }
    check_jams(&shape);
    done.ran.push("jamming");
    done
}

/// Forces and torques against central differences (ε = 1e-6) on two dense
/// configurations. The truncation error is ~ε²|V'''|/6 ≲ 1e-10 for the
/// smooth gaps of the families (V''' ≲ 10² for the sharpest profile), the
/// round-off ~1e-16·V/ε ≲ 1e-9, and the harmonic v'' jumps at h = 0 only
/// for a pair within ε of touching: all far below 1e-6 of gradients of
/// order 0.1–1, which any wrong or missing term exceeds.
pub fn check_gradient<const D: usize, S: Shape<D>>(shape: &S) {
    let name = &describe(shape);
    for seed in 1..=2 {
        let scene = dense(shape.clone(), BODIES, seed);
        let (err, scale) = gradient_error(&scene, 1e-6);
        assert!(scale > 1e-2, "{name}: seed {seed} barely overlaps");
        assert!(
            err < 1e-6 * scale,
            "{name}: gradient, seed {seed}: error {err:e} vs scale {scale:e}"
        );
    }
}

/// The Hessian against central differences of the analytic gradient
/// (ε = 1e-6): truncation ~ε²V'''' ~ 1e-12, round-off ~1e-16|∇V|/ε ~ 1e-10
/// relative to entries of order 1, so 1e-6 leaves four orders of margin
/// yet catches any wrong term, sign or factor. False when the family gives
/// no second derivatives.
pub fn check_hessian<const D: usize, S: Shape<D>>(shape: &S) -> bool {
    check_hessian_at(shape, 16, 3)
}

/// [`check_hessian`] on the dense configuration of `n` bodies made from
/// `seed` ([`dense`]).
pub fn check_hessian_at<const D: usize, S: Shape<D>>(shape: &S, n: usize, seed: u64) -> bool {
    let name = &describe(shape);
    let o = S::Orientation::reference();
    let apart = Vector::<D>::from_fn(|a, _| if a == 0 { 4.0 } else { 0.0 });
    if shape
        .gap_hessians(&Pair::new(1.0, o, 1.0, o, apart), f64::INFINITY, |_| {})
        .is_err()
    {
        return false;
    }
    let mut scene = dense(shape.clone(), n, seed);
    let h = Hessian::of_scene(&mut scene, &[], HessianOptions::default())
        .unwrap_or_else(|e| panic!("{name}: Hessian: {e}"))
        .dense();
    let fd = finite_difference(&scene, 1e-6);
    let scale = fd.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut err = 0.0f64;
    for (a, row) in fd.iter().enumerate() {
        for (b, x) in row.iter().enumerate() {
            err = err.max((h[(a, b)] - x).abs());
        }
    }
    assert!(
        scale > 0.5,
        "{name}: the Hessian configuration should overlap"
    );
    assert!(
        err < 1e-6 * scale,
        "{name}: Hessian: error {err:e} vs scale {scale:e}"
    );
    true
}

/// `h_ij = h_ji`: every pair of a dense configuration has the same gaps,
/// sorted, seen from `i` (`r_ij`) and from `j` (`−r_ij`), to 1e-12 of the
/// sizes. The two evaluations differ only by the order of floating-point
/// operations, so any larger difference is a wrong sign or a swapped body.
pub fn check_symmetry<const D: usize, S: Shape<D>>(shape: &S) {
    let name = &describe(shape);
    let scene = dense(shape.clone(), BODIES, 4);
    let p = scene.packing();
    let mut pairs = 0;
    for i in 0..p.positions.len() {
        for j in i + 1..p.positions.len() {
            let r = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
            let reach = shape.bounding_radius(p.sizes[i]) + shape.bounding_radius(p.sizes[j]);
            if r.norm() > reach {
                continue;
            }
            let gaps = |a: usize, b: usize, r: Vector<D>| {
                let mut g: Vec<f64> = shape
                    .pair_contacts(
                        &Pair::new(
                            p.sizes[a],
                            p.orientations[a],
                            p.sizes[b],
                            p.orientations[b],
                            r,
                        ),
                        f64::INFINITY,
                    )
                    .iter()
                    .map(|c| c.gap)
                    .collect();
                g.sort_by(f64::total_cmp);
                g
            };
            let (ij, ji) = (gaps(i, j, r), gaps(j, i, -r));
            assert_eq!(ij.len(), ji.len(), "{name}: pair ({i}, {j}): contacts");
            for (a, b) in ij.iter().zip(&ji) {
                assert!(
                    (a - b).abs() < 1e-12,
                    "{name}: h_ij = {a} but h_ji = {b} for pair ({i}, {j})"
                );
            }
            pairs += 1;
        }
    }
    assert!(pairs > 10, "{name}: only {pairs} pairs in reach");
}

/// Shifting every centre by one vector (and wrapping into the box) leaves
/// `V` unchanged to 1e-12 relative: only the last bits of the separations
/// change with the wrapping.
pub fn check_translation<const D: usize, S: Shape<D>>(shape: &S) {
    let name = &describe(shape);
    let scene = dense(shape.clone(), BODIES, 5);
    let p = scene.packing().clone();
    let e0 = energy(p.clone());
    let shift = Vector::<D>::from_fn(|a, _| 0.37 + 0.21 * a as f64);
    let mut q = p;
    for r in q.positions.iter_mut() {
        *r = q.bbox.wrap(*r + shift);
    }
    let e1 = energy(q);
    assert!(e0 > 1e-3, "{name}: the configuration should overlap");
    assert!(
        (e1 - e0).abs() < 1e-12 * e0,
        "{name}: translation changes V from {e0} to {e1}"
    );
}

/// Turning a compact cluster well inside a large box by an angle `α` in
/// the plane of the first two axes leaves `V` unchanged to 1e-12
/// relative. Periodic images would break the symmetry, hence the cluster.
/// This catches a gap that depends on the orientations other than through
/// angles relative to the pair's axis (a sign slip such as `θ_i + θ_ij`
/// gives smooth, self-consistent derivatives that finite differences
/// cannot catch). False where the family's coordinates cannot turn a body
/// about a fixed world axis (linear bodies in 3D turn about body axes).
pub fn check_rotation<const D: usize, S: Shape<D>>(shape: &S) -> bool {
    let name = &describe(shape);
    let turn: fn(f64) -> Option<Vec<f64>> = match (D, shape.rot_dof()) {
        (_, 0) => |_| Some(Vec::new()),
        (2, 1) => |a| Some(vec![a]),
        (3, 3) => |a| Some(vec![0.0, 0.0, a]),
        _ => return false,
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let sizes = SizeDistribution::default().sample(30, &mut rng);
    let mut p = Packing::<D, S>::random(shape.clone(), sizes, 0.01, &mut rng).unwrap();
    let centre = *p.bbox.edges() * 0.5;
    // Points of a ball about the centre, a golden-angle spiral in the first
    // two axes and a slow drift along the others: neighbours overlap.
    for (k, r) in p.positions.iter_mut().enumerate() {
        let a = k as f64 * 2.399;
        let rho = 0.55 * (k as f64).sqrt();
        *r = centre
            + Vector::<D>::from_fn(|d, _| match d {
                0 => rho * a.cos(),
                1 => rho * a.sin(),
                _ => 0.3 * ((k * (d + 1)) as f64).sin(),
            });
    }
    let e0 = energy(p.clone());
    assert!(e0 > 1e-3, "{name}: the cluster should overlap");
    for alpha in [0.3, 1.7, std::f64::consts::PI, -2.9] {
        let (sa, ca) = f64::sin_cos(alpha);
        let mut q = p.clone();
        let dq = turn(alpha).unwrap();
        for (r, o) in q.positions.iter_mut().zip(q.orientations.iter_mut()) {
            let d = *r - centre;
            let mut t = d;
            t[0] = ca * d[0] - sa * d[1];
            t[1] = sa * d[0] + ca * d[1];
            *r = centre + t;
            if !dq.is_empty() {
                shape.rotate(o, &dq);
            }
        }
        let e1 = energy(q);
        assert!(
            (e1 - e0).abs() < 1e-12 * e0,
            "{name}: turning by {alpha} changes V from {e0} to {e1}"
        );
    }
    true
}

/// Turns of the sweep in [`check_smooth`]: its coarse grid; the fine one
/// has twice as many.
const SWEEP: usize = 4096;

/// The deepest overlap [`check_smooth`] compares, relative to `R_i + R_j`.
const SHALLOW: f64 = 0.02;

/// The gap is smooth as body `i` turns a full turn about its first
/// rotational coordinate, at two separations (the bodies' reaches apart,
/// and 0.9 of it) and two directions: a profile with a corner (a jump in
/// its slope, such as `cos 2θ |cos θ|` at θ = ±π/2) or a step fails here
/// with its angle named, though forces against finite differences pass
/// everywhere but within the difference step of the corner.
///
/// The sum of the pair's gaps `H(θ)` and its slope `S = Σ ∂h/∂q_i[0]` are
/// taken on grids of [`SWEEP`] and `2·SWEEP` steps. For a C² gap the
/// largest change of `S` between neighbours, `max |ΔS| ≈ δθ max|H''|`,
/// halves with the step; across a corner it stays the jump `J` of the
/// slope. A corner is declared where the fine grid keeps more than 3/4 of
/// the coarse grid's `max |ΔS|` (a smooth profile keeps 1/2, to
/// `O(δθ²)`). And `ΔH` must agree with the trapezoid of the slopes,
/// `½(S_k + S_{k+1}) δθ`, to within `δθ max |ΔS|` (the rule's error is
/// `δθ³ max|H'''|/12` for a smooth gap): a jump of `H` itself fails that.
/// Below `10⁻¹⁰ (R_i + R_j)` changes are round-off (a disk's slope is 0).
///
/// Only steps where every gap is above `−SHALLOW (R_i + R_j)` at both ends
/// are compared: an exact gap of overlapping bodies is a penetration depth,
/// the least of several smooth branches, which has kinks of its own where
/// two branches tie in a deep overlap (far from any jammed packing's).
/// False (nothing checked) for bodies without rotational coordinates.
pub fn check_smooth<const D: usize, S: Shape<D>>(shape: &S) -> bool {
    if shape.rot_dof() == 0 {
        return false;
    }
    let name = &describe(shape);
    let (size_i, size_j) = (0.5, 0.7);
    let reach = shape.bounding_radius(size_i) + shape.bounding_radius(size_j);
    let floor = 1e-10 * (size_i + size_j);
    // The pair's summed gap and slope along a sweep of `k` steps, each
    // with its class: the contact count, or a class of its own for a deep
    // overlap.
    let sweep = |r_ij: Vector<D>, k: usize| {
        let step = std::f64::consts::TAU / k as f64;
        let mut dq = [0.0; 3];
        dq[0] = step;
        let dq = &dq[..shape.rot_dof()];
        let mut o = S::Orientation::reference();
        let o_j = S::Orientation::reference();
        let mut points = Vec::with_capacity(k + 1);
        for at in 0..=k {
            let found =
                shape.pair_contacts(&Pair::new(size_i, o, size_j, o_j, r_ij), f64::INFINITY);
            let h: f64 = found.iter().map(|c| c.gap).sum();
            let slope: f64 = found.iter().map(|c| c.grad_rot_i[0]).sum();
            let shallow = found.iter().all(|c| c.gap > -SHALLOW * (size_i + size_j));
            // Steps whose two ends have a different contact count, or a
            // deep overlap, are not compared (`usize::MAX` never matches).
            let class = if shallow {
                found.len()
            } else {
                usize::MAX - at
            };
            points.push((class, h, slope));
            shape.rotate(&mut o, dq);
        }
        (step, points)
    };
    let worst_jump = |points: &[(usize, f64, f64)]| {
        points
            .windows(2)
            .enumerate()
            .filter(|(_, w)| w[0].0 == w[1].0)
            .map(|(k, w)| ((w[1].2 - w[0].2).abs(), k))
            .fold((0.0_f64, 0), |a, b| if b.0 > a.0 { b } else { a })
    };
    let mut compared = 0;
    for fraction in [1.0, 0.9] {
        for direction in [0.0, 0.7] {
            let r_ij = Vector::<D>::from_fn(|a, _| match a {
                0 => fraction * reach * f64::cos(direction),
                1 => fraction * reach * f64::sin(direction),
                _ => 0.0,
            });
            let (coarse_step, coarse) = sweep(r_ij, SWEEP);
            let (fine_step, fine) = sweep(r_ij, 2 * SWEEP);
            let (jump_coarse, at_coarse) = worst_jump(&coarse);
            let (jump_fine, _) = worst_jump(&fine);
            assert!(
                jump_fine <= floor || jump_fine < 0.75 * jump_coarse,
                "{name}: the gap's slope jumps by {jump_coarse:.3e} near a turn of {:.4} rad of body i \
                 (|r_ij| = {:.3}, and by {jump_fine:.3e} at half the step): the outline has a corner \
                 or its slope is not continuous; the gap, the forces and the Newton finish need a \
                 profile with continuous first and second derivatives",
                at_coarse as f64 * coarse_step,
                r_ij.norm(),
            );
            for (k, w) in fine.windows(2).enumerate() {
                if w[0].0 != w[1].0 {
                    continue;
                }
                compared += 1;
                let rule = 0.5 * (w[0].2 + w[1].2) * fine_step;
                let miss = (w[1].1 - w[0].1 - rule).abs();
                assert!(
                    miss <= floor + fine_step * jump_fine,
                    "{name}: the gap changes by {:.3e} over {fine_step:.2e} rad near a turn of {:.4} rad \
                     of body i (|r_ij| = {:.3}) where its slope says {rule:.3e}: the gap jumps \
                     there, or its rotational derivative is wrong",
                    w[1].1 - w[0].1,
                    k as f64 * fine_step,
                    r_ij.norm(),
                );
            }
        }
    }
    assert!(
        compared >= SWEEP,
        "{name}: only {compared} steps of the sweeps had shallow contacts to compare"
    );
    true
}

/// The lane kernel (or the slots kernel) gives the generic pass's energy and gradient bit for
/// bit (the same operations in the same order, several pairs at a time).
pub fn check_lanes<const D: usize, S: Shape<D>>(shape: &S) {
    let name = &describe(shape);
    for seed in 1..=2 {
        let mut a = dense(shape.clone(), BODIES, seed);
        let mut b = a.clone();
        let mut ga = vec![0.0; a.dof()];
        let mut gb = vec![0.0; b.dof()];
        let ea = a.energy_gradient(&mut ga);
        let eb = b.energy_gradient_generic(&mut gb);
        assert_eq!(
            ea.to_bits(),
            eb.to_bits(),
            "{name}: lanes energy, seed {seed}"
        );
        for (k, (x, y)) in ga.iter().zip(&gb).enumerate() {
            assert_eq!(
                x.to_bits(),
                y.to_bits(),
                "{name}: lanes gradient [{k}], seed {seed}: {x} vs {y}"
            );
        }
    }
}

/// 16 bodies or more (see above) compressed from φ = 0.1 by the paper's
/// protocol end in its
/// window `10⁻¹⁶ < V/N < 2·10⁻¹⁶` (the family's FIRE defaults).
pub fn check_jams<const D: usize, S: Shape<D>>(shape: &S) {
    let name = &describe(shape);
    // The fewest bodies (from 16) whose box at φ = 0.95 still holds twice
    // the interaction range: a body must not meet its own image.
    let reach = shape.bounding_radius(1.0);
    let mut n = 16;
    let sizes = loop {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let sizes = SizeDistribution::default().sample(n, &mut rng);
        let volume: f64 = sizes.iter().map(|&s| shape.volume(s)).sum();
        let largest = sizes.iter().fold(0.0f64, |m, &s| m.max(s));
        let edge = (volume / 0.95).powf(1.0 / D as f64);
        if edge > 2.5 * 2.0 * reach * largest || n >= 512 {
            break sizes;
        }
        n *= 2;
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let packing = Packing::<D, S>::random(shape.clone(), sizes, 0.1, &mut rng).unwrap();
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.2);
    let mut fire = Fire::new(FireParams::default().for_family(shape));
    let out = jam(&mut scene, &mut fire, &JamParams::default())
        .unwrap_or_else(|e| panic!("{name}: jamming run: {e}"));
    assert!(
        out.energy_per_particle > 1e-16 && out.energy_per_particle < 2e-16,
        "{name}: jammed at V/N = {}",
        out.energy_per_particle
    );
}

/// Each `(params, field)`: the family's parameters in RON (as in an
/// experiment file, defaults filled in) are refused by the registry with an
/// error that names `field`; and the family's [`jamkit_core::Family::EXAMPLE`]
/// is accepted in `dim`.
pub fn check_bad_params(family: &str, dim: usize, cases: &[(&str, &str)]) {
    struct Build;
    impl registry::SceneVisitor for Build {
        type Output = ();
        fn visit<const D: usize, S: Shape<D>>(self, _shape: S) {}
    }
    let info = registry::family_info(family).unwrap();
    let k = registry::FAMILIES
        .iter()
        .position(|f| f.name == family)
        .unwrap();
    let parse = |text: &str| {
        let params =
            registry::params_from_ron(text).unwrap_or_else(|e| panic!("{family}: {text}: {e}"));
        registry::with_defaults(&info, &params)
    };
    registry::dispatch(family, dim, &parse(registry::EXAMPLES[k]), Build)
        .unwrap_or_else(|e| panic!("{family}: its example is refused: {e}"));
    for (text, field) in cases {
        let e = registry::dispatch(family, dim, &parse(text), Build)
            .err()
            .unwrap_or_else(|| panic!("{family}: {text} is accepted"))
            .to_string();
        assert!(
            e.contains(field),
            "{family}: {text}: {e} does not name {field}"
        );
    }
}

/// [`check_family`] on the shape the registry builds for `family` in
/// dimension `dim` from `params` (RON, defaults filled in): the path a
/// packing of the family takes, degenerate cases included.
pub fn check_registered(family: &str, dim: usize, params: &str) -> Checked {
    struct Kit;
    impl registry::SceneVisitor for Kit {
        type Output = Checked;
        fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Checked {
            check_family::<D, S>(shape)
        }
    }
    let info = registry::family_info(family).unwrap();
    let params =
        registry::params_from_ron(params).unwrap_or_else(|e| panic!("{family}: {params}: {e}"));
    let params = registry::with_defaults(&info, &params);
    registry::dispatch(family, dim, &params, Kit)
        .unwrap_or_else(|e| panic!("{family} in D = {dim}: {e}"))
}

/// One pair's gap as a function of the pair coordinates
/// `z = (r_j, q_i, q_j)` (`D` translations, then each body's `rot_dof`
/// rotational coordinates, applied through the family's own `rotate`: all
/// increments of a body at once, the convention of the second
/// derivatives), at `r_ij + z[..D]`, sizes `sizes`. Panics unless the pair
/// has exactly one contact.
pub fn pair_gap_at<const D: usize, S: Shape<D>>(
    shape: &S,
    sizes: (f64, f64),
    o_i: &S::Orientation,
    o_j: &S::Orientation,
    r_ij: &Vector<D>,
    z: &[f64],
) -> f64 {
    let m = shape.rot_dof();
    let (mut a, mut b) = (*o_i, *o_j);
    shape.rotate(&mut a, &z[D..D + m]);
    shape.rotate(&mut b, &z[D + m..D + 2 * m]);
    let mut r = *r_ij;
    for k in 0..D {
        r[k] += z[k];
    }
    let c = shape.pair_contacts(&Pair::new(sizes.0, a, sizes.1, b, r), f64::INFINITY);
    assert_eq!(c.len(), 1, "{}: one contact per pair", describe(shape));
    c[0].gap
}

/// One pair's analytic first and second derivatives in
/// `z = (r_j, q_i, q_j)` (from `Shape::contacts` and `Shape::gap_hessians`,
/// which must agree on the contact bit for bit), beside central
/// differences of [`pair_gap_at`]: of the gap with step `e1` for the
/// gradient, second central differences with step `e2` for the Hessian.
/// The caller asserts with the tolerances its family's derivatives allow.
#[derive(Clone, Debug)]
pub struct PairDerivatives {
    /// `∂h/∂z`, analytic.
    pub grad: Vec<f64>,
    /// `∂²h/∂z∂z`, analytic.
    pub hess: Vec<Vec<f64>>,
    /// `∂h/∂z` by central differences.
    pub fd_grad: Vec<f64>,
    /// `∂²h/∂z∂z` by second central differences.
    pub fd_hess: Vec<Vec<f64>>,
}

impl PairDerivatives {
    /// The largest `|analytic − finite difference|` of the gradient.
    pub fn grad_error(&self) -> f64 {
        let pairs = self.grad.iter().zip(&self.fd_grad);
        pairs.map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
    }

    /// The largest `|analytic − finite difference|` of the Hessian.
    pub fn hess_error(&self) -> f64 {
        let rows = self.hess.iter().zip(&self.fd_hess);
        rows.flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    }

    /// The largest `|∂²h/∂z∂z|` (so a test can show it has teeth).
    pub fn largest_second(&self) -> f64 {
        self.hess.iter().flatten().fold(0.0, |m, x| m.max(x.abs()))
    }
}

/// [`PairDerivatives`] of one pair (sizes `sizes`, orientations `o_i`,
/// `o_j`, separation `r_ij`).
pub fn pair_derivatives<const D: usize, S: Shape<D>>(
    shape: &S,
    sizes: (f64, f64),
    o_i: &S::Orientation,
    o_j: &S::Orientation,
    r_ij: &Vector<D>,
    e1: f64,
    e2: f64,
) -> PairDerivatives {
    let m = shape.rot_dof();
    let n = D + 2 * m;
    let mut found = None;
    shape
        .gap_hessians(
            &Pair::new(sizes.0, *o_i, sizes.1, *o_j, *r_ij),
            f64::INFINITY,
            |h| found = Some(h),
        )
        .unwrap();
    let h = found.expect("gap_hessians visits the pair");
    let c = shape.pair_contacts(
        &Pair::new(sizes.0, *o_i, sizes.1, *o_j, *r_ij),
        f64::INFINITY,
    );
    assert_eq!(c.len(), 1, "{}: one contact per pair", describe(shape));
    let c = c[0];
    assert_eq!(h.contact, c, "gap_hessians and contacts agree bit for bit");
    let mut grad = vec![0.0; n];
    let mut hess = vec![vec![0.0; n]; n];
    for a in 0..D {
        grad[a] = c.grad_r[a];
        for b in 0..D {
            hess[a][b] = h.rr[(a, b)];
        }
    }
    for p in 0..m {
        grad[D + p] = c.grad_rot_i[p];
        grad[D + m + p] = c.grad_rot_j[p];
        for a in 0..D {
            hess[a][D + p] = h.r_qi[p][a];
            hess[D + p][a] = h.r_qi[p][a];
            hess[a][D + m + p] = h.r_qj[p][a];
            hess[D + m + p][a] = h.r_qj[p][a];
        }
        for q in 0..m {
            hess[D + p][D + q] = h.qi_qi[p][q];
            hess[D + m + p][D + m + q] = h.qj_qj[p][q];
            hess[D + p][D + m + q] = h.qi_qj[p][q];
            hess[D + m + q][D + p] = h.qi_qj[p][q];
        }
    }
    let at = |z: &[f64]| pair_gap_at(shape, sizes, o_i, o_j, r_ij, z);
    let fd_grad = (0..n)
        .map(|a| {
            let (mut zp, mut zm) = (vec![0.0; n], vec![0.0; n]);
            zp[a] = e1;
            zm[a] = -e1;
            (at(&zp) - at(&zm)) / (2.0 * e1)
        })
        .collect();
    let fd_hess = (0..n)
        .map(|a| {
            (0..n)
                .map(|b| {
                    let d = |sa: f64, sb: f64| {
                        let mut z = vec![0.0; n];
                        z[a] += sa * e2;
                        z[b] += sb * e2;
                        at(&z)
                    };
                    (d(1.0, 1.0) - d(1.0, -1.0) - d(-1.0, 1.0) + d(-1.0, -1.0)) / (4.0 * e2 * e2)
                })
                .collect()
        })
        .collect();
    PairDerivatives {
        grad,
        hess,
        fd_grad,
        fd_hess,
    }
}

/// `h_ij = h_ji` for one pair seen from either body: the contact from
/// body `i` (sizes `sizes`, orientations `o_i`, `o_j`, at `r_ij`) and the
/// one from body `j` (sizes and orientations swapped, at `−r_ij`), one
/// contact each, must have the same gap (to `eps_gap`), `∂h/∂r_j`
/// reversed and the rotational derivatives swapped (to `eps_grad`). Each
/// number is compared as `approx::assert_relative_eq!` with that `epsilon`
/// compares it ([`relative_eq`]). The caller picks the tolerances its
/// family's gap allows.
pub fn check_swapped<const D: usize, S: Shape<D>>(
    shape: &S,
    sizes: (f64, f64),
    o_i: &S::Orientation,
    o_j: &S::Orientation,
    r_ij: &Vector<D>,
    eps_gap: f64,
    eps_grad: f64,
) {
    let one = |c: Vec<Contact<D>>| {
        assert_eq!(c.len(), 1, "{}: one contact per pair", describe(shape));
        c[0]
    };
    let ij = one(shape.pair_contacts(
        &Pair::new(sizes.0, *o_i, sizes.1, *o_j, *r_ij),
        f64::INFINITY,
    ));
    let ji = one(shape.pair_contacts(
        &Pair::new(sizes.1, *o_j, sizes.0, *o_i, -r_ij),
        f64::INFINITY,
    ));
    assert!(
        relative_eq(ij.gap, ji.gap, eps_gap),
        "h_ij = {} but h_ji = {}",
        ij.gap,
        ji.gap
    );
    for a in 0..D {
        assert!(
            relative_eq(ij.grad_r[a], -ji.grad_r[a], eps_grad),
            "∂h/∂r_j: {} from i, {} from j",
            ij.grad_r,
            ji.grad_r
        );
    }
    for p in 0..jamkit_core::MAX_ROT {
        for (a, b, which) in [
            (
                ij.grad_rot_i[p],
                ji.grad_rot_j[p],
                "∂h/∂q_i from i, ∂h/∂q_j from j",
            ),
            (
                ij.grad_rot_j[p],
                ji.grad_rot_i[p],
                "∂h/∂q_j from i, ∂h/∂q_i from j",
            ),
        ] {
            assert!(
                relative_eq(a, b, eps_grad),
                "{which}, coordinate {p}: {a} vs {b}"
            );
        }
    }
}

/// `a` and `b` equal to `epsilon` absolute, or to machine precision
/// relative: `approx`'s `relative_eq` with its default `max_relative`
/// (`f64::EPSILON`).
pub fn relative_eq(a: f64, b: f64, epsilon: f64) -> bool {
    approx::relative_eq!(a, b, epsilon = epsilon)
}

/// The dimensions `family` claims (`Dims::Any`: every compiled one).
pub fn claimed_dims(family: &str) -> Vec<usize> {
    let info = registry::family_info(family).unwrap();
    registry::COMPILED_DIMS
        .iter()
        .copied()
        .filter(|&d| registry::supports_dim(&info, d))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use jamkit_core::{Contact, GapHessian, Result};

    /// Disks whose gap gradient is 10% too long: a wrong derivative the
    /// kit must catch.
    #[derive(Clone, Debug)]
    struct WrongDisk;

    impl Shape<2> for WrongDisk {
        type Orientation = ();
        type Fast = jamkit_core::NoFastPath;
        fn family(&self) -> &'static str {
            "wrong_disk"
        }
        fn rot_dof(&self) -> usize {
            0
        }
        fn volume(&self, size: f64) -> f64 {
            std::f64::consts::PI * size * size
        }
        fn bounding_radius(&self, size: f64) -> f64 {
            size
        }
        fn rotate(&self, _o: &mut (), _dq: &[f64]) {}
        fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, ()>, max_gap: f64, mut visit: F) {
            let size_i = pair.size_i;
            let size_j = pair.size_j;
            let r_ij = &pair.r_ij;
            let d = r_ij.norm();
            let gap = d - size_i - size_j;
            if gap <= max_gap {
                visit(Contact::translational(gap, r_ij * (1.1 / d)));
            }
        }
        fn gap_hessians<F: FnMut(GapHessian<2>)>(
            &self,
            _pair: &Pair<2, ()>,
            _max_gap: f64,
            _visit: F,
        ) -> Result<()> {
            Err(jamkit_core::Error::invalid("test", 0, "no Hessian"))
        }
    }

    #[test]
    #[should_panic(expected = "gradient")]
    fn a_wrong_gradient_fails_the_kit() {
        check_family::<2, _>(WrongDisk);
    }

    /// `P(A) = cos 2A · |cos A|` (`P(A) = cos 2A` with `smooth`): the
    /// cornered profile's slope jumps by 2 at `A = ±π/2`, where
    /// `cos 2A = −1`.
    #[derive(Clone, Debug, PartialEq)]
    struct Cornered {
        smooth: bool,
    }

    impl jamkit_planar::profiled::NearDiskProfile for Cornered {
        const FAMILY: &'static str = "cornered";
        const HALF_TURN_SYMMETRIC: bool = true;
        fn value_slope(&self, cos: f64, sin: f64) -> (f64, f64) {
            let (c2, s2) = (cos * cos - sin * sin, 2.0 * sin * cos);
            if self.smooth {
                return (c2, -2.0 * s2);
            }
            let (a, sign) = (cos.abs(), cos.signum());
            (c2 * a, -2.0 * s2 * a - c2 * sin * sign)
        }
        fn curvature(&self, cos: f64, sin: f64) -> f64 {
            let (c2, s2) = (cos * cos - sin * sin, 2.0 * sin * cos);
            if self.smooth {
                return -4.0 * c2;
            }
            let (a, sign) = (cos.abs(), cos.signum());
            -4.0 * c2 * a + 4.0 * s2 * sin * sign - c2 * cos * sign
        }
        fn range(&self) -> (f64, f64) {
            (-1.0, 1.0)
        }
        fn describe(&self) -> String {
            String::from("cornered")
        }
    }

    fn cornered(smooth: bool) -> jamkit_planar::profiled::Profiled<Cornered> {
        jamkit_planar::profiled::Profiled::new(Cornered { smooth }, 0.1, None).unwrap()
    }

    #[test]
    #[should_panic(expected = "the outline has a corner")]
    fn a_profile_with_a_corner_fails_the_smoothness_check() {
        check_smooth(&cornered(false));
    }

    /// The same family without the corner passes, and the cornered one
    /// passes the force check (which is why the smoothness check exists).
    #[test]
    fn the_smooth_profile_passes_and_the_corner_escapes_the_force_check() {
        assert!(check_smooth(&cornered(true)));
        check_gradient(&cornered(false));
    }
}
