//! The exact gap started where the pair's last solve ended
//! ([`Shape::contacts_warm`] with the `"Joint"` solver,
//! [`Harmonic::exact_gap_warm`]) against the cold solve
//! ([`Shape::contacts`]): the same contacts to round-off whatever the memo
//! holds, the cold contacts bit for bit from an empty memo, and the
//! convergence the joint iteration promises.

use super::tests::{mixed, single};
use super::*;
use jamkit_kit::warm::{check_empty_memos, direction, nudged, worst_against_cold};
use rand::{RngExt, SeedableRng};

/// Convex exact-gap bodies with the joint solver: zonal `l = 2` at
/// `Δ = 0.1` and `0.3` (two rotational coordinates), tesseral `l = 2`,
/// `l = 3` and a mixed sum (up to `l = 5`).
fn shapes() -> Vec<Harmonic> {
    [
        single(2, 0, 0.1),
        single(2, 0, 0.3),
        single(2, 2, 0.2),
        single(3, -1, 0.12),
        mixed(0.08),
    ]
    .into_iter()
    .map(|h| {
        h.with_gap(GapModel::Exact)
            .unwrap()
            .with_exact_solver(ExactSolver::Joint)
    })
    .collect()
}

type Rng8 = rand_chacha::ChaCha8Rng;

/// A random pair near contact: sizes in [0.5, 0.7], random orientations
/// and direction, the centres from 5 % of the sizes' sum overlapping to
/// 3 % apart (measured from `g` at the line of centres).
fn random_pair(s: &Harmonic, rng: &mut Rng8) -> Pair<3, Quaternion> {
    let (si, sj) = (
        0.5 + 0.2 * rng.random::<f64>(),
        0.5 + 0.2 * rng.random::<f64>(),
    );
    let (qi, qj) = (Quaternion::random(rng), Quaternion::random(rng));
    let d = direction(rng);
    let reach = s.support(si, &qi.columns(), &d).jet.h + s.support(sj, &qj.columns(), &-d).jet.h;
    let r = reach + (si + sj) * (0.08 * rng.random::<f64>() - 0.05);
    Pair::new(si, qi, sj, qj, d * r)
}

/// The exact gap of `pair` as the energy pass finds it from `memo`
/// (with no cut), `memo` updated.
fn solved(s: &Harmonic, pair: &Pair<3, Quaternion>, memo: &mut PairMemo) -> ExactGap3 {
    s.exact_gap_warm(
        pair.size_i,
        &pair.o_i,
        pair.size_j,
        &pair.o_j,
        &pair.r_ij,
        f64::INFINITY,
        memo,
        false,
    )
    .unwrap()
}

/// How far warm and cold contacts may differ: the warm solve stops within
/// `K len² < K·10⁻¹⁰` of the optimum in the normal and the support points
/// ([`gap3d::WARM_TOL`], `K` below 1), the cold one within ~10⁻¹⁴, and the
/// contact's entries are order-1 multiples of those (`h` within
/// ~10⁻²⁰); the largest difference seen here is 6·10⁻¹¹.
const AGREE: f64 = 2e-10;

/// From an empty memo, [`Shape::contacts_warm`] is [`Shape::contacts`]
/// bit for bit (the cold solve), with the energy's cut and with none,
/// and it fills the memo for a pair in contact; the nested solver ignores
/// the memo.
#[test]
fn an_empty_memo_gives_the_cold_contacts_bit_for_bit() {
    let mut rng = Rng8::seed_from_u64(11);
    check_empty_memos(&shapes(), &mut rng, random_pair, |s| {
        s.clone().with_exact_solver(ExactSolver::Nested)
    });
}

/// Whatever the memo holds, the warm contacts are the cold ones to
/// [`AGREE`] ([`memo_scenarios`]: small moves, bodies turned far, an
/// unrelated pair's memo, memos that are no start).
#[test]
fn warm_contacts_agree_with_cold_ones_whatever_the_memo() {
    let mut rng = Rng8::seed_from_u64(12);
    let worst = worst_against_cold(&shapes(), &mut rng, random_pair, false);
    println!("warm against cold: {worst:e}");
    assert!(worst <= AGREE, "warm against cold: {worst:e}");
}

