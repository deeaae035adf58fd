//! Protocols: how the packing fraction is changed between minimisations.
//!
//! **Jamming (the paper's).** Starting from the scene's packing fraction,
//! change `φ → φ + ε` by affine rescaling and minimise. While `V/N ≤ E_low`
//! after minimisation keep compressing; when `V/N > E_low`, decompress with
//! `ε → −ε/2`, and halve and reverse again every time `V/N` crosses `E_low`.
//! Stop when `E_low < V/N < E_high` (the paper: `10⁻¹⁶` and `2·10⁻¹⁶`).
//! That is [`JamSearch::Bisection`]; the default, [`JamSearch::Adaptive`],
//! decompresses a jammed state by the step its pressure predicts and lets
//! the compression step grow again where the jamming point has moved up.
//! Off the bisection, a minimisation whose `V/N` decay forecasts the low
//! edge may end there as a state short of the window (the unjamming
//! forecast, [`crate::fire`]).
//!
//! **To a packing fraction.** Step `φ` by `ε` towards the target (the last
//! step lands on it exactly), minimising after each step.
//!
//! **To a pressure.** The same bisection as for jamming, on the virial
//! pressure: compress while `P < P*`, reverse and halve on every crossing,
//! stop when `|P − P*| < tol · P*`.
//!
//! **Above the jamming point.** Jam, then compress by `δφ` to
//! `φ_J + δφ`. A compression can rearrange the packing into a state that
//! jams above `φ_J + δφ`; it is jammed again from there, at most `rejams`
//! times.

use crate::fire::{Fire, MinimizeOutcome};
use crate::objective::{Objective, StopReason};
use crate::scene::Scene;
use jamkit_core::{Error, Potential, Result, Shape};
use serde::{Deserialize, Serialize};

/// Parameters of the paper's jamming bisection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JamParams {
    /// Initial step `ε` of the packing fraction.
    pub eps: f64,
    /// Lower edge of the jamming window for `V/N`.
    pub energy_low: f64,
    /// Upper edge of the jamming window for `V/N`.
    pub energy_high: f64,
    /// Give up after this many changes of `φ`.
    pub max_density_steps: u64,
    /// How the search moves: the paper's halved steps (`Bisection`, the
    /// paper's path bit for bit), decompressions by the step that a jammed
    /// state's own pressure predicts (`Extrapolated`), and with them
    /// compressions whose step grows again where the jamming point has
    /// moved up (`Adaptive`, the default).
    pub search: JamSearch,
}

/// How [`jam`] moves from a jammed state towards the energy window.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum JamSearch {
    /// The paper's: reverse and halve `ε` on every crossing of `E_low`.
    Bisection,
    /// The paper's moves, except that a jammed state's decompression is
    /// the step to the window that `V/N ∝ (φ − φ_J)^α` predicts from its
    /// `V/N` and its pressure (module docs), where that step stays above
    /// the last unjammed `φ`.
    Extrapolated,
    /// `Extrapolated`, and a compression step that doubles (up to `eps`)
    /// from the [`REGROW_AFTER`]-th state in a row found short of the
    /// target: the search has then passed the `φ` where it last found the
    /// packing jammed, so a minimisation has moved the jamming point up
    /// (a rearrangement while unjamming), and the halved steps would creep
    /// to it. The default: its ensembles are the bisection's
    /// (docs/reports/minimizers.md, "The defaults against the paper's
    /// path").
    #[default]
    Adaptive,
}

impl JamSearch {
    /// `Bisection` (left out of a packing's recorded settings, as before the
    /// field existed, so that bisection packings made then still resume).
    pub fn is_bisection(&self) -> bool {
        *self == JamSearch::Bisection
    }
}

/// How many states in a row found short of the target, counting the one
/// that ended the last decompression, before [`JamSearch::Adaptive`]
/// doubles its compression step: after a crossing the step is half the
/// last one, so two such steps are back at the last jammed `φ`, and the
/// third state below the target is beyond it.
pub const REGROW_AFTER: u32 = 3;

