//! The warm exact gap of many pairs side by side
//! ([`FastContacts::contacts_warm_lanes`]): the screens and the steps of
//! Halley's iteration from the memo ([`Ellipse::exact_gap_warm`]) over
//! plain arrays, one entry per pair, by the same functions as the scalar
//! solve ([`evaluate`], [`halley_step`], [`taylor`], [`overshoots`],
//! [`screened_out`], [`remember`]), so each lane gets the same bits.

use super::{
    Axis, Ellipse, Form, HALLEY_CAP, HALLEY_TOL, TAYLOR_FINISH, evaluate, halley_step, overshoots,
    remember, screened_out, square, taylor, unit,
};
use jamkit_core::{
    ContactLanes, FastContacts, MAX_ROT, MEMO_LEN, Pair, PairLanes, PairMemo, Shape,
};

/// The most steps of Halley's iteration [`Ellipse::exact_warm_lanes`]
/// takes side by side (a pair that needs more goes through the scalar
/// solve); from a memo most pairs take one.
pub const WARM_LANE_STEPS: u32 = 4;

const _: () = assert!(WARM_LANE_STEPS < HALLEY_CAP);

/// What a lane's pair has come to: no contact (its memo as it was), a
/// contact found side by side, the scalar solve, or another step.
const NONE: u8 = 0;
const SOLVED: u8 = 1;
const SCALAR: u8 = 2;
const GOING: u8 = 3;

/// Numbers per going-on pair ([`Ellipse::exact_warm_lanes`]): the
/// direction `v` (2), the last step's length, `g` and `|v|` at the
/// iterate before it, whether the step ended the iteration (1) or another
/// follows (0), the separation (2), and both bodies' quadratic forms
/// (`p`, `m`, `cos 2θ`, `sin 2θ`, 8).
const GO: usize = 16;

/// Numbers per pair of a further step: the gap, the normal (2), `H_i'`,
/// `H_j'`, the memo's first two numbers, and where the pair stands (the
/// first six of `GO`).
const FOUND: usize = 13;

/// The arrays of `W` numbers [`Ellipse::exact_warm_lanes`] keeps in its
/// scratch: `GO`, the memo's normal (2) and the memo of a solved pair (2).
const SCRATCH: usize = GO + 4;

