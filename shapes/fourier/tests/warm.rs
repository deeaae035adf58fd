//! The exact gap started where the pair's last solve ended
//! (`Shape::contacts_warm`, `Profiled::exact_solve_warm`) against the cold
//! solve (`Profiled::exact_solve`): the same contacts to round-off, whatever
//! the memo holds, and the convergence the joint iteration promises.

use jamkit_core::{Contact, Pair, PairMemo, Rotation2, Shape, ShapeExt, Warm};
use jamkit_fourier::{FourierParams, FourierSumParams, Mode, NearDisk};
use jamkit_planar::gap2d::{ExactGap, GapModel};
use jamkit_planar::profiled::ExactSolve;

#[path = "support/random.rs"]
mod random;
use random::{Uniform, nudged, random_pair};

/// Exact-gap near-disks: `fourier` n = 2..6 up to Δ = 0.3 (n = 2) and a
/// three-mode `fourier_sum`, all convex.
fn shapes() -> Vec<NearDisk> {
    let mut out: Vec<NearDisk> = [(2, 0.1), (2, 0.3), (3, 0.2), (4, 0.05), (6, 0.02)]
        .into_iter()
        .map(|(n, delta)| {
            NearDisk::fourier(&FourierParams {
                n,
                delta,
                inertia: None,
                gap: GapModel::Exact,
            })
            .unwrap()
        })
        .collect();
    let modes = vec![
        Mode {
            n: 2,
            a: 0.4,
            b: 0.3,
        },
        Mode {
            n: 3,
            a: 0.2,
            b: -1.0,
        },
        Mode {
            n: 7,
            a: 0.05,
            b: 0.0,
        },
    ];
    out.push(
        NearDisk::fourier_sum(&FourierSumParams {
            modes,
            delta: 0.15,
            inertia: None,
            gap: GapModel::Exact,
        })
        .unwrap(),
    );
    out
}

fn numbers(c: &Contact<2>) -> [f64; 5] {
    [
        c.gap,
        c.grad_r[0],
        c.grad_r[1],
        c.grad_rot_i[0],
        c.grad_rot_j[0],
    ]
}

/// The contacts of `contacts_warm` with the memo `memo` (which it updates).
fn warm(s: &NearDisk, pair: &Pair<2, Rotation2>, memo: &mut PairMemo) -> Vec<[f64; 5]> {
    let mut out = Vec::new();
    s.contacts_warm(pair, 0.0, memo, |c| out.push(numbers(&c)));
    out
}

fn cold(s: &NearDisk, pair: &Pair<2, Rotation2>) -> Vec<[f64; 5]> {
    s.pair_contacts(pair, 0.0).iter().map(numbers).collect()
}