impl Default for JamParams {
    fn default() -> Self {
        Self {
            eps: 1e-3,
            energy_low: 1e-16,
            energy_high: 2e-16,
            max_density_steps: 200_000,
            search: JamSearch::Adaptive,
        }
    }
}

impl JamParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.eps > 0.0 && self.eps < 1.0) {
            return Err(Error::invalid(
                format!("{prefix}.eps"),
                self.eps,
                "must lie in (0, 1)",
            ));
        }
        if !(self.energy_low > 0.0 && self.energy_low.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.energy_low"),
                self.energy_low,
                "must be positive and finite",
            ));
        }
        if !(self.energy_high > self.energy_low && self.energy_high.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.energy_high"),
                self.energy_high,
                format!(
                    "must be finite and greater than energy_low = {:e}",
                    self.energy_low
                ),
            ));
        }
        if self.max_density_steps == 0 {
            return Err(Error::invalid(
                format!("{prefix}.max_density_steps"),
                0,
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

/// Parameters of compression to a target pressure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PressureParams {
    /// Target pressure `P*`.
    pub pressure: f64,
    /// Relative tolerance on `P`.
    pub tol: f64,
    /// Initial step `ε` of the packing fraction.
    pub eps: f64,
    /// Give up after this many changes of `φ`.
    pub max_density_steps: u64,
}

impl Default for PressureParams {
    fn default() -> Self {
        Self {
            pressure: 1e-3,
            tol: 1e-3,
            eps: 1e-3,
            max_density_steps: 200_000,
        }
    }
}

/// The work of one or more minimisations, summed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// FIRE steps.
    pub fire_steps: u64,
    /// Minimisations (for a protocol: changes of `φ` plus one).
    pub minimizations: u64,
    /// Newton iterations of the finish.
    pub newton_iterations: u64,
    /// L-BFGS evaluations (on top of `fire_steps`).
    pub lbfgs_evaluations: u64,
    /// Moves of the plateau escape.
    pub plateau_escapes: u64,
    /// Times `stable_dt` lowered FIRE's `Δt_max`.
    pub dt_cuts: u64,
}

impl Work {
    /// The work of one minimisation.
    pub fn of(out: &MinimizeOutcome) -> Work {
        Work {
            fire_steps: out.steps,
            minimizations: 1,
            newton_iterations: out.newton_iterations,
            lbfgs_evaluations: out.lbfgs_evaluations,
            plateau_escapes: out.plateau_escapes,
            dt_cuts: out.dt_cuts,
        }
    }
}

impl std::ops::AddAssign for Work {
    fn add_assign(&mut self, other: Work) {
        self.fire_steps += other.fire_steps;
        self.minimizations += other.minimizations;
        self.newton_iterations += other.newton_iterations;
        self.lbfgs_evaluations += other.lbfgs_evaluations;
        self.plateau_escapes += other.plateau_escapes;
        self.dt_cuts += other.dt_cuts;
    }
}

/// What a protocol ended with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProtocolOutcome {
    /// Final packing fraction.
    pub phi: f64,
    /// Final `V/N`.
    pub energy_per_particle: f64,
    /// The work of all its minimisations.
    pub work: Work,
}

/// Bookkeeping shared by the protocols.
#[derive(Default)]
struct Tally {
    work: Work,
    /// The last minimisation ended on the unjamming forecast.
    forecast: bool,
}

impl Tally {
    fn relax<const D: usize, S: Shape<D>>(
        &mut self,
        scene: &mut Scene<D, S>,
        fire: &mut Fire,
    ) -> Result<f64> {
        scene.check_box()?;
        let out = fire.minimize(scene)?;
        self.work += Work::of(&out);
        self.forecast = out.reason == StopReason::Forecast;
        Ok(out.energy / scene.bodies() as f64)
    }