impl Ellipse {
    /// The warm contacts of the first `len` of `W` pairs
    /// ([`FastContacts::contacts_warm_lanes`]): lane `l` gets
    /// [`Shape::contacts_warm`]'s contact with memo `memos[at[l]]` and
    /// leaves in it what that call leaves, bit for bit.
    ///
    /// A pass over the lanes with no branch computes the bounding test,
    /// the screen at the line of centres and the first step of Halley's
    /// iteration from the memo's normal with its Taylor finish, each the
    /// same operations in the same order as [`Ellipse::exact_gap_warm`];
    /// the pairs that go on (a step of 10⁻⁶ rad or more) take their
    /// further evaluations and steps side by side, four at a time, up to
    /// [`WARM_LANE_STEPS`] steps in all. The pairs these steps do not
    /// settle (no memo, a failed guard, more steps) go through
    /// [`Ellipse::exact_gap_warm`] one at a time, from the start.
    /// `scratch` is any vector (it grows to `SCRATCH` arrays; what it
    /// holds on entry does not matter).
    ///
    /// NOTE: each pass is straight-line code over plain arrays, so that
    /// the compiler vectorises it (square roots and divisions included);
    /// the scalar solve of a pair is a chain of dependent operations that
    /// leaves most of the core idle.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn exact_warm_lanes<const W: usize>(
        &self,
        pairs: &PairLanes<2, Axis, W>,
        len: usize,
        max_gap: f64,
        memos: &mut [PairMemo],
        at: &[u32; W],
        scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<2, W>,
    ) {
        let len = len.min(W);
        if scratch.len() < SCRATCH {
            scratch.resize(SCRATCH, [0.0; W]);
        }
        // Per lane: where the pair stands (`GO` numbers), the memo's
        // normal (`START..`) and the memo a solved pair leaves (`KEPT..`),
        // its first two numbers.
        let s: &mut [[f64; W]; SCRATCH] = (&mut scratch[..SCRATCH])
            .try_into()
            .expect("SCRATCH arrays make an array of SCRATCH");
        let (go, rest) = s.split_at_mut(GO);
        let (start, kept) = rest.split_at_mut(2);
        // The memo's normal relative to the line of centres (times a
        // length), and whether there is one.
        let mut has = [false; W];
        for l in 0..len {
            if let Some(m) = &memos[at[l] as usize] {
                (start[0][l], start[1][l]) = (m[0], m[1]);
                has[l] = true;
            }
        }
        let mut state = [NONE; W];
        for l in 0..W {
            let (x, y) = (pairs.r_ij[0][l], pairs.r_ij[1][l]);
            let r = pairs.r2[l].sqrt();
            // `bounded` and `screen`.
            let far = r - pairs.reach_i[l] - pairs.reach_j[l] > max_gap;
            let fi = self.form(pairs.size_i[l], &pairs.o_i[l]);
            let fj = self.form(pairs.size_j[l], &pairs.o_j[l]);
            let screened = screened_out(&fi, &fj, (x, y), r, max_gap);
            // `solve`'s warm start and `halley`'s first step.
            let (a0, a1) = (start[0][l], start[1][l]);
            let v0 = (x * a0 - y * a1, y * a0 + x * a1);
            let l2 = square(v0);
            let (cur, g3, thirds) = evaluate(&fi, &fj, (x, y), v0, l2);
            let len_v = l2.sqrt();
            let s = halley_step(&cur, g3, v0, len_v, f64::INFINITY, max_gap);
            let len_next = square(s.v).sqrt();
            let n = unit(s.v, len_next);
            let (gap, ji, jj) = taylor(&cur, thirds, s.step, len_v, n, (x, y));
            state[l] = if far | screened {
                NONE
            } else if !has[l] | (!s.ok & !s.apart) {
                SCALAR
            } else if s.apart {
                NONE
            } else if s.len < TAYLOR_FINISH {
                if gap > max_gap { NONE } else { SOLVED }
            } else {
                GOING
            };
            out.found[l] = state[l] == SOLVED;
            out.gap[l] = gap;
            out.grad_r[0][l] = n.0;
            out.grad_r[1][l] = n.1;
            out.grad_rot_i[0][l] = ji.d1;
            out.grad_rot_j[0][l] = jj.d1;
            for a in 1..MAX_ROT {
                out.grad_rot_i[a][l] = 0.0;
                out.grad_rot_j[a][l] = 0.0;
            }
            let m = remember(n, (x, y));
            (kept[0][l], kept[1][l]) = (m[0], m[1]);
            let now = [
                s.v.0,
                s.v.1,
                s.len,
                cur.g,
                len_v,
                if s.len < HALLEY_TOL { 1.0 } else { 0.0 },
                x,
                y,
                fi.p,
                fi.m,
                fi.c2,
                fi.s2,
                fj.p,
                fj.m,
                fj.c2,
                fj.s2,
            ];
            for (k, x) in now.into_iter().enumerate() {
                go[k][l] = x;
            }
        }
        // The going-on lanes, the first `count` of `origin`.
        let mut origin = [0usize; W];
        let mut count = 0;
        for l in 0..len {
            if state[l] == GOING {
                origin[count] = l;
                count += 1;
            }
        }
        let mut steps = 1;
        while count > 0 && steps < WARM_LANE_STEPS {
            // This pass takes step `steps` (after the evaluation the last
            // one asked for): the last the lanes take, where it is
            // `WARM_LANE_STEPS`.
            steps += 1;
            let last_step = steps == WARM_LANE_STEPS;
            let mut next_count = 0;
            // Blocks of `B` going-on lanes, copied out so that the pass over
            // a block has a constant length (whole vectors, no bounds).
            const B: usize = 4;
            for base in (0..count).step_by(B) {
                let mut block = [[0.0; B]; GO];
                for t in 0..B {
                    let l = origin[(base + t).min(count - 1)];
                    for (k, a) in go.iter().enumerate() {
                        block[k][t] = a[l];
                    }
                }
                let mut settled = [NONE; B];
                let mut results = [[0.0; B]; FOUND];
                for t in 0..B {
                    let g = |k: usize| block[k][t];
                    let v = (g(0), g(1));
                    let (len, cur_g, len_v, ends) = (g(2), g(3), g(4), g(5) != 0.0);
                    let (x, y) = (g(6), g(7));
                    let fi = Form {
                        p: g(8),
                        m: g(9),
                        c2: g(10),
                        s2: g(11),
                    };
                    let fj = Form {
                        p: g(12),
                        m: g(13),
                        c2: g(14),
                        s2: g(15),
                    };
                    let l2 = square(v);
                    let len_next = l2.sqrt();
                    let n = unit(v, len_next);
                    // The last step ended the iteration: the evaluation at
                    // the unit normal; else at `v`, for the next step.
                    let (at_v, at_l2) = if ends { (n, 1.0) } else { (v, l2) };
                    let (next, g3, thirds) = evaluate(&fi, &fj, (x, y), at_v, at_l2);
                    let climbs = !overshoots(len, next.g, cur_g, len_v, len_next);
                    let s = halley_step(&next, g3, v, len_next, len, max_gap);
                    let m_next = unit(s.v, square(s.v).sqrt());
                    let (gap, ji, jj) = taylor(&next, thirds, s.step, len_next, m_next, (x, y));
                    let (state, result) = if ends {
                        (
                            if next.g > max_gap { NONE } else { SOLVED },
                            [next.g, n.0, n.1, next.ji.d1, next.jj.d1],
                        )
                    } else {
                        (
                            if !climbs | (!s.ok & !s.apart) {
                                SCALAR
                            } else if s.apart {
                                NONE
                            } else if s.len < TAYLOR_FINISH {
                                if gap > max_gap { NONE } else { SOLVED }
                            } else if last_step {
                                SCALAR
                            } else {
                                GOING
                            },
                            [gap, m_next.0, m_next.1, ji.d1, jj.d1],
                        )
                    };
                    settled[t] = state;
                    let kept = remember((result[1], result[2]), (x, y));
                    // Where the pair stands for the next pass.
                    let stands = [
                        s.v.0,
                        s.v.1,
                        s.len,
                        next.g,
                        len_next,
                        if s.len < HALLEY_TOL { 1.0 } else { 0.0 },
                    ];
                    for (a, x) in results
                        .iter_mut()
                        .zip(result.into_iter().chain([kept[0], kept[1]]).chain(stands))
                    {
                        a[t] = x;
                    }
                }
                // The block's lanes, in order: their results, and the
                // lanes that go on at the front of `origin` (at or before
                // the places read so far).
                for t in 0..B.min(count - base) {
                    let l = origin[base + t];
                    state[l] = settled[t];
                    match settled[t] {
                        SOLVED => {
                            out.found[l] = true;
                            out.gap[l] = results[0][t];
                            out.grad_r[0][l] = results[1][t];
                            out.grad_r[1][l] = results[2][t];
                            out.grad_rot_i[0][l] = results[3][t];
                            out.grad_rot_j[0][l] = results[4][t];
                            (kept[0][l], kept[1][l]) = (results[5][t], results[6][t]);
                        }
                        GOING => {
                            for (k, a) in go.iter_mut().take(6).enumerate() {
                                a[l] = results[7 + k][t];
                            }
                            origin[next_count] = l;
                            next_count += 1;
                        }
                        _ => {}
                    }
                }
            }
            count = next_count;
        }
        for &l in &origin[..count] {
            state[l] = SCALAR;
        }
        for l in 0..len {
            let memo = &mut memos[at[l] as usize];
            match state[l] {
                SOLVED => {
                    let mut m = [0.0; MEMO_LEN];
                    (m[0], m[1]) = (kept[0][l], kept[1][l]);
                    *memo = Some(m);
                }
                SCALAR => {
                    out.found[l] = false;
                    let pair = Pair::new(
                        pairs.size_i[l],
                        pairs.o_i[l],
                        pairs.size_j[l],
                        pairs.o_j[l],
                        pairs.separation(l),
                    );
                    self.contacts_warm(&pair, max_gap, memo, |c| out.set(l, &c));
                }
                _ => {}
            }
        }
    }
}

/// The ellipse family's fast path: its warm exact gap a chunk of pairs at
/// a time ([`Ellipse::exact_warm_lanes`]).
impl FastContacts<2, Ellipse> for Ellipse {
    fn use_warm_lanes(_shape: &Ellipse) -> bool {
        true
    }

    #[inline(always)]
    fn contacts_warm_lanes<const W: usize>(
        shape: &Ellipse,
        pairs: &PairLanes<2, Axis, W>,
        len: usize,
        max_gap: f64,
        memos: &mut [PairMemo],
        at: &[u32; W],
        scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<2, W>,
    ) {
        shape.exact_warm_lanes(pairs, len, max_gap, memos, at, scratch, out);
    }
}
