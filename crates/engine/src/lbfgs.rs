//! L-BFGS: a quasi-Newton minimiser, inside FIRE's loop.
//!
//! Limited-memory BFGS (Nocedal & Wright, *Numerical Optimization*,
//! Algorithm 7.4) keeps the last `memory` pairs of steps `s = q_{k+1} − q_k`
//! and gradient changes `y = g_{k+1} − g_k` and builds the direction
//! `d = −H g` from them by the two-loop recursion, with the initial inverse
//! Hessian `H₀ = γ M⁻¹`: the bodies' inverse masses (1 per translation, the
//! inverse moments of inertia per rotation, the metric FIRE moves in), scaled
//! by `γ = s·y / y·M⁻¹y` of the newest pair. Unlike FIRE it has no inertia
//! to damp, and unlike the Newton finish it needs no Hessian and no positive
//! definite one: it minimises along soft directions and through indefinite
//! regions with a line search. An iteration costs one energy-and-gradient
//! evaluation when the full step is accepted, plus `O(memory · dof)`
//! arithmetic for the recursion.
//!
//! **Step.** `d` is scaled so that no coordinate moves by more than
//! [`LbfgsParams::max_step`] (lengths, radians). The neighbour list stays
//! valid whatever the step (the scene checks its drift against the skin at
//! every evaluation and rebuilds when needed); the cap keeps an early,
//! poorly scaled direction from throwing bodies through each other.
//!
//! **Line search.** Backtracking from `α = 1` by the minimum of the
//! quadratic through `V(0)`, `V'(0)` and `V(α)` (clamped to `[0.1 α,
//! 0.5 α]`), until the Armijo condition `V(α) ≤ V(0) + 10⁻⁴ α g·d` holds,
//! or, where the energy change is within its round-off
//! (`|V(α) − V(0)| ≤ 10⁻⁸ |V(0)|`: close to a jammed minimum the energy's
//! decrease is hidden by the round-off of gaps computed as differences of
//! numbers of order one, see [`crate::newton`]), its derivative form
//! `g(α)·d ≤ (1 − 2·10⁻⁴) |g·d|` (Hager & Zhang's approximate Wolfe
//! condition, exact for a quadratic). A pair with `s·y ≤ 0` (negative
//! curvature along the step) is not stored. Moves go back and forth by
//! differences of `α`, so a backtrack costs no neighbour-list rebuild.
//!
//! **Giving up.** When no step is accepted, the memory is cleared and the
//! search tried again from `d = −M⁻¹g`; when that fails too, L-BFGS hands
//! the minimisation back to FIRE (from rest), whose next L-BFGS attempt
//! comes after twice as many FIRE steps as before. The stopping criteria
//! are FIRE's ([`crate::FireParams::stop`]).

use crate::objective::{Objective, StopReason};
use crate::precon::{BlockMasses, PreconParams};
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};

/// Settings of the L-BFGS minimiser (`minimizer.lbfgs`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LbfgsParams {
    /// FIRE steps of a minimisation before L-BFGS takes over (`0`: L-BFGS
    /// from the start, FIRE only where it gives up); doubled after every
    /// attempt that gives up.
    pub after: u64,
    /// Pairs `(s, y)` kept.
    pub memory: u32,
    /// Largest change of any coordinate in one iteration (lengths, radians).
    pub max_step: f64,
    /// `true`: only in the jamming search's minimisations that start from a
    /// decompressed jammed state (as `masses: Blocks((jammed_only: true))`);
    /// every other minimisation is FIRE's alone.
    pub jammed_only: bool,
    /// `true`: `H₀ = γ M⁻¹` with `M` each body's own block of the stiffness
    /// matrix ([`crate::precon`], at its default floor), rebuilt at the
    /// start of every attempt and every `refresh` iterations, instead of
    /// the bodies' inverse masses. The objective must give its stiffness
    /// blocks (else the plain masses).
    pub blocks: bool,
    /// Iterations between rebuilds of the blocks (with `blocks: true`).
    pub refresh: u64,
}