    fn outcome(&self, phi: f64, energy_per_particle: f64) -> ProtocolOutcome {
        ProtocolOutcome {
            phi,
            energy_per_particle,
            work: self.work,
        }
    }
}

/// Move `φ` by `eps`, failing when the step no longer changes `φ`.
fn step_phi<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    eps: f64,
    steps: u64,
) -> Result<()> {
    let phi = scene.phi();
    let next = phi + eps;
    if next == phi || !(next > 0.0) {
        return Err(Error::JammingFailed {
            phi,
            steps,
            reason: format!(
                "the step eps = {eps:e} no longer changes phi (floating-point resolution exhausted)"
            ),
        });
    }
    scene.set_phi(next);
    Ok(())
}

/// Where a relaxed state stands relative to the target of a bisection.
enum Verdict {
    /// In the target window: stop.
    Done,
    /// Beyond the target (too dense): the next step must decompress.
    Over,
    /// Short of the target: the next step must compress.
    Under,
}

/// The bisection shared by [`jam`] and [`compress_to_pressure`]: relax,
/// judge, and change φ by ε, reversing and halving ε on every crossing of
/// the target, until the judge says done. `judge` gets the relaxed scene and
/// `V/N`, and returns its verdict and a description of the state for the
/// error raised after `max_steps` changes of φ. `leap` may replace a
/// decompression's step; with `regrow` the compression step doubles, up to
/// the initial `eps`, from the [`REGROW_AFTER`]-th state in a row below the
/// target ([`JamSearch::Adaptive`]).
fn bisect<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    eps: f64,
    max_steps: u64,
    regrow: bool,
    mut judge: impl FnMut(&mut Scene<D, S>, f64) -> (Verdict, String),
    mut leap: impl FnMut(&mut Scene<D, S>, f64) -> Option<f64>,
) -> Result<ProtocolOutcome> {
    let mut tally = Tally::default();
    let initial = eps;
    let mut eps = eps;
    let mut steps = 0;
    // The largest φ found short of the target so far.
    let mut under_at = f64::NEG_INFINITY;
    // States found short of the target in a row.
    let mut unders = 0;
    fire.set_from_jammed(false);
    loop {
        let e = tally.relax(scene, fire)?;
        let (mut verdict, state) = judge(scene, e);
        if tally.forecast {
            // Its decay says where it ends: short of the target.
            verdict = Verdict::Under;
        }
        let over = match verdict {
            Verdict::Done => {
                fire.set_from_jammed(false);
                return Ok(tally.outcome(scene.phi(), e));
            }
            Verdict::Over => true,
            Verdict::Under => false,
        };
        // Reverse and halve on every crossing of the target.
        if over == (eps > 0.0) {
            eps *= -0.5;
        }
        fire.set_from_jammed(over);
        if !over {
            under_at = under_at.max(scene.phi());
            unders += 1;
            if regrow && unders >= REGROW_AFTER {
                eps = (2.0 * eps).min(initial);
            }
        } else {
            unders = 0;
            if let Some(step) = leap(scene, e) {
                // A predicted decompression, kept above the last state found
                // short of the target (else the halved step stands).
                let phi = scene.phi();
                if step < 0.0 && phi + step > under_at {
                    eps = step;
                }
            }
        }
        if steps >= max_steps {
            return Err(Error::JammingFailed {
                phi: scene.phi(),
                steps,
                reason: format!(
                    "not in the target after protocol.max_density_steps = {max_steps} ({state})"
                ),
            });
        }
        step_phi(scene, eps, steps)?;
        steps += 1;
    }
}

