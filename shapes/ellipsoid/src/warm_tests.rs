//! The exact gap started at the normal where the pair's last solve ended
//! ([`Shape::contacts_warm`] with `warm_start`,
//! [`Ellipsoid::exact_gap_warm`]) against the cold solve
//! ([`Shape::contacts`]): the same contacts to round-off whatever the memo
//! holds, the same pairs skipped, the cold contacts bit for bit from an
//! empty memo, and fewer steps after a small move.

use super::*;
use jamkit_kit::warm::{check_empty_memos, direction, nudged, worst_against_cold};
use rand::{RngExt, SeedableRng};

type Rng8 = rand_chacha::ChaCha8Rng;

/// Prolate (the spheroids' study at α = 1.5, and α = 3), oblate and
/// triaxial, with warm starts.
fn shapes() -> Vec<Ellipsoid> {
    [
        Ellipsoid::spheroid(1.5),
        Ellipsoid::spheroid(3.0),
        Ellipsoid::spheroid(0.6),
        Ellipsoid::triaxial([1.0, 1.4, 2.2]),
    ]
    .into_iter()
    .map(|s| s.unwrap().with_warm_start(true))
    .collect()
}

/// A random pair near contact: sizes in [0.5, 0.7], random orientations
/// and direction, the centres from 5 % of the sizes' sum overlapping to
/// 3 % apart (measured from `g` at the line of centres).
fn random_pair(s: &Ellipsoid, rng: &mut Rng8) -> Pair<3, Quaternion> {
    let (si, sj) = (
        0.5 + 0.2 * rng.random::<f64>(),
        0.5 + 0.2 * rng.random::<f64>(),
    );
    let (qi, qj) = (Quaternion::random(rng), Quaternion::random(rng));
    let d = direction(rng);
    let reach = s.support(si, &qi).jet(&d).h + s.support(sj, &qj).jet(&-d).h;
    let r = reach + (si + sj) * (0.08 * rng.random::<f64>() - 0.05);
    Pair::new(si, qi, sj, qj, d * r)
}

/// How far warm and cold contacts may differ: both stop within ~10⁻¹⁴ of
/// the optimum normal (a last Newton step below 10⁻⁷), at different
/// points, and the contact's entries are order-1 multiples of the normal
/// and the support points (`h` moves by ~10⁻²⁸).
const AGREE: f64 = 1e-13;

/// From an empty memo, [`Shape::contacts_warm`] is [`Shape::contacts`]
/// bit for bit (the cold solve), with the energy's cut and with none, and
/// it fills the memo for a pair it reports; without `warm_start` the
/// memo is ignored.
#[test]
fn an_empty_memo_gives_the_cold_contacts_bit_for_bit() {
    let mut rng = Rng8::seed_from_u64(21);
    check_empty_memos(&shapes(), &mut rng, random_pair, |s| {
        s.clone().with_warm_start(false)
    });
}

/// Whatever the memo holds, the warm contacts are the cold ones to
/// [`AGREE`], with the same pairs skipped ([`memo_scenarios`]: small
/// moves, bodies turned far, an unrelated pair's memo, memos that are no
/// start).
#[test]
fn warm_contacts_agree_with_cold_ones_whatever_the_memo() {
    let mut rng = Rng8::seed_from_u64(22);
    let worst = worst_against_cold(&shapes(), &mut rng, random_pair, true);
    assert!(worst <= AGREE, "warm against cold: {worst:e}");
}

/// After a small move (10⁻³, 10⁻² rad) the ascent from the memo's normal
/// takes at most `STEPS` Newton steps (the normal starts ~10⁻² off: steps
/// of ~10⁻², 10⁻⁴, 10⁻⁸) and, over all pairs, at most 3/4 of the cold
/// solve's (from `r̂`, 0.1–0.3 off): the warm start is used, not solved
/// around.
#[test]
fn a_warm_start_saves_steps() {
    const STEPS: u32 = 3;
    let mut rng = Rng8::seed_from_u64(23);
    let (mut warm_steps, mut cold_steps, mut most) = (0, 0, 0);
    for s in shapes() {
        for _ in 0..25 {
            let pair = random_pair(&s, &mut rng);
            let mut memo = None;
            let solve = |p: &Pair<3, Quaternion>, memo: &mut PairMemo| {
                s.exact_gap_warm(p, f64::INFINITY, memo).unwrap()
            };
            solve(&pair, &mut memo);
            let next = nudged(&pair, &mut rng, 1e-3, 1e-2);
            let e = solve(&next, &mut memo);
            let cold = solve(&next, &mut None);
            warm_steps += e.iterations;
            cold_steps += cold.iterations;
            most = most.max(e.iterations);
        }
    }
    assert!(most <= STEPS, "{most} steps");
    assert!(
        4 * warm_steps <= 3 * cold_steps,
        "warm {warm_steps}, cold {cold_steps} steps"
    );
}