impl Default for LbfgsParams {
    fn default() -> Self {
        Self {
            after: 0,
            memory: 8,
            max_step: 0.05,
            jammed_only: false,
            blocks: false,
            refresh: 100,
        }
    }
}

/// Whether FIRE hands its minimisations to L-BFGS (`minimizer.lbfgs`).
///
/// Three states, so that an experiment that leaves the field out can get
/// its family's choice and one that writes `lbfgs: None` gets FIRE alone:
///
/// | in the file | state |
/// |---|---|
/// | left out | `Family` |
/// | `None` | `Off` |
/// | `(…)` or `Some((…))` | `On(…)` |
///
/// [`crate::FireParams::for_family`] resolves `Family` to `On((after: 0,
/// blocks: true))` where the family says so
/// ([`jamkit_core::Policy::lbfgs_blocks`], with FIRE) and to
/// `Off` elsewhere; FIRE runs an unresolved `Family` as `Off`. Written
/// back as read (`Family` left out, `Off` as `None`), so that an
/// experiment round-trips through `--set`.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum LbfgsChoice {
    /// The family's choice (the field left out).
    #[default]
    Family,
    /// No L-BFGS: FIRE alone (`lbfgs: None`).
    Off,
    /// L-BFGS with these settings.
    On(LbfgsParams),
}

impl LbfgsChoice {
    /// The settings L-BFGS runs with, if it runs (`Family` and `Off`: none).
    pub fn params(&self) -> Option<&LbfgsParams> {
        match self {
            LbfgsChoice::On(p) => Some(p),
            LbfgsChoice::Family | LbfgsChoice::Off => None,
        }
    }

    /// `Family` (left out of written settings).
    pub fn is_family(&self) -> bool {
        *self == LbfgsChoice::Family
    }

    /// The family's default where it asks for L-BFGS: from the start, in
    /// the block metric, the other settings at their defaults.
    pub fn family_default() -> LbfgsParams {
        LbfgsParams {
            after: 0,
            blocks: true,
            ..LbfgsParams::default()
        }
    }
}

impl From<Option<LbfgsParams>> for LbfgsChoice {
    fn from(o: Option<LbfgsParams>) -> Self {
        o.map_or(LbfgsChoice::Off, LbfgsChoice::On)
    }
}

impl Serialize for LbfgsChoice {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        // `Family` is written by leaving the field out (`FireParams`'
        // `skip_serializing_if`); any value written for it would read back
        // as `Off` or `On`, so writing it alone is an error, not a change.
        match self {
            LbfgsChoice::Family => Err(serde::ser::Error::custom(
                "minimizer.lbfgs: the family's choice is written by leaving the field out",
            )),
            LbfgsChoice::Off => s.serialize_none(),
            LbfgsChoice::On(p) => s.serialize_some(p),
        }
    }
}

impl<'de> Deserialize<'de> for LbfgsChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Option::<LbfgsParams>::deserialize(d).map(LbfgsChoice::from)
    }
}

impl LbfgsParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(1..=100).contains(&self.memory) {
            return Err(Error::invalid(
                format!("{prefix}.memory"),
                self.memory,
                "must lie between 1 and 100 (pairs of steps kept)",
            ));
        }
        if self.refresh == 0 {
            return Err(Error::invalid(
                format!("{prefix}.refresh"),
                0,
                "must be at least 1 (iterations between rebuilds of the blocks)",
            ));
        }
        crate::objective::require_positive_finite(prefix, "max_step", self.max_step)
    }
}

/// How an L-BFGS attempt ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LbfgsEnd {
    /// A stopping criterion holds.
    Converged(StopReason),
    /// Back to FIRE (no step accepted, or the evaluation budget spent).
    GaveUp,
}

/// Sufficient-decrease constant of the Armijo condition.
const ARMIJO: f64 = 1e-4;
/// Relative change of the energy below which it is taken as round-off.
const ENERGY_NOISE: f64 = 1e-8;
/// Trial steps per line search.
const MAX_TRIES: u32 = 30;

