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

/// How far warm and cold contacts may differ: both stop within ~10⁻¹⁴ of
/// the optimum (normal and support points), at different points, and the
/// contact's entries are order-1 multiples of those (`h` ~10⁻²⁸); the
/// largest difference seen here is 4·10⁻¹⁵.
const AGREE: f64 = 1e-13;

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
    assert!(worst <= AGREE, "warm against cold: {worst:e}");
}

/// What "converged" guarantees for a warm result: at its normal `n`, with
/// both supports searched to convergence from scratch
/// ([`Harmonic::support`]), the tangent gradient of `g`,
/// `P(r − p_i(n) + p_j(−n))`, is below 10⁻¹³ (the normal is ~10⁻¹⁴ from
/// the optimum, `|W| = O(1)`), the gap is `g(n)` to 10⁻¹⁵ (round-off of
/// order-1 numbers) and the support points are the searched ones to
/// 10⁻¹³. From the memo of a small move (10⁻³, 10⁻² rad) the warm
/// iteration itself converges ([`gap3d::exact_joint_warm`] does not fall
/// back) in at most 3 steps.
#[test]
fn warm_results_are_converged() {
    let mut rng = Rng8::seed_from_u64(13);
    let (mut residual, mut gap, mut points): (f64, f64, f64) = (0.0, 0.0, 0.0);
    let mut steps = 0;
    for s in shapes() {
        for _ in 0..25 {
            let pair = random_pair(&s, &mut rng);
            let mut memo = None;
            solved(&s, &pair, &mut memo);
            let next = nudged(&pair, &mut rng, 1e-3, 1e-2);
            let (ci, cj) = (next.o_i.columns(), next.o_j.columns());
            let start = gap3d::JointStart::recall(&memo.unwrap(), &next.r_ij, &ci, &cj).unwrap();
            let gap3d::Joint::Found(e) = gap3d::exact_joint_warm(
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
    assert!(residual <= 1e-13, "tangent gradient {residual:e}");
    assert!(gap <= 1e-15, "gap against g(n): {gap:e}");
    assert!(points <= 1e-13, "support points {points:e}");
    assert!(steps <= 3, "{steps} steps");
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