/// What "converged" guarantees for a warm result: at its normal `n`, with
/// both supports searched to convergence from scratch
/// ([`Harmonic::support`]), the tangent gradient of `g`,
/// `P(r − p_i(n) + p_j(−n))`, is below 2·10⁻¹⁰ (the normal is within
/// `K len² < 10⁻¹⁰` of the optimum, [`gap3d::WARM_TOL`], `|W| = O(1)`),
/// the gap is `g(n)` to 10⁻¹⁵ (round-off of order-1 numbers: the support
/// points' error enters `h` squared) and the support points are the
/// searched ones to 2·10⁻¹⁰. From the memo of a small move (10⁻³,
/// 10⁻² rad) the warm iteration itself converges
/// ([`gap3d::exact_joint_warm`] does not fall back) in at most 3 steps.
/// Where it says it ended (the next start) is its result's normal and
/// support unit vectors `Qᵀp/|p|` to 10⁻¹¹ (after a step below
/// [`gap3d::TAYLOR_TOL`], `y + δy` against the point moved to first
/// order: `O(len²)` ≤ 10⁻¹²). The largest of each is printed.
#[test]
fn warm_results_are_converged() {
    let mut rng = Rng8::seed_from_u64(13);
    let (mut residual, mut gap, mut points, mut ends): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    let mut steps = 0;
    for s in shapes() {
        for _ in 0..25 {
            let pair = random_pair(&s, &mut rng);
            let mut memo = None;
            solved(&s, &pair, &mut memo);
            let next = nudged(&pair, &mut rng, 1e-3, 1e-2);
            let (ci, cj) = (next.o_i.columns(), next.o_j.columns());
            let start = gap3d::JointStart::recall(&memo.unwrap(), &next.r_ij, &ci, &cj).unwrap();
            let gap3d::Joint::Found(e, end) = gap3d::exact_joint_warm(
                &next.r_ij,
                &s.radial_body(next.size_i, &ci),
                &s.radial_body(next.size_j, &cj),
                &start,
                f64::INFINITY,
                false,
            ) else {
                panic!("the warm iteration fell back after a small move");
            };
            steps = steps.max(e.iterations);
            ends = ends
                .max((end.normal - e.normal).norm())
                .max((end.y_i - next.o_i.apply_inverse(&e.jet_i.point).normalize()).norm())
                .max((end.y_j - next.o_j.apply_inverse(&e.jet_j.point).normalize()).norm());
            let n = e.normal;
            let (pi, pj) = (
                s.support(next.size_i, &ci, &n),
                s.support(next.size_j, &cj, &-n),
            );
            let t = next.r_ij - pi.jet.point + pj.jet.point;
            residual = residual.max((t - n * n.dot(&t)).norm());
            gap = gap.max((e.gap - (n.dot(&next.r_ij) - pi.jet.h - pj.jet.h)).abs());
            points = points
                .max((e.jet_i.point - pi.jet.point).norm())
                .max((e.jet_j.point - pj.jet.point).norm());
        }
    }
    println!(
        "tangent gradient {residual:e}, gap {gap:e}, points {points:e}, ends {ends:e}, {steps} steps"
    );
    assert!(residual <= 2e-10, "tangent gradient {residual:e}");
    assert!(gap <= 1e-15, "gap against g(n): {gap:e}");
    assert!(points <= 2e-10, "support points {points:e}");
    assert!(steps <= 3, "{steps} steps");
    assert!(ends <= 1e-11, "where the iteration ended: {ends:e}");
}

/// [`gap3d::JointStart`] read back at the pair it was written for is the
/// solve's own normal and support unit vectors (round-off), and after the
/// whole pair turned by a rotation `T` (separation and both bodies) it is
/// the turned optimum: `T n` and the same body-frame `y`.
#[test]
fn a_memo_follows_a_pair_turned_as_a_whole() {
    let mut rng = Rng8::seed_from_u64(14);
    let s = &shapes()[4];
    for _ in 0..10 {
        let pair = random_pair(s, &mut rng);
        let e = solved(s, &pair, &mut None);
        let (ci, cj) = (pair.o_i.columns(), pair.o_j.columns());
        let memo = gap3d::JointStart::remember(&e, &pair.r_ij, &ci, &cj);
        let t = Quaternion::random(&mut rng);
        let (ti, tj) = (t.mul(&pair.o_i), t.mul(&pair.o_j));
        let r = t.apply(&pair.r_ij);
        let start = gap3d::JointStart::recall(&memo, &r, &ti.columns(), &tj.columns()).unwrap();
        assert!((start.normal - t.apply(&e.normal)).norm() < 1e-14);
        assert!((start.y_i - pair.o_i.apply_inverse(&e.jet_i.point).normalize()).norm() < 1e-14);
        assert!((start.y_j - pair.o_j.apply_inverse(&e.jet_j.point).normalize()).norm() < 1e-14);
    }
}