/// Work buffers of L-BFGS, kept across minimisations.
#[derive(Clone, Debug, Default)]
pub(crate) struct LbfgsWork {
    /// Ring buffers of the last pairs, `s` and `y`, and `1 / s·y`.
    s: Vec<Vec<f64>>,
    y: Vec<Vec<f64>>,
    rho: Vec<f64>,
    coef: Vec<f64>,
    /// Pairs stored, and where the next one goes.
    stored: usize,
    next: usize,
    direction: Vec<f64>,
    dq: Vec<f64>,
    trial: Vec<f64>,
    inv_m: Vec<f64>,
    scratch: Vec<f64>,
    /// Energies of the accepted states (tests only).
    #[cfg(test)]
    accepted: Vec<f64>,
}

/// The result of one attempt: how it ended, iterations (accepted steps),
/// energy-and-gradient evaluations, and the energy and `Σ g²` of the state
/// it leaves (whose gradient is in `g`).
pub(crate) struct LbfgsRun {
    pub end: LbfgsEnd,
    #[cfg_attr(not(test), allow(dead_code))]
    pub iterations: u64,
    pub evaluations: u64,
    pub energy: f64,
    pub force_sq: f64,
}

impl LbfgsWork {
    fn clear(&mut self) {
        self.stored = 0;
        self.next = 0;
    }

    /// `direction = −H g` by the two-loop recursion, `H₀ = γ M⁻¹` (the
    /// block masses `blocks` when given, else the bodies' own).
    fn direction(&mut self, g: &[f64], blocks: Option<&BlockMasses>) {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time); same code.
            return unsafe { self.direction_avx2(g, blocks) };
        }
        self.direction_portable(g, blocks)
    }

    /// [`LbfgsWork::direction_portable`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    unsafe fn direction_avx2(&mut self, g: &[f64], blocks: Option<&BlockMasses>) {
        self.direction_portable(g, blocks)
    }

    #[inline(always)]
    fn direction_portable(&mut self, g: &[f64], blocks: Option<&BlockMasses>) {
        let m = self.s.len();
        let d = &mut self.direction;
        d.clear();
        d.extend_from_slice(g);
        // Newest to oldest.
        for k in 0..self.stored {
            let i = (self.next + m - 1 - k) % m;
            let a = self.rho[i] * dot(&self.s[i], d);
            self.coef[i] = a;
            for (x, y) in d.iter_mut().zip(&self.y[i]) {
                *x -= a * y;
            }
        }
        let newest = (self.stored > 0).then(|| (self.next + m - 1) % m);
        let gamma = match (newest, blocks) {
            (Some(i), None) => 1.0 / (self.rho[i] * weighted_sq(&self.y[i], &self.inv_m)),
            (Some(i), Some(b)) => {
                let my = &mut self.scratch;
                my.resize(d.len(), 0.0);
                b.apply_inverse(&self.y[i], my);
                1.0 / (self.rho[i] * dot(&self.y[i], my))
            }
            (None, _) => 1.0,
        };
        match blocks {
            None => {
                for (x, w) in d.iter_mut().zip(&self.inv_m) {
                    *x *= gamma * w;
                }
            }
            Some(b) => {
                let md = &mut self.scratch;
                md.resize(d.len(), 0.0);
                b.apply_inverse(d, md);
                for (x, y) in d.iter_mut().zip(md.iter()) {
                    *x = gamma * y;
                }
            }
        }
        // Oldest to newest.
        for k in (0..self.stored).rev() {
            let i = (self.next + m - 1 - k) % m;
            let b = self.rho[i] * dot(&self.y[i], d);
            let c = self.coef[i] - b;
            for (x, s) in d.iter_mut().zip(&self.s[i]) {
                *x += c * s;
            }
        }
        for x in d.iter_mut() {
            *x = -*x;
        }
    }

    /// Store `s = α d` and `y = g(α) − g_old` (`g(α)` in `trial`) when
    /// `s·y > 0`.
    fn push(&mut self, alpha: f64, g_old: &[f64]) {
        let m = self.s.len();
        let i = self.next;
        let (s, y) = (&mut self.s[i], &mut self.y[i]);
        s.clear();
        s.extend(self.direction.iter().map(|d| alpha * d));
        y.clear();
        y.extend(self.trial.iter().zip(g_old).map(|(a, b)| a - b));
        let sy = dot(s, y);
        if sy > 0.0 && sy.is_finite() {
            self.rho[i] = 1.0 / sy;
            self.next = (i + 1) % m;
            self.stored = (self.stored + 1).min(m);
        }
    }
}

