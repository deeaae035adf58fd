//! A second-order finish for FIRE: Newton steps with the analytic Hessian.
//!
//! Above jamming a minimisation ends near a minimum where the energy is
//! close to quadratic, and FIRE — a first-order method — crawls there along
//! the softest modes (for near-disks, the rotations that only the contact
//! forces' prestress holds, with eigenvalues of the order of the pressure).
//! Newton's method converges on such a minimum in a handful of iterations
//! whatever its conditioning. FIRE does the rough part (it needs no
//! Hessian and copes with contacts opening and closing); after
//! [`NewtonParams::after`] FIRE steps without meeting a stopping criterion,
//! Newton iterations take over:
//!
//! ```text
//! (H + μ I) δ = −g,       q ← q + α δ,
//! ```
//!
//! with `H = ∂²V/∂q∂q` assembled sparse from the families' gap Hessians
//! (the same assembly as the spectrum's, every contact kept), factorised by
//! faer's sparse Cholesky, and `μ = shift · mean(diag H)` a small shift that
//! makes rattlers (zero rows) and the global translations (zero modes)
//! harmless: the gradient has no component along them, so the step has
//! none either.
//!
//! **Only at a minimum.** When `H + μI` is not positive definite, the state
//! sits near a saddle or is unjammed, with extended negative-curvature modes
//! (measured on disks at N = 512: the lowest eigenvalues −10⁻⁵ … −10⁻⁴
//! with participation ratios of 40–150 bodies). Newton steps with a larger
//! shift crawl there (they took 880 iterations on a packing of N = 1024
//! disks, twice FIRE's time); FIRE escapes better. So the attempt gives up
//! at once and FIRE goes on.
//!
//! **Plateaus** ([`crate::FireParams::escape_plateaus`]). FIRE leaves a
//! saddle only as fast as its unstable mode grows, `∝ exp(√|λ| t)`: near-
//! disks 0.002 below φ_J (N = 1024, n = 2, Δ = 0.1) sat at V/N =
//! 3.2·10⁻¹³ for 100 000 FIRE steps with `λ/d̄` between `−2.6·10⁻¹⁰` and
//! `−8.5·10⁻¹⁰`. Where an attempt finds `H + μI` not positive definite
//! ([`NewtonEnd::Indefinite`]), the minimisation has taken
//! [`PLATEAU_AFTER`] FIRE steps, and the energy is above [`PLATEAU_FALL`]
//! times its value at the attempt before, [`escape_plateau`] finds the
//! lowest mode as the saddle check does
//! ([`crate::saddle::negative_curvature`]), evaluates `V` along it on the
//! side where `V` falls to first order, at the largest coordinate changes
//! `max_step · 2⁻ᵏ` (`k < PLATEAU_TRIALS`), and moves [`PLATEAU_KICK`]
//! times as far as the lowest (at most `max_step`); FIRE goes on from
//! rest, with the next attempt `after` steps later. At most
//! [`PLATEAU_MOVES`] moves per minimisation. The lowest `V` along
//! the mode lay `~10⁻³` away there, where a contact closes, and a move to
//! it alone left the state on the plateau: the overshoot puts FIRE off
//! the saddle's neighbourhood, as the saddle escape's kick does
//! ([`crate::saddle`]). Where no attempt meets these conditions the
//! minimisation is the one without the escape, bit for bit.
//!
//! **Step acceptance.** `α` starts at 1 (after scaling `δ` so that no
//! coordinate moves by more than [`NewtonParams::max_step`]) and halves
//! until either the energy decreases by the Armijo amount
//! `V(q + αδ) ≤ V(q) + 10⁻⁴ α g·δ` or the squared force falls by 4. The
//! second rule is needed because close to the minimum the energy's
//! round-off (a gap `h ≈ 10⁻⁸` computed as a difference of numbers of
//! order one carries a relative error `10⁻⁸`) hides the decrease; since
//! `H` is positive definite it cannot lead to a saddle.
//!
//! **Giving up.** When no step is accepted, when over three iterations the
//! force has not halved nor the energy fallen (contacts opening and
//! closing), or after `max_iterations`, Newton hands back to FIRE, which
//! restarts from rest; the next attempt comes after twice as many FIRE
//! steps as the last. The stopping criteria are FIRE's, so a minimisation
//! ends in the same window of energy or force whichever method finished it.
//!
//! Iterations (counted in [`crate::MinimizeOutcome::newton_iterations`]) are
//! Hessian factorisations, including the ones that gave up.