/// The screen of the warm solve, [`Harmonic::gap_lower_bound`], is a
/// lower bound on `g(n)` (hence on `h ≥ g(n)`) wherever it is read: at
/// the optimum normal, at normals turned 0.05 and 0.5 rad from it, and at
/// the line of centres, for every shape and 40 random pairs each, against
/// `g(n)` with both supports searched to convergence (round-off 10⁻¹⁴
/// allowed). What it gives away at the optimum normal, against the two
/// margins `π²G²/(16ρ_min)`, is printed.
#[test]
fn the_gap_lower_bound_is_below_g_everywhere() {
    let mut rng = Rng8::seed_from_u64(15);
    let mut used: f64 = 0.0;
    for s in shapes() {
        for _ in 0..40 {
            let pair = random_pair(&s, &mut rng);
            let (ci, cj) = (pair.o_i.columns(), pair.o_j.columns());
            let e = solved(&s, &pair, &mut None);
            let axis = direction(&mut rng);
            let turned = |angle: f64| Quaternion::exp(&(axis * angle)).apply(&e.normal);
            for n in [e.normal, turned(0.05), turned(0.5), pair.r_ij.normalize()] {
                let bound = s.gap_lower_bound(pair.size_i, &ci, pair.size_j, &cj, &pair.r_ij, &n);
                let (pi, pj) = (
                    s.support(pair.size_i, &ci, &n),
                    s.support(pair.size_j, &cj, &-n),
                );
                let g = n.dot(&pair.r_ij) - pi.jet.h - pj.jet.h;
                assert!(bound <= g + 1e-14, "bound {bound} above g(n) = {g}");
            }
            let bound =
                s.gap_lower_bound(pair.size_i, &ci, pair.size_j, &cj, &pair.r_ij, &e.normal);
            let margins = std::f64::consts::PI.powi(2) / 16.0
                * [pair.size_i, pair.size_j]
                    .iter()
                    .map(|size| {
                        let slope = size * s.delta * s.f_slope;
                        slope * slope / (size * (1.0 - s.delta * s.f_bound))
                    })
                    .sum::<f64>();
            used = used.max((e.gap - bound) / margins);
        }
    }
    println!("h − bound at the optimum: at most {used:.3} of the margins");
}

/// The joint solve's closed-form radial jet of a quadratic `F` (every mode
/// `l = 2`) is the general one ([`Harmonic::radial_jet`], checked against
/// finite differences in `exact_tests`) to round-off, 10⁻¹⁴ in `ρ`, `∇ρ̃`
/// and `∇∇ρ̃` at 200 random unit vectors, for zonal, tesseral and mixed
/// `l = 2`; shapes with other degrees have no quadratic form and read the
/// general jet.
#[test]
fn the_quadratic_radial_jet_is_the_general_one() {
    let mut rng = Rng8::seed_from_u64(16);
    let mixed2 = Harmonic::new(&HarmonicParams {
        l: None,
        m: None,
        modes: Some(vec![
            Mode { l: 2, m: 0, c: 0.7 },
            Mode {
                l: 2,
                m: -1,
                c: -0.4,
            },
            Mode { l: 2, m: 2, c: 0.5 },
        ]),
        delta: 0.1,
        inertia: None,
        gap: GapModel::FirstOrder,
        exact_solver: ExactSolver::Nested,
    })
    .unwrap();
    let quadratic = [
        single(2, 0, 0.1),
        single(2, 2, 0.2),
        single(2, -1, 0.3),
        mixed2,
    ];
    for s in &quadratic {
        assert!(s.quadratic.is_some());
        for _ in 0..200 {
            let y = direction(&mut rng);
            let (a, b) = (s.joint_jet(0.6, &y), s.radial_jet(0.6, &y));
            assert!((a.0 - b.0).abs() <= 1e-14, "{} vs {}", a.0, b.0);
            assert!((a.1 - b.1).amax() <= 1e-14, "{:?} vs {:?}", a.1, b.1);
            assert!((a.2 - b.2).amax() <= 1e-14, "{:?} vs {:?}", a.2, b.2);
        }
    }
    for s in [single(3, -1, 0.12), mixed(0.08)] {
        assert!(s.quadratic.is_none());
    }
}