/// `Σ w y²`, as [`dot`].
#[inline(always)]
fn weighted_sq(y: &[f64], w: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    for (y4, w4) in y.chunks_exact(4).zip(w.chunks_exact(4)) {
        for l in 0..4 {
            lanes[l] += y4[l] * y4[l] * w4[l];
        }
    }
    let tail = y.len() / 4 * 4;
    for a in tail..y.len() {
        lanes[0] += y[a] * y[a] * w[a];
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// `a·b` with four independent partial sums (one accumulator would
/// serialise the sum on the adder's latency: the recursion's dot products
/// then cost about as much as an evaluation of a disk packing).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            lanes[l] += x[l] * y[l];
        }
    }
    for (x, y) in ra.iter().zip(rb) {
        lanes[0] += x * y;
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// L-BFGS iterations from the current state of `obj` (energy `energy`,
/// gradient `g`) until `stop(V, Σ g², g)` holds, the attempt gives up, or
/// `budget` evaluations are spent; the work buffers and the block masses
/// (rebuilt with `blocks: true`) are the minimiser's. On return `g` holds
/// the gradient of the state `obj` is left in.
pub(crate) fn attempt<O: Objective>(
    obj: &mut O,
    g: &mut [f64],
    mut energy: f64,
    params: &LbfgsParams,
    (w, blocks): (&mut LbfgsWork, &mut BlockMasses),
    budget: u64,
    stop: impl Fn(f64, f64, &[f64]) -> Option<StopReason>,
) -> Result<LbfgsRun> {
    let n = g.len();
    let m = params.memory as usize;
    w.s.resize_with(m, Vec::new);
    w.y.resize_with(m, Vec::new);
    w.s.truncate(m);
    w.y.truncate(m);
    w.rho.resize(m, 0.0);
    w.coef.resize(m, 0.0);
    w.trial.resize(n, 0.0);
    w.inv_m.clear();
    w.inv_m.extend_from_slice(obj.inverse_masses());
    w.clear();
    #[cfg(test)]
    w.accepted.clear();
    let mut force_sq = dot(g, g);
    let (mut iterations, mut evaluations) = (0u64, 0u64);
    let precon = PreconParams::default();
    let mut blocked = false;
    let run = |end, iterations, evaluations, energy, force_sq| {
        Ok(LbfgsRun {
            end,
            iterations,
            evaluations,
            energy,
            force_sq,
        })
    };
    // Line searches failed in a row (the second from `d = −M⁻¹g`).
    let mut failures = 0;
    loop {
        if evaluations >= budget {
            return run(LbfgsEnd::GaveUp, iterations, evaluations, energy, force_sq);
        }
        if params.blocks && iterations.is_multiple_of(params.refresh) {
            blocked = blocks.rebuild(obj, &w.inv_m, &precon);
        }
        w.direction(g, blocked.then_some(&*blocks));
        let mut slope = dot(g, &w.direction);
        if !(slope < 0.0) {
            if w.stored == 0 {
                return run(LbfgsEnd::GaveUp, iterations, evaluations, energy, force_sq);
            }
            // Not a descent direction: forget the pairs.
            w.clear();
            continue;
        }
        let largest = w.direction.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if largest > params.max_step {
            let cap = params.max_step / largest;
            w.direction.iter_mut().for_each(|d| *d *= cap);
            slope *= cap;
        }
        // Backtracking line search; `moved` is where the state stands.
        let (mut alpha, mut moved) = (1.0, 0.0);
        let mut accepted = None;
        for _ in 0..MAX_TRIES {
            if evaluations >= budget {
                break;
            }
            w.dq.clear();
            w.dq.extend(w.direction.iter().map(|d| (alpha - moved) * d));
            obj.displace(&w.dq);
            moved = alpha;
            let e = obj.energy_gradient(&mut w.trial);
            evaluations += 1;
            let f = dot(&w.trial, &w.trial);
            if e.is_finite() && f.is_finite() {
                let armijo = e <= energy + ARMIJO * alpha * slope;
                let in_noise = (e - energy).abs() <= ENERGY_NOISE * energy.abs();
                let approximate =
                    in_noise && dot(&w.trial, &w.direction) <= -(1.0 - 2.0 * ARMIJO) * slope;
                if armijo || approximate {
                    accepted = Some((e, f));
                    break;
                }
                // The minimum of the quadratic through V(0), V'(0), V(α).
                let curvature = e - energy - slope * alpha;
                let best = if curvature > 0.0 {
                    -slope * alpha * alpha / (2.0 * curvature)
                } else {
                    0.5 * alpha
                };
                alpha = best.clamp(0.1 * alpha, 0.5 * alpha);
            } else {
                alpha *= 0.5;
            }
        }
        let Some((e, f)) = accepted else {
            // Back to where the search started.
            w.dq.clear();
            w.dq.extend(w.direction.iter().map(|d| -moved * d));
            obj.displace(&w.dq);
            energy = obj.energy_gradient(g);
            evaluations += 1;
            force_sq = dot(g, g);
            failures += 1;
            if failures >= 2 || w.stored == 0 {
                return run(LbfgsEnd::GaveUp, iterations, evaluations, energy, force_sq);
            }
            w.clear();
            continue;
        };
        failures = 0;
        iterations += 1;
        w.push(alpha, g);
        g.copy_from_slice(&w.trial);
        energy = e;
        force_sq = f;
        #[cfg(test)]
        w.accepted.push(energy);
        if let Some(reason) = stop(energy, force_sq, g) {
            return run(
                LbfgsEnd::Converged(reason),
                iterations,
                evaluations,
                energy,
                force_sq,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fire::{Fire, FireParams};
    // The Newton finish's test well: `V = Σ_a k_a (x_a − 1)² / 2 + Σ_a
    // (x_a − x_{a+1})⁴ / 4`, stiffnesses over four decades, `V = 0` at `x = 1`.
    use crate::newton::tests::{Well, well};

    /// Run one attempt to `Σ g² < tol` (no energy criterion).
    fn run(obj: &mut impl Objective, params: &LbfgsParams, tol: f64) -> (LbfgsRun, Vec<f64>) {
        let mut g = vec![0.0; obj.dof()];
        let energy = obj.energy_gradient(&mut g);
        let mut w = LbfgsWork::default();
        let out = attempt(
            obj,
            &mut g,
            energy,
            params,
            (&mut w, &mut BlockMasses::default()),
            100_000,
            |_, f, _| (f < tol).then_some(StopReason::Force),
        )
        .unwrap();
        let mut accepted = vec![energy];
        accepted.extend_from_slice(&w.accepted);
        (out, accepted)
    }

    /// The full first step overshoots: on `V = 10 x²/2` from `x = 1` the
    /// step `d = −M⁻¹ g = −10` lands at `x = −9`, `V = 405 > 5`; the line
    /// search must reject it and take the minimum of the quadratic through
    /// `V(0)`, `V'(0)` and `V(1)`, `α = 0.1`, which is the exact minimum.
    #[test]
    fn the_line_search_backtracks_when_the_full_step_overshoots() {
        let mut q = Well {
            x: vec![1.0 + 1.0],
            k: vec![10.0],
            inv_m: vec![1.0],
            saved: Vec::new(),
        };
        // (x − 1 = 1: the same as x = 1 in V = 10 x²/2.)
        let params = LbfgsParams {
            max_step: 100.0,
            ..LbfgsParams::default()
        };
        let (out, energies) = run(&mut q, &params, 1e-20);
        assert_eq!(out.end, LbfgsEnd::Converged(StopReason::Force));
        assert_eq!(out.iterations, 1, "{:?}", energies);
        // One rejected trial (x = −9) and the accepted one.
        assert_eq!(out.evaluations, 2);
        assert!((q.x[0] - 1.0).abs() < 1e-12, "{:?}", q.x);
        assert_eq!(energies, vec![5.0, 0.0]);
    }

    /// L-BFGS reaches the force criterion on the ill-conditioned quartic
    /// well, and no accepted step raises the energy. Tolerance: the line
    /// search accepts a step whose energy change is within `10⁻⁸ |V|`
    /// (round-off, see the module's docs) on its derivative, so an accepted
    /// energy may exceed the previous one by at most that.
    #[test]
    fn lbfgs_minimises_a_quartic_well_and_the_energy_never_increases() {
        for blocks in [false, true] {
            let params = LbfgsParams {
                blocks,
                ..LbfgsParams::default()
            };
            let mut w = well();
            let (out, energies) = run(&mut w, &params, 1e-24);
            assert_eq!(out.end, LbfgsEnd::Converged(StopReason::Force), "{blocks}");
            assert!(out.iterations > 1 && out.evaluations >= out.iterations);
            assert!(w.x.iter().all(|x| (x - 1.0).abs() < 1e-6), "{:?}", w.x);
            for pair in energies.windows(2) {
                assert!(
                    pair[1] <= pair[0] + ENERGY_NOISE * pair[0].abs(),
                    "blocks {blocks}: the energy rose from {:e} to {:e}",
                    pair[0],
                    pair[1]
                );
            }
        }
    }

    /// Inside FIRE's loop: `after: 0` minimises with L-BFGS alone (no FIRE
    /// step), and its evaluations are counted; a budget of `max_steps`
    /// evaluations that cannot suffice ends in the usual error.
    #[test]
    fn fire_hands_the_minimisation_to_lbfgs() {
        let params = FireParams {
            energy_tol: 1e-300,
            force_tol: 1e-24,
            newton: None,
            lbfgs: LbfgsChoice::On(LbfgsParams::default()),
            ..FireParams::paper()
        };
        let mut w = well();
        let out = Fire::new(params.clone()).minimize(&mut w).unwrap();
        assert_eq!(out.reason, StopReason::Force);
        assert_eq!(out.steps, 0);
        assert!(out.lbfgs_evaluations > 0 && out.force_sq < 1e-24, "{out:?}");
        let mut w = well();
        let capped = Fire::new(FireParams {
            max_steps: 5,
            ..params
        })
        .minimize(&mut w);
        assert!(
            matches!(capped, Err(Error::NotConverged { steps: 5, .. })),
            "{capped:?}"
        );
    }

    #[test]
    fn bad_settings_are_named() {
        let bad = [
            (
                LbfgsParams {
                    memory: 0,
                    ..LbfgsParams::default()
                },
                "minimizer.lbfgs.memory",
            ),
            (
                LbfgsParams {
                    max_step: f64::NAN,
                    ..LbfgsParams::default()
                },
                "minimizer.lbfgs.max_step",
            ),
            (
                LbfgsParams {
                    refresh: 0,
                    ..LbfgsParams::default()
                },
                "minimizer.lbfgs.refresh",
            ),
        ];
        for (params, field) in bad {
            let fire = FireParams {
                lbfgs: LbfgsChoice::On(params),
                ..FireParams::default()
            };
            let e = fire.validate("minimizer").unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
        assert!(LbfgsParams::default().validate("minimizer.lbfgs").is_ok());
    }
}