/// The paper's compress/decompress bisection to the jamming point.
pub fn jam<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    params: &JamParams,
) -> Result<ProtocolOutcome> {
    let target = (params.energy_low * params.energy_high).sqrt();
    // Its minimisations may end on the unjamming forecast (`crate::fire`),
    // which the search takes as a state short of the window; not on the
    // paper's bisection, which stays the paper's path bit for bit.
    if params.search != JamSearch::Bisection {
        fire.forecast_unjamming(Some((params.energy_low, params.energy_high)));
    }
    let out = bisect(
        scene,
        fire,
        params.eps,
        params.max_density_steps,
        params.search == JamSearch::Adaptive,
        |_, e| {
            let verdict = if e > params.energy_low && e < params.energy_high {
                Verdict::Done
            } else if e > params.energy_low {
                Verdict::Over
            } else {
                Verdict::Under
            };
            (verdict, format!("last V/N = {e:.3e}"))
        },
        |scene, e| match params.search {
            JamSearch::Bisection => None,
            JamSearch::Extrapolated | JamSearch::Adaptive => {
                extrapolated_step(scene, e, target.max(e * LEAP))
            }
        },
    );
    fire.forecast_unjamming(None);
    out
}

/// Parameters of [`above_jam`].
#[derive(Clone, Debug, PartialEq)]
pub struct AboveJamParams {
    /// The jamming bisection.
    pub jam: JamParams,
    /// `δφ`: how far above its jamming point the packing ends.
    pub delta_phi: f64,
    /// Step of `φ` on the way up.
    pub compress_eps: f64,
    /// How many times a packing that unjammed on its way up is jammed again
    /// from there before the protocol gives up.
    pub rejams: u32,
}

/// What [`above_jam`] ended with.
#[derive(Clone, Debug, PartialEq)]
pub struct AboveJamOutcome {
    /// The packing at `φ_J + δφ`: its `φ` and `V/N`, with the work of
    /// every pass.
    pub above: ProtocolOutcome,
    /// `φ_J`, the jamming point it was compressed from.
    pub phi_j: f64,
    /// The jamming points left because the packing unjammed on its way up.
    pub left: Vec<f64>,
}

/// Jam, then compress to `φ_J + δφ` (module documentation). `at_jam` is
/// called at every jamming point, before the compression, with the scene,
/// the bisection's outcome and the jamming points left so far: the place to
/// measure the jamming point (it must not move a body).
pub fn above_jam<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    params: &AboveJamParams,
    mut at_jam: impl FnMut(&mut Scene<D, S>, &ProtocolOutcome, &[f64]),
) -> Result<AboveJamOutcome> {
    let AboveJamParams {
        delta_phi,
        compress_eps,
        rejams,
        ..
    } = *params;
    let energy_high = params.jam.energy_high;
    let mut left = Vec::new();
    // The work of the passes that unjammed while compressed.
    let mut spent = Work::default();
    loop {
        let jammed = jam(scene, fire, &params.jam)?;
        at_jam(scene, &jammed, &left);
        let climb = compress_to_phi(scene, fire, jammed.phi + delta_phi, compress_eps)?;
        // φ and V/N of the compression, the work of every pass.
        let mut above = climb;
        above.work += jammed.work;
        above.work += spent;
        if above.energy_per_particle > energy_high {
            return Ok(AboveJamOutcome {
                above,
                phi_j: jammed.phi,
                left,
            });
        }
        // NOTE: a compression step followed by FIRE can rearrange the
        // packing into a state that jams above φ_J + δφ (measured: N = 64
        // disks, seed 1, δφ = 3e-3 ended with V/N = 7e-17 and no contact).
        // That is not a packing at δφ above its jamming point: jam it again
        // from there (`rejams` times at most), or fail, naming it.
        if left.len() as u32 >= rejams {
            return Err(Error::JammingFailed {
                phi: climb.phi,
                // The compression's density changes: one minimisation more
                // (the first, at φ_J).
                steps: climb.work.minimizations.saturating_sub(1),
                reason: format!(
                    "the packing unjammed while compressed by delta_phi = {delta_phi:e} from phi_J = {:.12} (V/N = {:.3e}, not above energy_high = {energy_high:e}): a rearrangement found a state that jams above phi_J + delta_phi{}",
                    jammed.phi,
                    climb.energy_per_particle,
                    if rejams == 0 {
                        "; try protocol.rejams (jam it again from there), a smaller protocol.compress_eps or another seed".to_string()
                    } else {
                        format!(
                            ", after protocol.rejams = {rejams} earlier jamming points ({left:?}) left the same way"
                        )
                    }
                ),
            });
        }
        left.push(jammed.phi);
        spent = above.work;
    }
}