use crate::objective::{Objective, StopReason};
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side, linalg::solvers::Solve};
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};

/// Settings of the Newton finish.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NewtonParams {
    /// FIRE steps of a minimisation before the first Newton attempt (the
    /// interval doubles after every attempt that gives up).
    pub after: u64,
    /// Newton iterations per attempt.
    pub max_iterations: u32,
    /// Shift `μ` of the Hessian, relative to the mean of its diagonal.
    pub shift: f64,
    /// Largest change of any coordinate in one iteration (lengths, radians).
    pub max_step: f64,
}

impl Default for NewtonParams {
    fn default() -> Self {
        Self {
            after: 2000,
            max_iterations: 50,
            shift: 1e-10,
            max_step: 0.05,
        }
    }
}

impl NewtonParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if self.after == 0 {
            return Err(Error::invalid(
                format!("{prefix}.after"),
                0,
                "must be at least 1 (FIRE steps before the first Newton iteration)",
            ));
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid(
                format!("{prefix}.max_iterations"),
                0,
                "must be at least 1",
            ));
        }
        if !(self.shift > 0.0 && self.shift < 1.0) {
            return Err(Error::invalid(
                format!("{prefix}.shift"),
                self.shift,
                "must lie strictly between 0 and 1 (relative to the mean diagonal of the Hessian)",
            ));
        }
        crate::objective::require_positive_finite(prefix, "max_step", self.max_step)
    }
}

/// How a Newton attempt ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NewtonEnd {
    /// A stopping criterion holds.
    Converged(StopReason),
    /// Back to FIRE.
    GaveUp,
    /// Back to FIRE: `H + μI` is not positive definite at the state the
    /// attempt leaves (whose Hessian is in the work buffers, for
    /// [`escape_plateau`]).
    Indefinite,
    /// The objective has no Hessian: FIRE alone, untouched.
    Unavailable,
}

/// Work buffers of the Newton finish, kept across minimisations.
#[derive(Clone, Debug, Default)]
pub(crate) struct NewtonWork {
    entries: Vec<(u32, u32, f64)>,
    triplets: Vec<Triplet<usize, usize, f64>>,
    diag: Vec<f64>,
    delta: Vec<f64>,
    dq: Vec<f64>,
    trial: Vec<f64>,
}

/// The result of one attempt: how it ended, iterations made, and the
/// energy and `Σ g²` of the state it leaves (whose gradient is in `g`).
pub(crate) struct NewtonRun {
    pub end: NewtonEnd,
    pub iterations: u64,
    pub energy: f64,
    pub force_sq: f64,
}

