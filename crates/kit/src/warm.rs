//! Helpers for the tests of a family whose gap solve starts where the
//! pair's last one ended ([`Shape::contacts_warm`]) in 3D: a pair moved a
//! little, the warm contacts collected, and how far two lists of contacts
//! differ.

use jamkit_core::{Contact, MEMO_LEN, Pair, PairMemo, Quaternion, Shape, ShapeExt, Vector};
use rand::{Rng, RngExt};

/// A random unit vector (the first column of a random rotation).
pub fn direction<R: Rng>(rng: &mut R) -> Vector<3> {
    Quaternion::random(rng).columns()[0]
}

/// The pair moved: the separation by up to `dr` along each axis, each body
/// turned by up to `dt` rad about a random axis.
pub fn nudged<R: Rng>(
    p: &Pair<3, Quaternion>,
    rng: &mut R,
    dr: f64,
    dt: f64,
) -> Pair<3, Quaternion> {
    let mut q = *p;
    let mut shift = || dr * (2.0 * rng.random::<f64>() - 1.0);
    q.r_ij += Vector::<3>::new(shift(), shift(), shift());
    let ti = direction(rng) * (dt * rng.random::<f64>());
    let tj = direction(rng) * (dt * rng.random::<f64>());
    q.o_i = Quaternion::exp(&ti).mul(&q.o_i);
    q.o_j = Quaternion::exp(&tj).mul(&q.o_j);
    q
}

/// The contacts [`Shape::contacts_warm`] visits with `memo`.
pub fn warm<S: Shape<3, Orientation = Quaternion>>(
    s: &S,
    pair: &Pair<3, Quaternion>,
    max_gap: f64,
    memo: &mut PairMemo,
) -> Vec<Contact<3>> {
    let mut out = Vec::new();
    s.contacts_warm(pair, max_gap, memo, |c| out.push(c));
    out
}

/// A contact's gap and first derivatives as one list.
pub fn numbers(c: &Contact<3>) -> [f64; 10] {
    let mut out = [0.0; 10];
    out[0] = c.gap;
    out[1..4].copy_from_slice(c.grad_r.as_slice());
    out[4..7].copy_from_slice(&c.grad_rot_i);
    out[7..10].copy_from_slice(&c.grad_rot_j);
    out
}

/// The largest difference of two lists of contacts with gap ≤ 0 (those
/// that carry energy), which must be the same pairs (a panic otherwise):
/// with `max_gap = 0` a solve may report a gap just above 0 that another
/// skips, both as [`Shape::contacts`] allows.
pub fn distance(a: &[Contact<3>], b: &[Contact<3>]) -> f64 {
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

/// The memos a warm start must survive, each handed to `check` with the
/// pair it is read at and with the energy's cut and with none
/// (`max_gap` 0 and ∞): along a run of five small moves from `pair` (the
/// separation by up to 10⁻³, the bodies turned by up to 10⁻² rad, each
/// from the memo the call before left); the last of those with both bodies
/// turned far (up to π rad each) since its memo was written; the memo of
/// `other`, an unrelated pair; and memos that are no start at all (zeros,
/// NaN, a normal opposite the line of centres: `n − r̂ = −2r̂` in body
/// `i`'s frame).
pub fn memo_scenarios<S, R, F>(
    s: &S,
    pair: &Pair<3, Quaternion>,
    other: &Pair<3, Quaternion>,
    rng: &mut R,
    mut check: F,
) where
    S: Shape<3, Orientation = Quaternion>,
    R: Rng,
    F: FnMut(&Pair<3, Quaternion>, f64, PairMemo),
{
    let cuts = [0.0, f64::INFINITY];
    let mut pair = *pair;
    let mut memo = None;
    warm(s, &pair, f64::INFINITY, &mut memo);
    for _ in 0..5 {
        pair = nudged(&pair, rng, 1e-3, 1e-2);
        for max_gap in cuts {
            check(&pair, max_gap, memo);
        }
        warm(s, &pair, f64::INFINITY, &mut memo);
    }
    let turned = nudged(&pair, rng, 0.0, std::f64::consts::PI);
    for max_gap in cuts {
        check(&turned, max_gap, memo);
    }
    let mut unrelated = None;
    warm(s, other, f64::INFINITY, &mut unrelated);
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
        for max_gap in cuts {
            check(&pair, max_gap, start);
        }
    }
}

/// From an empty memo [`Shape::contacts_warm`] is [`Shape::contacts`]
/// bit for bit, with the energy's cut and with none, and it fills the
/// memo exactly for a pair it reports.
pub fn assert_empty_memo_is_cold<S: Shape<3, Orientation = Quaternion>>(
    s: &S,
    pair: &Pair<3, Quaternion>,
) {
    for max_gap in [0.0, f64::INFINITY] {
        let mut memo = None;
        let got = warm(s, pair, max_gap, &mut memo);
        assert_eq!(got, s.pair_contacts(pair, max_gap));
        assert_eq!(memo.is_some(), !got.is_empty());
    }
}

/// A family that ignores the memo (`s` with its warm start off):
/// [`Shape::contacts_warm`] is [`Shape::contacts`] and leaves the memo as
/// it was.
pub fn assert_memo_ignored<S: Shape<3, Orientation = Quaternion>>(
    s: &S,
    pair: &Pair<3, Quaternion>,
) {
    let mut memo = Some([0.3; MEMO_LEN]);
    let got = warm(s, pair, 0.0, &mut memo);
    assert_eq!(got, s.pair_contacts(pair, 0.0));
    assert_eq!(memo, Some([0.3; MEMO_LEN]));
}

/// [`assert_empty_memo_is_cold`] on 30 pairs `random_pair` draws for each
/// of `shapes`, and [`assert_memo_ignored`] on each shape turned into one
/// that ignores the memo by `memo_off`.
pub fn check_empty_memos<S, R, P, M>(shapes: &[S], rng: &mut R, random_pair: P, memo_off: M)
where
    S: Shape<3, Orientation = Quaternion>,
    R: Rng,
    P: Fn(&S, &mut R) -> Pair<3, Quaternion>,
    M: Fn(&S) -> S,
{
    for s in shapes {
        let off = memo_off(s);
        for _ in 0..30 {
            let pair = random_pair(s, rng);
            assert_empty_memo_is_cold(s, &pair);
            assert_memo_ignored(&off, &pair);
        }
    }
}

/// The largest difference of warm and cold contacts ([`distance`]) over
/// [`memo_scenarios`] from 25 pairs `random_pair` draws for each of
/// `shapes`; with `same_pairs`, the warm and cold lists must also have the
/// same length (no pair skipped by one and reported by the other).
pub fn worst_against_cold<S, R, P>(
    shapes: &[S],
    rng: &mut R,
    random_pair: P,
    same_pairs: bool,
) -> f64
where
    S: Shape<3, Orientation = Quaternion>,
    R: Rng,
    P: Fn(&S, &mut R) -> Pair<3, Quaternion>,
{
    let mut worst: f64 = 0.0;
    for s in shapes {
        for _ in 0..25 {
            let (pair, other) = (random_pair(s, rng), random_pair(s, rng));
            memo_scenarios(s, &pair, &other, rng, |p, max_gap, mut memo| {
                let got = warm(s, p, max_gap, &mut memo);
                let cold = s.pair_contacts(p, max_gap);
                if same_pairs {
                    assert_eq!(got.len(), cold.len(), "{got:?} vs {cold:?}");
                }
                worst = worst.max(distance(&got, &cold));
            });
        }
    }
    worst
}