/// `d(V/N)/dφ` of a relaxed state under affine compression, from the
/// virial pressure: `dV/dφ = −P dVol/dφ = P Vol / φ` (the box scales, the
/// bodies keep their sizes).
///
/// NOTE: at a minimum this is also the derivative of the *relaxed* energy:
/// the non-affine relaxation changes `V` only at second order.
pub fn energy_slope<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> f64 {
    let phi = scene.phi();
    let volume = scene.packing().bbox.volume();
    scene.pressure() * volume / (phi * Objective::bodies(scene) as f64)
}

/// How far one extrapolated decompression aims: to `LEAP` times the
/// state's `V/N` (or the window's geometric middle, if that is higher).
///
/// NOTE: a leap straight to the window lands there (the prediction is good
/// to a few digits of `φ − φ_J`), but relaxing a state decompressed by
/// `~10⁻³` to within `~10⁻⁸` of `φ_J` is slow (FIRE near marginal
/// stability): near-disks N = 256, seeds 1–6, 1.08 M FIRE steps against the
/// bisection's 0.79 M. Leaps of two decades of `V/N` (one of `φ − φ_J`)
/// each: 0.72 M; of one decade or three or four: 0.73–0.76 M (the rule:
/// docs/explanation/physics.md, "Jamming (`protocol: Jam`)").
const LEAP: f64 = 1e-2;

/// The change of `φ` that brings a jammed, relaxed state to `V/N = e*`
/// if `V/N = c (φ − φ_J)^α` holds between here and there (`α = 2` for the
/// harmonic potential, `5/2` for the Hertzian): `φ − φ_J = α e / e'` with
/// `e' = d(V/N)/dφ` from the pressure, and the step is
/// `−(φ − φ_J)(1 − (e*/e)^{1/α})`. `None` where the pressure gives no
/// usable slope.
///
/// NOTE: at a minimum the energy's derivative along `φ` is the affine one
/// (the non-affine relaxation changes `V` only at second order), so
/// `dV/dφ = −P dVol/dφ = P Vol / φ` with the virial pressure `P`.
pub fn extrapolated_step<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    e: f64,
    target: f64,
) -> Option<f64> {
    let alpha = match scene.potential() {
        Potential::Harmonic => 2.0,
        Potential::Hertzian => 2.5,
    };
    let slope = energy_slope(scene);
    let distance = alpha * e / slope;
    let step = -distance * (1.0 - (target / e).powf(1.0 / alpha));
    (slope > 0.0 && step.is_finite()).then_some(step)
}

/// Compress (or decompress) in steps of `eps` to packing fraction `target`,
/// minimising after every step.
pub fn compress_to_phi<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    target: f64,
    eps: f64,
) -> Result<ProtocolOutcome> {
    let mut tally = Tally::default();
    let mut e = tally.relax(scene, fire)?;
    // NOTE: φ is recomputed from the box volume, so it may miss `target` by an
    // ulp after the last rescale; count the steps instead of comparing φ.
    let start = scene.phi();
    let steps = ((target - start).abs() / eps).ceil() as u64;
    for k in 1..=steps {
        let next = if k == steps {
            target
        } else {
            start + (k as f64) * eps.copysign(target - start)
        };
        scene.set_phi(next);
        e = tally.relax(scene, fire)?;
    }
    Ok(tally.outcome(scene.phi(), e))
}