/// Newton iterations from the current state of `obj` (energy `energy`,
/// gradient `g`) until `stop(V, Σ g², g)` holds or the attempt gives up.
/// On return `g` holds the gradient of the state `obj` is left in.
pub(crate) fn attempt<O: Objective>(
    obj: &mut O,
    g: &mut [f64],
    mut energy: f64,
    newton: &NewtonParams,
    w: &mut NewtonWork,
    stop: impl Fn(f64, f64, &[f64]) -> Option<StopReason>,
) -> Result<NewtonRun> {
    let n = g.len();
    let mut iterations = 0;
    let mut force_sq: f64 = g.iter().map(|x| x * x).sum();
    // Squared force and energy three iterations back, for the progress test.
    let mut history = [(f64::INFINITY, f64::INFINITY); 3];
    let run = |end, iterations, energy, force_sq| {
        Ok(NewtonRun {
            end,
            iterations,
            energy,
            force_sq,
        })
    };
    while iterations < newton.max_iterations as u64 {
        w.entries.clear();
        if !obj.hessian_entries(&mut w.entries)? {
            return run(NewtonEnd::Unavailable, iterations, energy, force_sq);
        }
        // Not positive definite at the base shift: a saddle or an unjammed
        // state, where FIRE does better than shifted Newton steps.
        if !solve_shifted(n, g, newton.shift, w) {
            return run(NewtonEnd::Indefinite, iterations + 1, energy, force_sq);
        }
        // δ = −(H + μI)⁻¹ g, capped.
        let largest = w.delta.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let cap = if largest > newton.max_step {
            newton.max_step / largest
        } else {
            1.0
        };
        for d in w.delta.iter_mut() {
            *d *= -cap;
        }
        let slope: f64 = g.iter().zip(&w.delta).map(|(a, b)| a * b).sum();
        if !(slope < 0.0) {
            return run(NewtonEnd::GaveUp, iterations, energy, force_sq);
        }
        obj.save();
        w.trial.resize(n, 0.0);
        let mut alpha = 1.0;
        let mut accepted = None;
        for tries in 0..30 {
            if tries > 0 {
                obj.restore();
            }
            w.dq.clear();
            w.dq.extend(w.delta.iter().map(|d| alpha * d));
            obj.displace(&w.dq);
            let e = obj.energy_gradient(&mut w.trial);
            let f: f64 = w.trial.iter().map(|x| x * x).sum();
            if !(e.is_finite() && f.is_finite()) {
                alpha *= 0.5;
                continue;
            }
            let armijo = e <= energy + 1e-4 * alpha * slope;
            let force_drop = f < 0.25 * force_sq;
            if armijo || force_drop {
                accepted = Some((e, f));
                break;
            }
            alpha *= 0.5;
        }
        iterations += 1;
        let Some((e, f)) = accepted else {
            obj.restore();
            energy = obj.energy_gradient(g);
            return run(NewtonEnd::GaveUp, iterations, energy, force_sq);
        };
        g.copy_from_slice(&w.trial);
        energy = e;
        force_sq = f;
        if let Some(reason) = stop(energy, force_sq, g) {
            return run(NewtonEnd::Converged(reason), iterations, energy, force_sq);
        }
        // Progress: the force halved, or the energy fell (leaving a saddle,
        // or an unjammed state on its way to V = 0), over three iterations.
        let (f_back, e_back) = history[0];
        if iterations >= 3 && force_sq > 0.5 * f_back && energy > e_back - 1e-9 * e_back.abs() {
            return run(NewtonEnd::GaveUp, iterations, energy, force_sq);
        }
        history.rotate_left(1);
        history[2] = (force_sq, energy);
    }
    run(NewtonEnd::GaveUp, iterations, energy, force_sq)
}

/// Largest coordinate changes the plateau escape tries along the mode:
/// `max_step · 2⁻ᵏ`, `k = 0 … PLATEAU_TRIALS − 1` (down to `~5·10⁻⁸` at
/// the default `max_step`).
pub const PLATEAU_TRIALS: i32 = 21;

/// The plateau escape acts only in a minimisation that has taken at least
/// this many FIRE steps: minimisations of disks near φ_J (N = 1024) take
/// up to ~45 000 steps without a plateau, and a move there made them
/// longer.
pub const PLATEAU_AFTER: u64 = 50_000;

/// A minimisation sits on a plateau when its energy at a Newton attempt is
/// above this fraction of its energy at the attempt before.
pub const PLATEAU_FALL: f64 = 0.5;

/// The plateau escape moves a state at most this many times per
/// minimisation: a state can return to the same saddle after each move
/// (near-disks, n = 3, Δ = 0.1, N = 1024: V/N 4.18·10⁻¹¹, 4.32·10⁻¹¹,
/// 4.18·10⁻¹¹ at three attempts 2000 steps apart), and without a bound
/// the attempts would stay 2000 steps apart.
pub const PLATEAU_MOVES: u64 = 8;

/// The plateau escape moves this many times as far along the mode as the
/// lowest `V` of the amplitudes tried (at most `max_step`).
pub const PLATEAU_KICK: f64 = 16.0;

