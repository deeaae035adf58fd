//! The exact gap started where the pair's last solve ended
//! ([`Shape::contacts_warm`] with the `"Joint"` solver,
//! [`Harmonic::exact_gap_warm`]) against the cold solve
//! ([`Shape::contacts`]): the same contacts to round-off whatever the memo
//! holds, the cold contacts bit for bit from an empty memo, and the
//! convergence the joint iteration promises.

use super::tests::{mixed, single};
use super::*;
use jamkit_core::{MEMO_LEN, ShapeExt};
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

/// A random unit vector.
fn direction(rng: &mut Rng8) -> Vector<3> {
    Quaternion::random(rng).columns()[0]
}

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

/// The pair moved a little: the separation by up to `dr` along each axis,
/// each body turned by up to `dt` rad about a random axis.
fn nudged(p: &Pair<3, Quaternion>, rng: &mut Rng8, dr: f64, dt: f64) -> Pair<3, Quaternion> {
    let mut q = *p;
    let mut shift = || dr * (2.0 * rng.random::<f64>() - 1.0);
    q.r_ij += Vector::<3>::new(shift(), shift(), shift());
    let ti = direction(rng) * (dt * rng.random::<f64>());
    let tj = direction(rng) * (dt * rng.random::<f64>());
    q.o_i = Quaternion::exp(&ti).mul(&q.o_i);
    q.o_j = Quaternion::exp(&tj).mul(&q.o_j);
    q
}

fn warm(
    s: &Harmonic,
    pair: &Pair<3, Quaternion>,
    max_gap: f64,
    memo: &mut PairMemo,
) -> Vec<Contact<3>> {
    let mut out = Vec::new();
    s.contacts_warm(pair, max_gap, memo, |c| out.push(c));
    out
}

fn numbers(c: &Contact<3>) -> [f64; 10] {
    [
        c.gap,
        c.grad_r[0],
        c.grad_r[1],
        c.grad_r[2],
        c.grad_rot_i[0],
        c.grad_rot_i[1],
        c.grad_rot_i[2],
        c.grad_rot_j[0],
        c.grad_rot_j[1],
        c.grad_rot_j[2],
    ]
}

/// The largest difference of two lists of contacts with gap ≤ 0 (those
/// that carry energy), which must be the same pairs: with `max_gap = 0`
/// the cold solve may also report a gap just above 0 (when `g(r̂) ≤ 0 < h`)
/// that the warm one skips, both as [`Shape::contacts`] allows.
fn distance(a: &[Contact<3>], b: &[Contact<3>]) -> f64 {
    let touching = |v: &[Contact<3>]| {
        v.iter()
            .filter(|c| c.gap <= 0.0)
            .map(numbers)
            .collect::<Vec<_>>()
    };
    let (a, b) = (touching(a), touching(b));
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    a.iter()
        .zip(&b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
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
    for s in shapes() {
        for _ in 0..30 {
            let pair = random_pair(&s, &mut rng);
            for max_gap in [0.0, f64::INFINITY] {
                let mut memo = None;
                let got = warm(&s, &pair, max_gap, &mut memo);
                assert_eq!(got, s.pair_contacts(&pair, max_gap));
                assert_eq!(memo.is_some(), !got.is_empty());
            }
            let nested = s.clone().with_exact_solver(ExactSolver::Nested);
            let mut memo = Some([0.3; MEMO_LEN]);
            let got = warm(&nested, &pair, 0.0, &mut memo);
            assert_eq!(got, nested.pair_contacts(&pair, 0.0));
            assert_eq!(memo, Some([0.3; MEMO_LEN]));
        }
    }
}

/// Whatever the memo holds, the warm contacts are the cold ones to
/// [`AGREE`]: along a run of small moves (the separation by up to 10⁻³,
/// the bodies turned by up to 10⁻² rad, each call from the memo the one
/// before left), from the memo of an unrelated pair (other sizes,
/// orientations and direction: the bodies turned far), and from memos
/// that are no start at all (zeros, NaN, a normal opposite the line of
/// centres).
#[test]
fn warm_contacts_agree_with_cold_ones_whatever_the_memo() {
    let mut rng = Rng8::seed_from_u64(12);
    let mut worst: f64 = 0.0;
    for s in shapes() {
        for _ in 0..25 {
            let mut pair = random_pair(&s, &mut rng);
            let mut memo = None;
            warm(&s, &pair, f64::INFINITY, &mut memo);
            for _ in 0..5 {
                pair = nudged(&pair, &mut rng, 1e-3, 1e-2);
                for max_gap in [0.0, f64::INFINITY] {
                    let got = warm(&s, &pair, max_gap, &mut memo.clone());
                    worst = worst.max(distance(&got, &s.pair_contacts(&pair, max_gap)));
                }
                warm(&s, &pair, f64::INFINITY, &mut memo);
            }
            let other = random_pair(&s, &mut rng);
            let mut unrelated = None;
            warm(&s, &other, f64::INFINITY, &mut unrelated);
            // The normal −r̂: `n − r̂ = −2r̂`, in body i's frame.
            let back = pair
                .o_i
                .apply_inverse(&(pair.r_ij * (-2.0 / pair.r_ij.norm())));
            let mut opposite = [0.0; MEMO_LEN];
            opposite[..3].copy_from_slice(back.as_slice());
            for start in [
                unrelated,
                Some([0.0; MEMO_LEN]),
                Some([f64::NAN; MEMO_LEN]),
                Some(opposite),
            ] {
                for max_gap in [0.0, f64::INFINITY] {
                    let got = warm(&s, &pair, max_gap, &mut start.clone());
                    worst = worst.max(distance(&got, &s.pair_contacts(&pair, max_gap)));
                }
            }
        }
    }
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
            s.exact_gap_warm(
                pair.size_i,
                &pair.o_i,
                pair.size_j,
                &pair.o_j,
                &pair.r_ij,
                f64::INFINITY,
                &mut memo,
                false,
            )
            .unwrap();
            let next = nudged(&pair, &mut rng, 1e-3, 1e-2);
            let (ci, cj) = (next.o_i.columns(), next.o_j.columns());
            let start = gap3d::JointStart::recall(&memo.unwrap(), &next.r_ij, &ci, &cj).unwrap();
            let gap3d::Joint::Found(e) = gap3d::exact_joint_warm(
                &next.r_ij,
                &gap3d::RadialBody {
                    columns: &ci,
                    radial: |y: &Vector<3>| s.radial_jet(next.size_i, y),
                },
                &gap3d::RadialBody {
                    columns: &cj,
                    radial: |y: &Vector<3>| s.radial_jet(next.size_j, y),
                },
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
        let e = s
            .exact_gap(
                pair.size_i,
                &pair.o_i,
                pair.size_j,
                &pair.o_j,
                &pair.r_ij,
                f64::INFINITY,
            )
            .unwrap();
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
