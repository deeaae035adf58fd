//! The exact gap's warm contacts many pairs at a time
//! (`FastContacts::contacts_warm_lanes`, `Profiled::exact_warm_lanes`)
//! against one pair at a time (`Shape::contacts_warm`): the same contacts
//! and the same memos, bit for bit, over pairs that move a little, turn
//! far, come new (no memo) or go apart between calls.

use jamkit_core::{
    Contact, ContactLanes, FastContacts, Pair, PairLanes, PairMemo, Rotation2, Shape,
};
use jamkit_fourier::{FourierParams, FourierSumParams, Mode, NearDisk};
use jamkit_planar::gap2d::GapModel;

#[path = "support/random.rs"]
mod random;
use random::{Uniform, nudged, random_pair};

/// Exact-gap near-disks: `fourier` n = 2 (Δ = 0.1, 0.3), 3, 4, 6 and 7 (a
/// mode number without a copy of its own) and a `fourier_sum` with phases.
fn shapes() -> Vec<NearDisk> {
    let mut out: Vec<NearDisk> = [
        (2, 0.1),
        (2, 0.3),
        (3, 0.2),
        (4, 0.05),
        (6, 0.02),
        (7, 0.015),
    ]
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

/// The bits of a contact, or none.
fn bits(c: Option<Contact<2>>) -> Option<Vec<u64>> {
    c.map(|c| {
        [c.gap, c.grad_r[0], c.grad_r[1]]
            .into_iter()
            .chain(c.grad_rot_i)
            .chain(c.grad_rot_j)
            .map(f64::to_bits)
            .collect()
    })
}

fn memo_bits(m: &PairMemo) -> Option<Vec<u64>> {
    m.map(|v| v.iter().map(|x| x.to_bits()).collect())
}

const W: usize = 64;

/// The lanes of `pairs` (at most `W`).
fn lanes(shape: &NearDisk, pairs: &[Pair<2, Rotation2>]) -> PairLanes<2, Rotation2, W> {
    let mut p = PairLanes::filled(Rotation2::new(0.0));
    for (l, q) in pairs.iter().enumerate() {
        let reach = (
            shape.bounding_radius(q.size_i),
            shape.bounding_radius(q.size_j),
        );
        p.set(l, q, reach);
    }
    p
}

/// 150 tracked pairs over 40 calls, with `max_gap` 0 and 0.02: between
/// calls every pair moves by 1e-7 … 1e-2 (centres) and turns by up to
/// 1e-6 … 3 rad, some are replaced by new pairs (memo `None`) and some
/// pushed apart. Lanes (chunks of 64, the last one short, each pair's
/// memo at a place of its own, in reverse order) and one pair at a time
/// give the same contacts and memos, bit for bit. The moves reach every
/// branch of the lanes: one step from the memo (small moves), several
/// (moves of 1e-4 … 1e-2), the scalar solve (new pairs, turns by up to
/// 3 rad) and no contact (pairs apart).
#[test]
fn lanes_match_one_pair_at_a_time_bit_for_bit() {
    for (k, shape) in shapes().iter().enumerate() {
        assert!(<NearDisk as FastContacts<2, NearDisk>>::use_warm_lanes(
            shape
        ));
        for max_gap in [0.0, 0.02] {
            let mut u = Uniform::new(31 + k as u64);
            let mut pairs: Vec<_> = (0..150).map(|_| random_pair(&mut u)).collect();
            let mut scalar: Vec<PairMemo> = vec![None; pairs.len()];
            // The lanes' memos in reverse order.
            let mut laned: Vec<PairMemo> = vec![None; pairs.len()];
            let mut scratch = Vec::new();
            let mut out = ContactLanes::<2, W>::default();
            for call in 0..40 {
                for p in pairs.iter_mut() {
                    let x = u.next();
                    *p = if x < 0.05 {
                        random_pair(&mut u)
                    } else if x < 0.08 {
                        nudged(p, &mut u, 0.5, 0.0)
                    } else if x < 0.15 {
                        nudged(p, &mut u, 1e-2, 3.0)
                    } else if x < 0.4 {
                        nudged(p, &mut u, 1e-4, 1e-3)
                    } else {
                        nudged(p, &mut u, 1e-7, 1e-6)
                    };
                }
                let n = pairs.len();
                let mut fresh = vec![false; n];
                for (i, f) in fresh.iter_mut().enumerate() {
                    *f = u.next() < 0.03;
                    if *f {
                        scalar[i] = None;
                        laned[n - 1 - i] = None;
                    }
                }
                for start in (0..n).step_by(W) {
                    let chunk = &pairs[start..n.min(start + W)];
                    let batch = lanes(shape, chunk);
                    let at: [u32; W] =
                        std::array::from_fn(|l| (n - 1 - (start + l).min(n - 1)) as u32);
                    <NearDisk as FastContacts<2, NearDisk>>::contacts_warm_lanes(
                        shape,
                        &batch,
                        chunk.len(),
                        max_gap,
                        &mut laned,
                        &at,
                        &mut scratch,
                        &mut out,
                    );
                    for (l, p) in chunk.iter().enumerate() {
                        let i = start + l;
                        let mut one = None;
                        shape.contacts_warm(p, max_gap, &mut scalar[i], |c| one = Some(c));
                        let what = format!("{shape:?}, max_gap {max_gap}, call {call}, pair {i}");
                        assert_eq!(bits(out.get(l)), bits(one), "{what}");
                        assert_eq!(
                            memo_bits(&laned[n - 1 - i]),
                            memo_bits(&scalar[i]),
                            "{what}"
                        );
                    }
                }
            }
        }
    }
}