/// The plateau escape (module documentation): from the state a Newton
/// attempt left with [`NewtonEnd::Indefinite`], the lowest mode of its
/// Hessian (still in `w`) by [`crate::saddle::negative_curvature`] at the
/// shift `newton.shift`, and the move along it, on the side where `V`
/// falls to first order, [`PLATEAU_KICK`] times as far as the lowest `V`
/// of the amplitudes tried (at most `max_step`). `None` when no mode
/// curves below `−μ` (nothing moved); else `(V, moved)`, `g` holding the
/// gradient of the state left (moved: some amplitude lowers `V`; not
/// moved: the state restored).
pub(crate) fn escape_plateau<O: Objective>(
    obj: &mut O,
    g: &mut [f64],
    energy: f64,
    newton: &NewtonParams,
    w: &mut NewtonWork,
) -> Option<(f64, bool)> {
    let n = g.len();
    let Ok(Some((_, _, mode))) = crate::saddle::negative_curvature(n, &w.entries, newton.shift)
    else {
        return None;
    };
    let biggest = mode.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if !(biggest > 0.0) {
        return None;
    }
    // Unit largest component, on the side where g·d ≤ 0.
    let slope: f64 = g.iter().zip(&mode).map(|(a, b)| a * b).sum();
    let scale = if slope > 0.0 { -1.0 } else { 1.0 } / biggest;
    w.delta.clear();
    w.delta.extend(mode.iter().map(|x| x * scale));
    w.trial.resize(n, 0.0);
    obj.save();
    let mut best = (0.0, energy);
    for k in 0..PLATEAU_TRIALS {
        let amplitude = newton.max_step * 0.5f64.powi(k);
        w.dq.clear();
        w.dq.extend(w.delta.iter().map(|d| amplitude * d));
        obj.displace(&w.dq);
        let e = obj.energy_gradient(&mut w.trial);
        obj.restore();
        if e.is_finite() && e < best.1 {
            best = (amplitude, e);
        }
    }
    // Beyond the lowest V: off the saddle's neighbourhood, so that FIRE
    // does not slide back onto it (module documentation).
    let amplitude = (PLATEAU_KICK * best.0).min(newton.max_step);
    if best.0 > 0.0 {
        w.dq.clear();
        w.dq.extend(w.delta.iter().map(|d| amplitude * d));
        obj.displace(&w.dq);
    }
    Some((obj.energy_gradient(g), best.0 > 0.0))
}

/// Solve `(H + μI) x = g` into `w.delta` for the Hessian in `w.entries`,
/// with `μ = shift · mean(diag H)` (the mean over positive diagonal
/// entries). Returns `false` when the Cholesky factorisation fails (`H + μI`
/// not positive definite) or the solution is not finite.
fn solve_shifted(n: usize, g: &[f64], shift: f64, w: &mut NewtonWork) -> bool {
    let mu = shift * mean_positive_diagonal(n, &w.entries, &mut w.diag).unwrap_or(1.0);
    upper_triplets(&w.entries, &mut w.triplets);
    w.triplets.extend((0..n).map(|a| Triplet::new(a, a, mu)));
    let Some(llt) = sparse_cholesky(n, &w.triplets) else {
        return false;
    };
    let mut x = Mat::<f64>::from_fn(n, 1, |a, _| g[a]);
    llt.solve_in_place(x.as_mut());
    w.delta.clear();
    w.delta.extend((0..n).map(|a| x[(a, 0)]));
    w.delta.iter().all(|d| d.is_finite())
}

/// The mean `d̄` of the positive diagonal entries of the `n × n` matrix with
/// these entries (repeated pairs adding; `diag` is work space), or `None`
/// when there is none. The shift of the Newton finish and of the saddle
/// check is relative to it.
pub(crate) fn mean_positive_diagonal(
    n: usize,
    entries: &[(u32, u32, f64)],
    diag: &mut Vec<f64>,
) -> Option<f64> {
    diag.clear();
    diag.resize(n, 0.0);
    for &(r, c, v) in entries {
        if r == c {
            diag[r as usize] += v;
        }
    }
    let (sum, count) = diag
        .iter()
        .filter(|&&d| d > 0.0)
        .fold((0.0, 0usize), |(s, k), &d| (s + d, k + 1));
    (count > 0).then(|| sum / count as f64)
}