/// The largest difference of two lists of contacts (which must have the
/// same length: the same pairs in contact).
fn distance(a: &[[f64; 5]], b: &[[f64; 5]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Warm and cold agree on random pairs to 1e-14 in the gap and its
/// derivatives (both stop within `~C·1e-16` rad of the same optimum,
/// `C = O(n³Δ)`: what is left is the round-off of the last Newton steps,
/// a few ulps amplified by `1/k`), with the memo
/// * empty (then warm is the cold solve, bit for bit),
/// * from the same pair a step earlier (centres moved by 1e-4, bodies
///   turned by 1e-3 rad),
/// * from another random pair (a very different configuration: the warm
///   start fails its safeguards or converges to the same optimum, and the
///   cold solve takes over where it fails).
///
/// After moves of 1e-6 (centres; turns by 1e-5 rad) the warm start takes
/// one Newton step (below `gap2d::JOINT_FINISH`, then corrected to second
/// order) on all but a few pairs, against the cold solve's three or more,
/// and its contact is that of the cold solve run to `JOINT_TOLERANCE`
/// with the jets evaluated at its end (`ExactSolve::JointAlone`) to 1e-14;
/// after moves of 1e-10 (turns by 1e-9 rad), one step.
#[test]
fn warm_and_cold_solves_agree() {
    let mut u = Uniform::new(11);
    let (mut compared, mut near) = (0, 0);
    let (mut warm_steps, mut cold_steps) = (0, 0);
    let mut worst: f64 = 0.0;
    for s in shapes() {
        let profiled = s.profiled();
        let mut last: PairMemo = None;
        for _ in 0..2000 {
            let pair = random_pair(&mut u);
            let reference = cold(&s, &pair);
            // Empty memo: the cold solve, bit for bit.
            let mut memo = None;
            let got = warm(&s, &pair, &mut memo);
            assert_eq!(got, reference);
            if got.is_empty() {
                continue;
            }
            assert!(memo.is_some());
            // The same pair a step later, from the memo of the step before.
            let next = nudged(&pair, &mut u, 1e-4, 1e-3);
            let got = warm(&s, &next, &mut memo.clone());
            let want = cold(&s, &next);
            worst = worst.max(distance(&got, &want));
            assert!(distance(&got, &want) <= 1e-14, "{s:?} {next:?}");
            // A memo from an unrelated pair.
            let got = warm(&s, &pair, &mut last.clone());
            worst = worst.max(distance(&got, &reference));
            assert!(distance(&got, &reference) <= 1e-14, "{s:?} {pair:?}");
            // Newton steps after a small move, where the joint iteration runs.
            let next = nudged(&pair, &mut u, 1e-6, 1e-5);
            if let (Some(w), Some(c)) = (
                profiled.exact_solve_warm(&next, 0.0, &mut memo.clone()),
                profiled.exact_solve(&next, 0.0, ExactSolve::JointAlone),
            ) {
                near += 1;
                warm_steps += w.iterations;
                cold_steps += c.iterations;
                assert!(w.iterations <= 2, "{}", w.iterations);
                let d = distance(&[numbers(&w.contact())], &[numbers(&c.contact())]);
                worst = worst.max(d);
                assert!(d <= 1e-14, "{s:?} {next:?}: {d:e}");
            }
            let next = nudged(&pair, &mut u, 1e-10, 1e-9);
            if profiled
                .exact_solve(&next, 0.0, ExactSolve::JointAlone)
                .is_some()
            {
                let w = profiled.exact_solve_warm(&next, 0.0, &mut memo.clone());
                assert_eq!(w.unwrap().iterations, 1);
            }
            last = memo;
            compared += 1;
        }
    }
    println!(
        "{compared} pairs, {near} joint solves after small moves: {warm_steps} steps warm, \
         {cold_steps} cold; largest difference {worst:e}"
    );
    assert!(compared > 3000, "{compared}");
    assert!(near > 3000, "{near}");
    assert!(
        3 * warm_steps < 2 * cold_steps,
        "{warm_steps} against {cold_steps}"
    );
    assert!(
        100 * warm_steps < 101 * near,
        "{warm_steps} steps, {near} solves"
    );
}

/// What "converged" promises (`gap2d::JOINT_TOLERANCE`): at the returned
/// point the stationarity conditions hold to round-off, warm or cold,
/// `|g'(ψ)| = |r·e'(ψ) − H_i' − H_j'|` below 1e-14 and each support
/// condition `|q| = |R sin δ − R' cos δ|` below 1e-14 (sizes ≤ 0.7,
/// `r ≤ 1.5`: a few hundred ulps of the terms, where the step tolerance
/// alone leaves `~C·1e-16` rad).
#[test]
fn converged_means_stationary_to_round_off() {
    let mut u = Uniform::new(5);
    let mut checked = 0;
    for s in shapes() {
        let profiled = s.profiled();
        let (delta, profile) = (profiled.delta(), profiled.profile());
        use jamkit_planar::profiled::NearDiskProfile;
        // R/R⁰ and R'/R⁰ at the body-frame support point e^{iφ}.
        let outline = |p: (f64, f64)| {
            let j = profile.jet3(p.0, -p.1).unwrap();
            (1.0 + delta * j[0], -delta * j[1])
        };
        let check = |pair: &Pair<2, Rotation2>, e: &ExactGap, memo: &PairMemo| {
            let m = memo.unwrap();
            let (c, sn) = e.normal;
            let g1 = -pair.r_ij[0] * sn + pair.r_ij[1] * c - e.jet_i.d1 - e.jet_j.d1;
            assert!(g1.abs() <= 1e-14, "g' = {g1:e}");
            let cmul =
                |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
            for (o, d, size, flip) in [
                (pair.o_i, (m[2], m[3]), pair.size_i, 1.0),
                (pair.o_j, (m[4], m[5]), pair.size_j, -1.0),
            ] {
                let z = o.unit();
                let beta = cmul(e.normal, (flip * z.0, -flip * z.1));
                let (r, r1) = outline(cmul(beta, d));
                let q = size * (r * d.1 - r1 * d.0);
                assert!(q.abs() <= 1e-14, "q = {q:e}");
            }
        };
        let mut memo = None;
        for _ in 0..1000 {
            let pair = random_pair(&mut u);
            // Where the joint iteration runs (the nested solve's own
            // tolerance is 1e-7 rad on ψ).
            if profiled
                .exact_solve(&pair, 0.0, ExactSolve::JointAlone)
                .is_none()
            {
                continue;
            }
            let mut fresh = None;
            if let Some(e) = profiled.exact_solve_warm(&pair, 0.0, &mut fresh) {
                check(&pair, &e, &fresh);
                checked += 1;
            }
            let next = nudged(&pair, &mut u, 1e-3, 1e-2);
            memo = fresh.or(memo);
            if profiled
                .exact_solve(&next, 0.0, ExactSolve::JointAlone)
                .is_some()
                && let Some(e) = profiled.exact_solve_warm(&next, 0.0, &mut memo)
            {
                check(&next, &e, &memo);
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

/// `Shape::contact_warm`, through which `contacts_warm` reaches the warm
/// solve: the exact gap answers with its contact (bit for bit
/// `Shape::contacts` from an empty memo, which it fills); the first- and
/// second-order gaps have no warm solve (`Warm::Cold`, the memo left
/// empty), and their `contacts_warm` is `contacts`, bit for bit.
#[test]
fn contact_warm_answers_for_the_exact_gap_alone() {
    let mut u = Uniform::new(3);
    let (mut exact, mut approximate) = (0, 0);
    for gap in [GapModel::Exact, GapModel::FirstOrder, GapModel::SecondOrder] {
        let s = NearDisk::fourier(&FourierParams {
            n: 2,
            delta: 0.2,
            inertia: None,
            gap,
        })
        .unwrap();
        for _ in 0..200 {
            let pair = random_pair(&mut u);
            let reference = cold(&s, &pair);
            let mut memo: PairMemo = None;
            match s.contact_warm(&pair, 0.0, &mut memo) {
                Warm::Solved(c) => {
                    assert_eq!(gap, GapModel::Exact);
                    let got: Vec<[f64; 5]> = c.iter().map(numbers).collect();
                    assert_eq!(got, reference);
                    assert_eq!(memo.is_some(), c.is_some());
                    exact += usize::from(c.is_some());
                }
                Warm::Cold => {
                    assert_ne!(gap, GapModel::Exact);
                    assert!(memo.is_none());
                    assert_eq!(warm(&s, &pair, &mut memo), reference);
                    approximate += reference.len();
                }
            }
        }
    }
    assert!(exact > 50 && approximate > 100, "{exact} {approximate}");
}