/// Bisect `φ` to the target pressure.
pub fn compress_to_pressure<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    params: &PressureParams,
) -> Result<ProtocolOutcome> {
    bisect(
        scene,
        fire,
        params.eps,
        params.max_density_steps,
        false,
        |scene, _| {
            let p = scene.pressure();
            let verdict = if (p - params.pressure).abs() < params.tol * params.pressure {
                Verdict::Done
            } else if p > params.pressure {
                Verdict::Over
            } else {
                Verdict::Under
            };
            (
                verdict,
                format!("pressure {p:.6e}, target {:.6e}", params.pressure),
            )
        },
        |_, _| None,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fire::FireParams;

    /// Minimisations the bisection takes from φ = 0.01 to a jamming point
    /// that moves from `0.0203` to `0.0203 + jump` at the first state found
    /// jammed (a rearrangement), judged by φ alone on a dilute scene (no
    /// contacts, so every minimisation ends at once), with and without
    /// regrowth.
    fn density_steps(jump: f64, regrow: bool) -> u64 {
        let mut scene = crate::random_disks(4, 0.01, 1);
        let mut fire = Fire::new(FireParams::paper());
        let mut phi_j = 0.0203;
        let mut moved = false;
        let outcome = bisect(
            &mut scene,
            &mut fire,
            1e-3,
            100_000,
            regrow,
            |scene, _| {
                let phi = scene.phi();
                let verdict = if (phi - phi_j).abs() < 1e-9 {
                    Verdict::Done
                } else if phi > phi_j {
                    if !moved {
                        (moved, phi_j) = (true, phi_j + jump);
                    }
                    Verdict::Over
                } else {
                    Verdict::Under
                };
                (verdict, String::new())
            },
            |_, _| None,
        )
        .unwrap();
        assert!(
            (outcome.phi - phi_j).abs() < 1e-9,
            "{} {phi_j}",
            outcome.phi
        );
        outcome.work.minimizations
    }

    /// A jamming point that moves up once the search has crossed it: the
    /// halved steps (2.5·10⁻⁴ after the crossing) creep there, the regrown
    /// ones double back to `eps` = 10⁻³: fewer minimisations for a move of
    /// 2·10⁻³, fewer than half for one of 0.05 (about 200 creeping steps
    /// against about 50). Without a move both take the same path: a third
    /// state below the target in a row does not occur.
    #[test]
    fn regrowth_reaches_a_jamming_point_that_moved_up_in_fewer_steps() {
        let (creep, regrown) = (density_steps(2e-3, false), density_steps(2e-3, true));
        assert!(regrown < creep, "regrown {regrown}, halved {creep}");
        let (creep, regrown) = (density_steps(0.05, false), density_steps(0.05, true));
        assert!(
            2 * regrown < creep,
            "a far move: regrown {regrown}, halved {creep}"
        );
        assert_eq!(density_steps(0.0, false), density_steps(0.0, true));
    }

    /// A protocol's work is the sum of its minimisations' (as the step
    /// trace records each): a counter left out of the sum, or added twice,
    /// shows here.
    #[test]
    fn a_jams_work_is_the_sum_of_its_minimisations() {
        let mut scene = crate::random_disks(16, 0.1, 3);
        let mut fire = Fire::new(FireParams::default());
        fire.record();
        let out = jam(&mut scene, &mut fire, &JamParams::default()).unwrap();
        let trace = fire.take_trace();
        let total = |f: fn(&MinimizeOutcome) -> u64| trace.iter().map(|(_, m)| f(m)).sum::<u64>();
        let sum = Work {
            fire_steps: total(|m| m.steps),
            minimizations: trace.len() as u64,
            newton_iterations: total(|m| m.newton_iterations),
            lbfgs_evaluations: total(|m| m.lbfgs_evaluations),
            plateau_escapes: total(|m| m.plateau_escapes),
            dt_cuts: total(|m| m.dt_cuts),
        };
        let mut added = Work::default();
        for (_, m) in &trace {
            added += Work::of(m);
        }
        assert_eq!(added, sum);
        assert_eq!(out.work, sum);
    }
}