/// The upper triangle (`row ≤ column`) of these entries as faer's
/// triplets, into `upper` (cleared first), for [`sparse_cholesky`].
pub(crate) fn upper_triplets(
    entries: &[(u32, u32, f64)],
    upper: &mut Vec<Triplet<usize, usize, f64>>,
) {
    upper.clear();
    upper.extend(
        entries
            .iter()
            .filter(|&&(r, c, _)| r <= c)
            .map(|&(r, c, v)| Triplet::new(r as usize, c as usize, v)),
    );
}

/// The sparse Cholesky factorisation `L Lᵀ` of the symmetric `n × n`
/// matrix whose upper triangle is `upper` (`(row ≤ column, value)`;
/// repeated index pairs add), by faer's supernodal/simplicial `LLᵀ` with its
/// fill-reducing ordering; `None` when the matrix is not positive definite
/// (or the triplets are out of range). Used by the Newton finish and by
/// the moduli's sparse solve (`jamkit_observe::moduli`).
pub fn sparse_cholesky(n: usize, upper: &[Triplet<usize, usize, f64>]) -> Option<Llt<usize, f64>> {
    let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, upper).ok()?;
    m.sp_cholesky(Side::Upper).ok()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::fire::{Fire, FireParams};
    use crate::objective::StopReason;

    /// `V = Σ_a k_a (x_a − c_a)² / 2 + Σ_a (x_a − x_{a+1})⁴ / 4`: an
    /// anisotropic well (stiffnesses over four decades) with a quartic
    /// coupling, whose Hessian is tridiagonal.
    pub(crate) struct Well {
        pub(crate) x: Vec<f64>,
        pub(crate) k: Vec<f64>,
        pub(crate) inv_m: Vec<f64>,
        pub(crate) saved: Vec<f64>,
    }

    impl Objective for Well {
        fn dof(&self) -> usize {
            self.x.len()
        }
        fn bodies(&self) -> usize {
            1
        }
        fn inverse_masses(&self) -> &[f64] {
            &self.inv_m
        }
        fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
            let n = self.x.len();
            let mut e = 0.0;
            for a in 0..n {
                let d = self.x[a] - 1.0;
                e += 0.5 * self.k[a] * d * d;
                grad[a] = self.k[a] * d;
            }
            for a in 0..n - 1 {
                let d = self.x[a] - self.x[a + 1];
                e += 0.25 * d.powi(4);
                grad[a] += d.powi(3);
                grad[a + 1] -= d.powi(3);
            }
            e
        }
        fn displace(&mut self, dq: &[f64]) {
            self.x.iter_mut().zip(dq).for_each(|(x, d)| *x += d);
        }
        fn phi(&self) -> f64 {
            0.0
        }
        fn hessian_entries(&mut self, e: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
            let n = self.x.len();
            for a in 0..n {
                e.push((a as u32, a as u32, self.k[a]));
            }
            for a in 0..n - 1 {
                let c = 3.0 * (self.x[a] - self.x[a + 1]).powi(2);
                let (i, j) = (a as u32, a as u32 + 1);
                e.extend([(i, i, c), (j, j, c), (i, j, -c), (j, i, -c)]);
            }
            Ok(true)
        }
        fn save(&mut self) {
            self.saved.clone_from(&self.x);
        }
        fn restore(&mut self) {
            self.x.clone_from(&self.saved);
        }
        fn stiffness_blocks(&mut self, blocks: &mut Vec<f64>) -> bool {
            // One body: its block is the harmonic part of the Hessian.
            crate::fire::tests::diagonal_block(&self.k, blocks)
        }
    }

    pub(crate) fn well() -> Well {
        Well {
            x: vec![0.0, 2.0, -1.0, 0.5, 3.0, 1.5],
            k: vec![1e-4, 1e-3, 1e-2, 0.1, 1.0, 3.0],
            inv_m: vec![1.0; 6],
            saved: Vec::new(),
        }
    }

    /// Newton finishes what FIRE started: the force criterion holds, in a
    /// few iterations, at the minimum `x = 1` (where the quartic coupling
    /// vanishes); FIRE alone needs ten times the steps on the softest
    /// stiffness (10⁻⁴).
    #[test]
    fn newton_finishes_an_ill_conditioned_well() {
        let params = FireParams {
            energy_tol: 1e-300,
            force_tol: 1e-24,
            newton: Some(NewtonParams {
                after: 50,
                ..NewtonParams::default()
            }),
            ..FireParams::paper()
        };
        let mut w = well();
        let out = Fire::new(params.clone()).minimize(&mut w).unwrap();
        assert_eq!(out.reason, StopReason::Force);
        assert!(
            out.newton_iterations > 0 && out.newton_iterations < 30,
            "{out:?}"
        );
        assert!(w.x.iter().all(|x| (x - 1.0).abs() < 1e-6), "{:?}", w.x);
        let mut fire_only = well();
        let plain = Fire::new(FireParams {
            newton: None,
            ..params
        })
        .minimize(&mut fire_only)
        .unwrap();
        assert_eq!(plain.newton_iterations, 0);
        assert!(
            plain.steps > 10 * out.steps,
            "FIRE {} against {}",
            plain.steps,
            out.steps
        );
    }

    /// The shifted solve on a known system: `H = [[2, −1], [−1, 2]]`.
    #[test]
    fn shifted_solve_solves() {
        let mut w = NewtonWork {
            entries: vec![(0, 0, 2.0), (1, 1, 2.0), (0, 1, -1.0), (1, 0, -1.0)],
            ..NewtonWork::default()
        };
        assert!(solve_shifted(2, &[1.0, 0.0], 1e-12, &mut w));
        // H⁻¹ = [[2, 1], [1, 2]] / 3.
        assert!((w.delta[0] - 2.0 / 3.0).abs() < 1e-10 && (w.delta[1] - 1.0 / 3.0).abs() < 1e-10);
        // Indefinite: refused.
        w.entries = vec![(0, 0, 1.0), (1, 1, -1.0)];
        assert!(!solve_shifted(2, &[1.0, 1.0], 1e-12, &mut w));
    }

    /// `V = Σ_a k_a x_a² / 2 + c²/4b − c y²/2 + b y⁴/4` (`x` the first
    /// coordinates, `y` the last): a saddle at `y = 0` whose one unstable
    /// mode, of curvature `−c`, leads to the minima `V = 0` at
    /// `y = ±√(c/b)`.
    struct Plateau {
        q: Vec<f64>,
        k: Vec<f64>,
        c: f64,
        b: f64,
        inv_m: Vec<f64>,
        saved: Vec<f64>,
    }

    impl Objective for Plateau {
        fn dof(&self) -> usize {
            self.q.len()
        }
        fn bodies(&self) -> usize {
            1
        }
        fn inverse_masses(&self) -> &[f64] {
            &self.inv_m
        }
        fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
            let last = self.q.len() - 1;
            let mut e = 0.0;
            for a in 0..last {
                e += 0.5 * self.k[a] * self.q[a] * self.q[a];
                grad[a] = self.k[a] * self.q[a];
            }
            let y = self.q[last];
            e +=
                self.c * self.c / (4.0 * self.b) - 0.5 * self.c * y * y + 0.25 * self.b * y.powi(4);
            grad[last] = -self.c * y + self.b * y.powi(3);
            e
        }
        fn displace(&mut self, dq: &[f64]) {
            self.q.iter_mut().zip(dq).for_each(|(x, d)| *x += d);
        }
        fn phi(&self) -> f64 {
            0.0
        }
        fn hessian_entries(&mut self, e: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
            let last = self.q.len() - 1;
            for a in 0..last {
                e.push((a as u32, a as u32, self.k[a]));
            }
            let y = self.q[last];
            e.push((last as u32, last as u32, -self.c + 3.0 * self.b * y * y));
            Ok(true)
        }
        fn save(&mut self) {
            self.saved.clone_from(&self.q);
        }
        fn restore(&mut self) {
            self.q.clone_from(&self.saved);
        }
    }

    /// `c = b` (minima at `y = ±1`), started where the saddle's force is
    /// `c y = 10⁻¹²` (above the force test's `√10⁻²⁵`): FIRE alone leaves
    /// it only as fast as the unstable mode grows, `∝ exp(√c t)`. At
    /// `c = 10⁻⁸` (`y = 10⁻⁴`) that takes about 92 000 time units, longer
    /// than the escape's [`PLATEAU_AFTER`] steps; at `c = 10⁻⁶`
    /// (`y = 10⁻⁶`) about 14 000.
    fn plateau(c: f64) -> Plateau {
        Plateau {
            q: vec![0.3, -0.2, 1e-12 / c],
            k: vec![1.0, 0.1],
            c,
            b: c,
            inv_m: vec![1.0; 3],
            saved: Vec::new(),
        }
    }

    /// The escape's mode is the saddle's unstable direction: the lowest
    /// eigenvector of `H = diag(1, 0.1, −c)` is the `y` axis, found to
    /// `10⁻⁹` (inverse iteration from a vector with components along every
    /// axis, converging by `(c − c/2)/(0.1 + c/2)` per iteration at the
    /// shift that first factorises), with Rayleigh quotient `−c` to
    /// `10⁻⁶` relative (the iteration's stopping rule).
    #[test]
    fn the_plateau_mode_is_the_unstable_direction() {
        let mut p = plateau(1e-8);
        let mut entries = Vec::new();
        p.hessian_entries(&mut entries).unwrap();
        let (rho, _, mode) = crate::saddle::negative_curvature(3, &entries, 1e-10)
            .unwrap()
            .expect("a saddle");
        assert!((rho + 1e-8).abs() < 1e-14, "{rho}");
        assert!(mode[2].abs() > 1.0 - 1e-9, "{mode:?}");
    }

    /// On the plateau the escape moves along the unstable mode once the
    /// minimisation has taken [`PLATEAU_AFTER`] steps, and the minimisation
    /// ends at a minimum (`|y| = 1` to 10⁻⁴) in under three quarters of
    /// FIRE's steps with the escape off, which ends at a minimum too
    /// (measured: 137 248 against 250 358 steps; the way down from
    /// `|y| ~ max_step` to the minimum is as slow with and without it);
    /// on a plateau left in fewer steps than that (`c = 10⁻⁶`: 37 008 steps)
    /// and on a well whose Hessian is positive definite the minimisation is
    /// the same with it on and off, bit for bit.
    #[test]
    fn the_plateau_escape_leaves_a_long_plateau_faster_and_changes_nothing_elsewhere() {
        let run = |escape: bool, c: f64| {
            let mut p = plateau(c);
            let out = Fire::new(FireParams {
                escape_plateaus: escape,
                ..FireParams::fire_newton()
            })
            .minimize(&mut p)
            .unwrap();
            assert!(
                (p.q[2].abs() - 1.0).abs() < 1e-4,
                "{escape}: {:?} {out:?}",
                p.q
            );
            (out, p.q)
        };
        let (on, off) = (run(true, 1e-8).0, run(false, 1e-8).0);
        assert!(
            on.plateau_escapes >= 1 && off.plateau_escapes == 0,
            "{on:?} {off:?}"
        );
        assert!(
            4 * on.steps < 3 * off.steps,
            "{} against {}",
            on.steps,
            off.steps
        );
        let (short_on, short_off) = (run(true, 1e-6), run(false, 1e-6));
        assert_eq!(short_on.0.plateau_escapes, 0);
        assert_eq!(short_on, short_off);
        let well_run = |escape: bool| {
            let mut w = well();
            let out = Fire::new(FireParams {
                energy_tol: 1e-300,
                force_tol: 1e-24,
                escape_plateaus: escape,
                ..FireParams::fire_newton()
            })
            .minimize(&mut w)
            .unwrap();
            (out, w.x)
        };
        let (on, off) = (well_run(true), well_run(false));
        assert_eq!(on.0.plateau_escapes, 0);
        assert_eq!(on, off);
    }
}
