//! The warm exact gap of many pairs at a time
//! (`FastContacts::contacts_warm_lanes`, `Ellipse::exact_warm_lanes`)
//! against one pair at a time (`Shape::contacts_warm`): the same contacts
//! and the same memos, bit for bit, over pairs that move a little, turn
//! far, come new (no memo) or go apart between calls.

use jamkit_core::{Contact, ContactLanes, FastContacts, Pair, PairLanes, PairMemo, Shape, Vector};
use jamkit_ellipse::{Axis, Ellipse, EllipseParams};

/// Seeded uniform numbers in `[0, 1)`.
struct Uniform(rand_chacha::ChaCha8Rng);

impl Uniform {
    fn new(seed: u64) -> Self {
        use rand::SeedableRng;
        Self(rand_chacha::ChaCha8Rng::seed_from_u64(seed))
    }

    fn next(&mut self) -> f64 {
        use rand::RngExt;
        self.0.random::<f64>()
    }
}

fn ellipse(aspect: f64) -> Ellipse {
    Ellipse::new(&EllipseParams {
        aspect,
        inertia: None,
    })
    .unwrap()
}

/// A random pair around contact: sizes in [0.5, 0.7], any angles and
/// direction, centres from 5 % inside the sum of the short semi-axes to
/// 5 % beyond the sum of the long ones (overlapping, touching and apart).
fn random_pair(s: &Ellipse, u: &mut Uniform) -> Pair<2, Axis> {
    let pi = std::f64::consts::PI;
    let (si, sj) = (0.5 + 0.2 * u.next(), 0.5 + 0.2 * u.next());
    let (ti, tj) = (pi - 2.0 * pi * u.next(), pi - 2.0 * pi * u.next());
    let dir = 2.0 * pi * u.next();
    let ((ai, bi), (aj, bj)) = (s.semi_axes(si), s.semi_axes(sj));
    let (short, long) = (0.95 * (bi + bj), 1.05 * (ai + aj));
    let r = short + (long - short) * u.next();
    Pair::new(
        si,
        Axis::new(ti),
        sj,
        Axis::new(tj),
        Vector::<2>::new(r * dir.cos(), r * dir.sin()),
    )
}

/// The pair moved: centres by up to `dr`, bodies turned by up to `dt` rad.
fn nudged(p: &Pair<2, Axis>, u: &mut Uniform, dr: f64, dt: f64) -> Pair<2, Axis> {
    let mut q = *p;
    q.r_ij += Vector::<2>::new(dr * (2.0 * u.next() - 1.0), dr * (2.0 * u.next() - 1.0));
    q.o_i = q.o_i.turned(dt * (2.0 * u.next() - 1.0));
    q.o_j = q.o_j.turned(dt * (2.0 * u.next() - 1.0));
    q
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
fn lanes(shape: &Ellipse, pairs: &[Pair<2, Axis>]) -> PairLanes<2, Axis, W> {
    let mut p = PairLanes::filled(Axis::new(0.0));
    for (l, q) in pairs.iter().enumerate() {
        let reach = (
            shape.bounding_radius(q.size_i),
            shape.bounding_radius(q.size_j),
        );
        p.set(l, q, reach);
    }
    p
}

/// 150 tracked pairs over 40 calls, at α = 1.1, 1.5, 2 and 3, with
/// `max_gap` 0 and 0.02: between calls every pair moves by 1e-7 … 1e-2
/// (centres) and turns by up to 1e-6 … 3 rad, some are replaced by new
/// pairs (memo `None`) and some pushed apart. Lanes (chunks of 64, the
/// last one short, each pair's memo at a place of its own, in reverse
/// order) and one pair at a time give the same contacts and memos, bit
/// for bit. The moves reach every branch of the lanes: one step from the
/// memo with the Taylor finish (small moves), a step followed by an
/// evaluation at the normal, several steps (moves of 1e-4 … 1e-2), the
/// scalar solve (new pairs, failed guards after turns by up to 3 rad) and
/// no contact (pairs apart, by the bounding test, the screen or an
/// iterate).
#[test]
fn lanes_match_one_pair_at_a_time_bit_for_bit() {
    for (k, aspect) in [1.1, 1.5, 2.0, 3.0].into_iter().enumerate() {
        let shape = ellipse(aspect);
        assert!(<Ellipse as FastContacts<2, Ellipse>>::use_warm_lanes(
            &shape
        ));
        for max_gap in [0.0, 0.02] {
            let mut u = Uniform::new(31 + k as u64);
            let mut pairs: Vec<_> = (0..150).map(|_| random_pair(&shape, &mut u)).collect();
            let mut scalar: Vec<PairMemo> = vec![None; pairs.len()];
            // The lanes' memos in reverse order.
            let mut laned: Vec<PairMemo> = vec![None; pairs.len()];
            let mut scratch = Vec::new();
            let mut out = ContactLanes::<2, W>::default();
            let (mut found, mut solved) = (0, 0);
            for call in 0..40 {
                for p in pairs.iter_mut() {
                    let x = u.next();
                    *p = if x < 0.05 {
                        random_pair(&shape, &mut u)
                    } else if x < 0.08 {
                        nudged(p, &mut u, 0.5, 0.0)
                    } else if x < 0.15 {
                        nudged(p, &mut u, 1e-2, 3.0)
                    } else if x < 0.25 {
                        nudged(p, &mut u, 1e-3, 1e-2)
                    } else if x < 0.4 {
                        nudged(p, &mut u, 1e-4, 1e-3)
                    } else {
                        nudged(p, &mut u, 1e-7, 1e-6)
                    };
                }
                let n = pairs.len();
                for i in 0..n {
                    if u.next() < 0.03 {
                        scalar[i] = None;
                        laned[n - 1 - i] = None;
                    }
                }
                for start in (0..n).step_by(W) {
                    let chunk = &pairs[start..n.min(start + W)];
                    let batch = lanes(&shape, chunk);
                    let at: [u32; W] =
                        std::array::from_fn(|l| (n - 1 - (start + l).min(n - 1)) as u32);
                    <Ellipse as FastContacts<2, Ellipse>>::contacts_warm_lanes(
                        &shape,
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
                        let what =
                            format!("α = {aspect}, max_gap {max_gap}, call {call}, pair {i}");
                        assert_eq!(bits(out.get(l)), bits(one), "{what}");
                        assert_eq!(
                            memo_bits(&laned[n - 1 - i]),
                            memo_bits(&scalar[i]),
                            "{what}"
                        );
                        found += usize::from(one.is_some());
                        solved += usize::from(one.is_some_and(|c| c.gap < 0.0));
                    }
                }
            }
            // Both contacts and pairs apart, overlapping pairs among the
            // contacts.
            let total = 40 * pairs.len();
            assert!(
                found > total / 5 && found < total * 4 / 5,
                "α = {aspect}: {found} contacts of {total}"
            );
            assert!(solved > total / 10, "α = {aspect}: {solved} overlaps");
        }
    }
}
