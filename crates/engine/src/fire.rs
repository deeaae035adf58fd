//! FIRE: the Fast Inertial Relaxation Engine.
//!
//! Damped molecular dynamics `m q̈ = −∂V/∂q` whose velocity is steered
//! towards the force while the power `P = F·v` stays positive and zeroed
//! when it turns negative (Bitzek et al., PRL 97, 170201 (2006)). FIRE 2.0
//! (Guénolé et al., Comput. Mater. Sci. 175, 109584 (2020)) adds a delay
//! before the time step may grow, a half step back on `P ≤ 0`, and a lower
//! bound on the time step.
//!
//! Both use the semi-implicit Euler integrator, so a step costs **one**
//! energy-and-gradient evaluation. With a mass `m_a` per coordinate, the
//! velocity is mixed in mass-weighted form,
//! `v ← (1 − α) v + α (|v|_m / |F|_{1/m}) F/m` with `|v|_m² = Σ m v²` and
//! `|F|_{1/m}² = Σ F²/m`, which reduces to the usual rule when every mass is 1.
//!
//! With `masses: Blocks` the masses are each body's own block of the
//! stiffness matrix instead ([`crate::precon`]): the same rules in that
//! metric.
//!
//! Minimisation stops when `V/N < energy_tol` or when the force measure
//! of [`ForceCriterion`] is below `force_tol` (`10⁻¹⁶` and `10⁻²⁵`). The
//! default measure is the largest `(∂V/∂q_a)²`, which does not tighten
//! per body as `N` grows; the paper's is the sum `Σ_a (∂V/∂q_a)²`
//! ([`FireParams::paper`]); with `force_tol_per_body` the sum is divided by
//! `N` first, as in the paper author's public code.
//!
//! **The unjamming forecast** (`unjam_forecast`, on by default; the paper's
//! bisection never asks for it). A jamming search judges a relaxed state by its `V/N`
//! alone: at or below the window's low edge `energy_low` it is unjammed.
//! Just below φ_J a state can creep down to that edge for hundreds of
//! thousands of steps, at a rate that tells where it goes. When the search
//! asks for it ([`Fire::forecast_unjamming`]), `V` is sampled every
//! [`FORECAST_EVERY`] FIRE steps from the [`FORECAST_AFTER`]-th on. Four
//! samples in a row that fall, the last within ten times the window's
//! upper edge, forecast when `V/N` reaches `energy_low`: at the last
//! fall's rate if the falls do not shrink, else along the geometric decay
//! through the last three samples, if its limit (Aitken's `Δ²`,
//! `V₃ − ΔV₃ r/(1 − r)`, `r = ΔV₃/ΔV₂`) lies below the edge. When the last
//! two such forecasts both see the edge reached, the last within as many
//! steps as the minimisation has taken, it ends with
//! [`StopReason::Forecast`] and the search takes the state as unjammed.
//! A state that jams settles at its own `V/N` above the edge: its falls
//! shrink towards that limit, or fade into round-off too slow to reach the
//! edge in time, and it runs on to the force test. The verdict can differ
//! only where a state above φ_J falls to within ten times the window and
//! keeps falling, at a jamming point found to that precision.

use crate::lbfgs::{LbfgsChoice, LbfgsEnd, LbfgsWork};
use crate::newton::{NewtonEnd, NewtonParams, NewtonWork};
use crate::objective::{Objective, StopReason};
use crate::precon::{BlockMasses, PreconParams};
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Which force measure the stopping rule compares with `force_tol`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ForceCriterion {
    /// `Σ_a (∂V/∂q_a)²`, the paper's rule as written: `N` times stricter per
    /// body at `N` bodies than at one.
    Sum,
    /// `Σ_a (∂V/∂q_a)² / N`, the paper author's public code (also
    /// `force_tol_per_body: true`).
    PerBody,
    /// `max_a (∂V/∂q_a)²`: every coordinate's residual force below
    /// `√force_tol`, whatever `N` (the default).
    #[default]
    Max,
}

/// Where the residual force of an unconverged minimisation sits: the body
/// with the largest share of `Σ g²` and that share, and the share of the
/// rotational coordinates (per cent; the gradient `g` has `stride`
/// coordinates per body, the first `translations` of them translational).
///
/// NOTE: cold and out of line: it runs once, on the error path; inlined
/// into FIRE's loop, disk packings took 2.03 s user against 1.91–1.95 s
/// out of line (N = 1024, seed 3, three interleaved runs each).
#[cold]
#[inline(never)]
fn residual_shares(g: &[f64], stride: usize, translations: usize) -> (usize, f64, f64) {
    let total: f64 = g.iter().map(|x| x * x).sum();
    if !(total > 0.0) || stride == 0 {
        return (0, 0.0, 0.0);
    }
    let (mut worst, mut worst_sq, mut rotational) = (0, 0.0, 0.0);
    for (b, body) in g.chunks(stride).enumerate() {
        let sq: f64 = body.iter().map(|x| x * x).sum();
        if sq > worst_sq {
            (worst, worst_sq) = (b, sq);
        }
        rotational += body[translations.min(body.len())..]
            .iter()
            .map(|x| x * x)
            .sum::<f64>();
    }
    (worst, 100.0 * worst_sq / total, 100.0 * rotational / total)
}

/// Which FIRE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum FireVariant {
    /// Bitzek et al. 2006.
    #[default]
    Fire,
    /// Guénolé et al. 2020.
    Fire2,
}

/// `Δt_max` when neither the experiment nor the family sets it: stable with
/// room to spare for disks and spheres of unit mass (`2/ω_max ≈ 0.8`).
pub const DEFAULT_DT_MAX: f64 = 0.5;

/// FIRE's parameters and stopping criteria.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FireParams {
    /// FIRE or FIRE 2.0.
    pub variant: FireVariant,
    /// Initial time step.
    pub dt_init: f64,
    /// Largest time step; `None`: the family's own
    /// ([`jamkit_core::Policy::fire_dt_max`], 0.5 unless the family says
    /// otherwise). FIRE slows to a crawl as `dt_max` nears `2/ω_max`, the
    /// stability limit of the semi-implicit Euler step on the stiffest
    /// vibration (`ω_max² ≈ 5.4` for jammed disks, ≈ 12 for 3D dimers).
    pub dt_max: Option<f64>,
    /// Smallest time step (FIRE 2.0 only).
    pub dt_min: f64,
    /// Steps with `P > 0` before `Δt` may grow (`N_min` in FIRE, `N_delay`
    /// in FIRE 2.0); `None`: the variant's own (5 for FIRE, 20 for FIRE 2.0).
    pub n_min: Option<u32>,
    /// Growth factor of `Δt`.
    pub f_inc: f64,
    /// Shrink factor of `Δt` on `P ≤ 0`.
    pub f_dec: f64,
    /// Initial mixing `α`; `None`: the variant's own (0.1 for FIRE, 0.25 for FIRE 2.0).
    pub alpha_start: Option<f64>,
    /// Decay factor of `α`.
    pub f_alpha: f64,
    /// Stop when `V/N` falls below this.
    pub energy_tol: f64,
    /// Stop when the force measure of `force_criterion` falls below this.
    pub force_tol: f64,
    /// Divide the force sum by `N` before comparing (the author's public
    /// code): `force_criterion: PerBody`, whatever `force_criterion` says.
    pub force_tol_per_body: bool,
    /// The force measure of the stopping rule (`Sum`, `PerBody`, `Max`).
    pub force_criterion: ForceCriterion,
    /// Give up (with an error) after this many steps in one minimisation.
    pub max_steps: u64,
    /// The Newton finish ([`crate::newton`]): after `after` FIRE steps
    /// without convergence, Newton iterations with the analytic Hessian.
    /// `None`: FIRE all the way, as in the paper.
    pub newton: Option<NewtonParams>,
    /// The masses FIRE integrates with: the family's choice (`Family`, the
    /// default, resolved by [`FireParams::for_family`]), the bodies' own
    /// (`Plain`, the paper) or each body's own block of the stiffness
    /// matrix (`Blocks`, [`crate::precon`]; FIRE only). Left out of the
    /// recorded settings when `Plain`, so that packings made before it
    /// existed still resume.
    pub masses: Masses,
    /// L-BFGS ([`crate::lbfgs`]): after `after` FIRE steps without
    /// convergence (`0`: from the start), L-BFGS iterations until a
    /// stopping criterion holds; FIRE again where it gives up. `Family`
    /// (the default, the field left out): the family's choice, resolved by
    /// [`FireParams::for_family`] (L-BFGS from the start in the block
    /// metric for 3D dimers, none elsewhere); `Off` (`None` in a file): no
    /// L-BFGS. A packing's recorded settings leave it out when `Off`, so
    /// that packings made before it existed still resume.
    #[serde(skip_serializing_if = "LbfgsChoice::is_family")]
    pub lbfgs: LbfgsChoice,
    /// In a jamming search other than the paper's bisection, end a
    /// minimisation whose `V` decay forecasts `V/N` at the search's
    /// `energy_low` as a state short of the window (module documentation).
    /// On by default; off in [`FireParams::paper`]. A packing's recorded
    /// settings leave it out when off, and where it does not act, so that
    /// packings made before it existed resume.
    pub unjam_forecast: bool,
    /// With the Newton finish: where a minimisation of at least
    /// [`crate::newton::PLATEAU_AFTER`] FIRE steps sits on a plateau (its
    /// energy at a Newton attempt above half that at the attempt before)
    /// and the attempt finds `H + μI` not positive definite, move along the
    /// Hessian's lowest mode, beyond the lowest `V` of a few amplitudes, then
    /// FIRE again ([`crate::newton`]). On by default; off in
    /// [`FireParams::paper`] (which has no Newton finish). A packing's
    /// recorded settings leave it out when off, and where it does not act
    /// (no Newton finish), so that packings made before it existed resume.
    pub escape_plateaus: bool,
    /// Where a minimisation has not converged after
    /// [`crate::stable_dt::STABLE_DT_AFTER`] FIRE steps (and every as many
    /// after), lower `Δt_max` below the stability bound `2/ω_max` of the
    /// stiffest mode, estimated from the analytic Hessian
    /// ([`crate::stable_dt`]); FIRE crawls where `Δt_max` is near or above
    /// it. Acts with plain masses only, and never on a minimisation that
    /// converges sooner. On by default; off in [`FireParams::paper`]. A
    /// packing's recorded settings leave it out when off, so that packings
    /// made before it existed resume.
    pub stable_dt: bool,
}

/// FIRE steps between two samples of `V` of the unjamming forecast.
pub const FORECAST_EVERY: u64 = 2000;

/// FIRE steps of a minimisation before the unjamming forecast takes its
/// first sample.
pub const FORECAST_AFTER: u64 = 10_000;

/// The unjamming forecast looks at states with `V/N` within this factor
/// of the window's upper edge.
pub const FORECAST_NEAR: f64 = 10.0;

/// The unjamming forecast of one minimisation (module documentation).
#[derive(Clone, Copy, Debug)]
struct Forecast {
    /// `energy_low · N`: the energy at or below which the search calls a
    /// state unjammed.
    level: f64,
    /// `FORECAST_NEAR · energy_high · N`: forecasts start below it.
    near: f64,
    /// The last five samples of `V`, oldest first.
    samples: [f64; 5],
    /// Samples taken.
    taken: u64,
    /// The FIRE step of the next sample.
    next: u64,
}

impl Forecast {
    fn new(level: f64, near: f64) -> Self {
        Self {
            level,
            near,
            samples: [0.0; 5],
            taken: 0,
            next: FORECAST_AFTER,
        }
    }

    /// Samples from the four samples `x`, `x[3]` the last, until `V`
    /// reaches the level, or `None` where they forecast no such end.
    fn samples_to_level(&self, x: &[f64]) -> Option<f64> {
        let (d2, d3) = (x[1] - x[2], x[2] - x[3]);
        if !(x[0] > x[1] && d2 > 0.0 && d3 > 0.0 && x[3] <= self.near) {
            return None;
        }
        let above = x[3] - self.level;
        if above <= 0.0 {
            return Some(0.0);
        }
        if d3 >= d2 {
            // Falling at least as fast as before: at the last rate.
            return Some(above / d3);
        }
        // A geometric decay, ratio r, towards its Aitken limit.
        let r = d3 / d2;
        let limit = x[3] - d3 * r / (1.0 - r);
        (limit < self.level).then(|| ((self.level - limit) / (x[3] - limit)).ln() / r.ln())
    }

    /// Take the sample `energy` at `steps` (a sample is due); `true` when
    /// the last two forecasts see `V` reach the level, the last within
    /// `steps` more steps.
    #[cold]
    #[inline(never)]
    fn sample(&mut self, steps: u64, energy: f64) -> bool {
        self.next = steps.saturating_add(FORECAST_EVERY);
        self.samples.rotate_left(1);
        self.samples[4] = energy;
        self.taken += 1;
        if self.taken < 5 {
            return false;
        }
        let earlier = self.samples_to_level(&self.samples[..4]);
        let last = self.samples_to_level(&self.samples[1..]);
        matches!((earlier, last), (Some(_), Some(n)) if n * FORECAST_EVERY as f64 <= steps as f64)
    }
}

/// Which masses FIRE integrates with.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Masses {
    /// The family's choice ([`jamkit_core::Policy::jammed_block_masses`]):
    /// `Blocks((jammed_only: true))` where the family says so and the
    /// variant is FIRE, else `Plain`; resolved by [`FireParams::for_family`]
    /// (FIRE integrates an unresolved `Family` with the plain masses).
    #[default]
    Family,
    /// The bodies' own masses: 1 per translation, the family's moments of
    /// inertia per rotation (the paper).
    Plain,
    /// Block preconditioning: each body's own block of the stiffness
    /// matrix as its mass ([`crate::precon`]).
    Blocks(PreconParams),
}

impl Default for FireParams {
    fn default() -> Self {
        Self {
            variant: FireVariant::Fire,
            dt_init: 0.1,
            dt_max: None,
            dt_min: 0.002,
            n_min: None,
            f_inc: 1.1,
            f_dec: 0.5,
            alpha_start: None,
            f_alpha: 0.99,
            energy_tol: 1e-16,
            force_tol: 1e-25,
            force_tol_per_body: false,
            force_criterion: ForceCriterion::Max,
            max_steps: 20_000_000,
            newton: Some(NewtonParams::default()),
            masses: Masses::Family,
            lbfgs: LbfgsChoice::Family,
            unjam_forecast: true,
            escape_plateaus: true,
            stable_dt: true,
        }
    }
}

impl FireParams {
    /// FIRE 2.0 with the mixing and delay of Guénolé et al. (their Table 1).
    pub fn fire2() -> Self {
        Self {
            variant: FireVariant::Fire2,
            ..Self::default()
        }
    }

    /// The paper's FIRE: FIRE (Bitzek et al.) all the way, no Newton
    /// finish (nor its plateau escape), `Σ (∂V/∂q)² < 10⁻²⁵`, no unjamming
    /// forecast. Bit for bit
    /// the packings recorded without the Newton finish.
    pub fn paper() -> Self {
        Self {
            variant: FireVariant::Fire,
            force_tol_per_body: false,
            force_criterion: ForceCriterion::Sum,
            newton: None,
            masses: Masses::Plain,
            lbfgs: LbfgsChoice::Off,
            unjam_forecast: false,
            escape_plateaus: false,
            stable_dt: false,
            ..Self::default()
        }
    }

    /// FIRE with the Newton finish at its default settings (and its plateau
    /// escape), the default force criterion and the unjamming forecast,
    /// with plain masses and no L-BFGS.
    pub fn fire_newton() -> Self {
        Self {
            newton: Some(NewtonParams::default()),
            force_criterion: ForceCriterion::default(),
            unjam_forecast: true,
            escape_plateaus: true,
            stable_dt: true,
            ..Self::paper()
        }
    }

    /// The force criterion in force (`force_tol_per_body` means `PerBody`).
    pub fn criterion(&self) -> ForceCriterion {
        if self.force_tol_per_body {
            ForceCriterion::PerBody
        } else {
            self.force_criterion
        }
    }

    /// The stopping rule: `Energy` when `V/N < energy_tol`, `Force` when the
    /// force measure of [`FireParams::criterion`] is below `force_tol`.
    /// `force_sq` is `Σ g²` of the gradient `g`.
    #[inline(always)]
    pub fn stop(&self, energy: f64, force_sq: f64, g: &[f64], bodies: f64) -> Option<StopReason> {
        if energy / bodies < self.energy_tol {
            return Some(StopReason::Energy);
        }
        let converged = match self.criterion() {
            ForceCriterion::Sum => force_sq < self.force_tol,
            ForceCriterion::PerBody => force_sq / bodies < self.force_tol,
            // max g² ≤ Σ g²: the pass over g only when the sum cannot decide.
            ForceCriterion::Max => {
                force_sq < self.force_tol
                    || (force_sq < self.force_tol * g.len() as f64 && max_sq(g) < self.force_tol)
            }
        };
        converged.then_some(StopReason::Force)
    }

    /// These parameters with `dt_max`, the masses and L-BFGS set: their
    /// own, else the family's ([`jamkit_core::Policy::fire_dt_max`], 0.5
    /// where the family has none; [`jamkit_core::Policy::jammed_block_masses`]
    /// and [`jamkit_core::Policy::lbfgs_blocks`] with FIRE, the
    /// plain masses and no L-BFGS with FIRE 2.0), so that the settings a
    /// packing records hold the time step, masses and minimiser it was made
    /// with.
    pub fn for_family<const D: usize, S: jamkit_core::Shape<D>>(&self, shape: &S) -> Self {
        let policy = shape.policy();
        let masses = match &self.masses {
            Masses::Family if self.variant == FireVariant::Fire && policy.jammed_block_masses => {
                Masses::Blocks(PreconParams {
                    jammed_only: true,
                    ..PreconParams::default()
                })
            }
            Masses::Family => Masses::Plain,
            chosen => chosen.clone(),
        };
        let lbfgs = match &self.lbfgs {
            LbfgsChoice::Family if self.variant == FireVariant::Fire && policy.lbfgs_blocks => {
                LbfgsChoice::On(LbfgsChoice::family_default())
            }
            LbfgsChoice::Family => LbfgsChoice::Off,
            chosen => chosen.clone(),
        };
        Self {
            dt_max: Some(self.dt_max.or(policy.fire_dt_max).unwrap_or(DEFAULT_DT_MAX)),
            masses,
            lbfgs,
            ..self.clone()
        }
    }

    /// `Δt_max` in force (`dt_max`, or 0.5 when no family chose it).
    pub fn dt_max(&self) -> f64 {
        self.dt_max.unwrap_or(DEFAULT_DT_MAX)
    }

    /// `N_min` (FIRE) or `N_delay` (FIRE 2.0) in force.
    pub fn n_min(&self) -> u32 {
        self.n_min.unwrap_or(match self.variant {
            FireVariant::Fire => 5,
            FireVariant::Fire2 => 20,
        })
    }

    /// `α_start` in force.
    pub fn alpha_start(&self) -> f64 {
        self.alpha_start.unwrap_or(match self.variant {
            FireVariant::Fire => 0.1,
            FireVariant::Fire2 => 0.25,
        })
    }

    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let positive = [
            ("dt_init", self.dt_init),
            ("dt_max", self.dt_max()),
            ("dt_min", self.dt_min),
            ("energy_tol", self.energy_tol),
            ("force_tol", self.force_tol),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::invalid(
                    format!("{prefix}.{name}"),
                    v,
                    "must be positive and finite",
                ));
            }
        }
        if self.dt_max() < self.dt_init {
            return Err(Error::invalid(
                format!("{prefix}.dt_max"),
                self.dt_max(),
                format!("must be at least dt_init = {}", self.dt_init),
            ));
        }
        let unit = [
            ("f_dec", self.f_dec),
            ("f_alpha", self.f_alpha),
            ("alpha_start", self.alpha_start()),
        ];
        for (name, v) in unit {
            if !(v > 0.0 && v < 1.0) {
                return Err(Error::invalid(
                    format!("{prefix}.{name}"),
                    v,
                    "must lie strictly between 0 and 1",
                ));
            }
        }
        if !(self.f_inc >= 1.0 && self.f_inc.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.f_inc"),
                self.f_inc,
                "must be at least 1",
            ));
        }
        if self.max_steps == 0 {
            return Err(Error::invalid(
                format!("{prefix}.max_steps"),
                0,
                "must be at least 1",
            ));
        }
        if let Some(newton) = &self.newton {
            newton.validate(&format!("{prefix}.newton"))?;
        }
        if let Some(lbfgs) = self.lbfgs.params() {
            lbfgs.validate(&format!("{prefix}.lbfgs"))?;
        }
        if let Masses::Blocks(precon) = &self.masses {
            precon.validate(&format!("{prefix}.masses"))?;
            if self.variant != FireVariant::Fire {
                return Err(Error::invalid(
                    format!("{prefix}.masses"),
                    "Blocks(…)",
                    "needs variant: Fire (the block preconditioner is not built for FIRE 2.0); give masses: Plain or variant: Fire",
                ));
            }
        }
        Ok(())
    }
}

/// What a minimisation ended with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinimizeOutcome {
    /// FIRE steps taken (each one evaluation).
    pub steps: u64,
    /// Final energy `V`.
    pub energy: f64,
    /// Final `Σ (∂V/∂q)²`.
    pub force_sq: f64,
    /// Which criterion stopped it.
    pub reason: StopReason,
    /// Newton iterations of the finish (0 without it).
    pub newton_iterations: u64,
    /// Energy-and-gradient evaluations of L-BFGS (0 without it), on top of
    /// `steps`.
    pub lbfgs_evaluations: u64,
    /// Moves of the plateau escape (`escape_plateaus`).
    pub plateau_escapes: u64,
    /// Times `stable_dt` lowered `Δt_max`.
    pub dt_cuts: u64,
}

/// A FIRE minimiser with its work buffers (reused across minimisations).
#[derive(Clone, Debug, Default)]
pub struct Fire {
    /// Parameters.
    pub params: FireParams,
    velocity: Vec<f64>,
    grad: Vec<f64>,
    step: Vec<f64>,
    inv_mass: Vec<f64>,
    mass: Vec<f64>,
    newton_work: NewtonWork,
    lbfgs_work: LbfgsWork,
    blocks: BlockMasses,
    /// `M⁻¹ g` of the preconditioned FIRE.
    precon_grad: Vec<f64>,
    stable_dt_work: crate::stable_dt::StableDtWork,
    /// With [`Fire::record`]: `(φ, outcome)` of every minimisation.
    trace: Option<Vec<(f64, MinimizeOutcome)>>,
    /// With [`Fire::watch`]: where the minimiser stands, for another thread.
    progress: Option<Arc<Progress>>,
    /// The next minimisation starts from a decompressed jammed state (set
    /// by the jamming search; read by `masses: Blocks((jammed_only: true))`).
    from_jammed: bool,
    /// The jamming search's window `(energy_low, energy_high)` while it
    /// asks for the unjamming forecast ([`Fire::forecast_unjamming`]).
    unjam_window: Option<(f64, f64)>,
}

/// Where a minimiser stands, written after every minimisation and read by
/// another thread (a run's batch log): the last minimisation's `φ` and
/// `V/N`, and the counts so far. Reading it changes nothing in the run.
#[derive(Debug, Default)]
pub struct Progress {
    minimizations: AtomicU64,
    fire_steps: AtomicU64,
    phi: AtomicU64,
    energy_per_particle: AtomicU64,
}

/// A copy of a [`Progress`] at one moment.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProgressSnapshot {
    /// Minimisations finished.
    pub minimizations: u64,
    /// FIRE steps over them.
    pub fire_steps: u64,
    /// `φ` of the last one.
    pub phi: f64,
    /// `V/N` at its end.
    pub energy_per_particle: f64,
}

impl Progress {
    fn record(&self, phi: f64, energy_per_particle: f64, steps: u64) {
        self.phi.store(phi.to_bits(), Ordering::Relaxed);
        self.energy_per_particle
            .store(energy_per_particle.to_bits(), Ordering::Relaxed);
        self.fire_steps.fetch_add(steps, Ordering::Relaxed);
        self.minimizations.fetch_add(1, Ordering::Relaxed);
    }

    /// The counts and the last state (fields may be one minimisation
    /// apart: each is read on its own).
    pub fn snapshot(&self) -> ProgressSnapshot {
        ProgressSnapshot {
            minimizations: self.minimizations.load(Ordering::Relaxed),
            fire_steps: self.fire_steps.load(Ordering::Relaxed),
            phi: f64::from_bits(self.phi.load(Ordering::Relaxed)),
            energy_per_particle: f64::from_bits(self.energy_per_particle.load(Ordering::Relaxed)),
        }
    }
}

impl Fire {
    /// A minimiser with these parameters.
    pub fn new(params: FireParams) -> Self {
        Self {
            params,
            ..Self::default()
        }
    }

    /// Say whether the next minimisations start from a decompressed jammed
    /// state (the jamming search does; see [`PreconParams::jammed_only`]).
    pub fn set_from_jammed(&mut self, from_jammed: bool) {
        self.from_jammed = from_jammed;
    }

    /// Let the next minimisations end on the unjamming forecast against
    /// this window `(energy_low, energy_high)` of `V/N`, where
    /// `unjam_forecast` is on; `None`: they run to a stopping criterion
    /// (set by the jamming search).
    pub fn forecast_unjamming(&mut self, window: Option<(f64, f64)>) {
        self.unjam_window = window;
    }

    /// Keep `(φ, outcome)` of every minimisation from now on (a step trace:
    /// where a protocol spends its steps), for [`Fire::take_trace`].
    pub fn record(&mut self) {
        self.trace.get_or_insert_with(Vec::new);
    }

    /// The minimisations recorded since [`Fire::record`] (empty without it).
    pub fn take_trace(&mut self) -> Vec<(f64, MinimizeOutcome)> {
        self.trace.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// Report every minimisation from now on to `progress` (read by another
    /// thread; changes nothing in the minimisations).
    pub fn watch(&mut self, progress: Arc<Progress>) {
        self.progress = Some(progress);
    }

    /// Minimise `obj` from its current state, starting at rest.
    pub fn minimize<O: Objective>(&mut self, obj: &mut O) -> Result<MinimizeOutcome> {
        let out = self.minimize_dispatch(obj)?;
        if let Some(trace) = self.trace.as_mut() {
            trace.push((obj.phi(), out));
        }
        if let Some(p) = &self.progress {
            p.record(
                obj.phi(),
                out.energy / obj.bodies().max(1) as f64,
                out.steps,
            );
        }
        Ok(out)
    }

    fn minimize_dispatch<O: Objective>(&mut self, obj: &mut O) -> Result<MinimizeOutcome> {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2 (checked at run time by `simd::avx2`);
            // the AVX2 copy is the same code with the same results.
            return unsafe { self.minimize_avx2(obj) };
        }
        self.minimize_portable(obj)
    }

    /// [`Fire::minimize_portable`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn minimize_avx2<O: Objective>(&mut self, obj: &mut O) -> Result<MinimizeOutcome> {
        self.minimize_portable(obj)
    }

    #[inline(always)]
    fn minimize_portable<O: Objective>(&mut self, obj: &mut O) -> Result<MinimizeOutcome> {
        let p = self.params.clone();
        let n = obj.dof();
        let bodies = obj.bodies().max(1) as f64;
        self.velocity.clear();
        self.velocity.resize(n, 0.0);
        self.grad.resize(n, 0.0);
        self.step.resize(n, 0.0);
        self.inv_mass.clear();
        self.inv_mass.extend_from_slice(obj.inverse_masses());
        self.mass.clear();
        self.mass.extend(self.inv_mass.iter().map(|m| 1.0 / m));
        let (v, g, dq) = (&mut self.velocity, &mut self.grad, &mut self.step);
        let (inv_m, mass) = (&self.inv_mass, &self.mass);
        let unit = inv_m.iter().all(|&m| m == 1.0);
        let precon = match &p.masses {
            Masses::Blocks(pc)
                if p.variant == FireVariant::Fire && (self.from_jammed || !pc.jammed_only) =>
            {
                Some(pc)
            }
            _ => None,
        };
        let (blocks, w) = (&mut self.blocks, &mut self.precon_grad);
        w.resize(n, 0.0);
        // Whether the blocks are in use (the objective may have none).
        let mut blocked = false;

        let mut dt = p.dt_init;
        let mut dt_max = p.dt_max();
        let mut next_dt_check = if p.stable_dt && precon.is_none() {
            crate::stable_dt::STABLE_DT_AFTER
        } else {
            u64::MAX
        };
        let mut dt_cuts: u64 = 0;
        let (alpha_start, n_min) = (p.alpha_start(), p.n_min());
        let mut alpha = alpha_start;
        let mut positive_steps: u32 = 0;
        let mut energy = obj.energy_gradient(g);
        let mut forecast = match self.unjam_window {
            Some((low, high)) if p.unjam_forecast => {
                Some(Forecast::new(low * bodies, FORECAST_NEAR * high * bodies))
            }
            _ => None,
        };
        let mut steps: u64 = 0;
        let mut newton_iterations: u64 = 0;
        let mut newton_interval = p.newton.as_ref().map_or(u64::MAX, |nw| nw.after);
        let mut next_newton = newton_interval;
        // Energy at the last Newton attempt (the plateau test).
        let mut attempt_energy = f64::INFINITY;
        let mut plateau_escapes: u64 = 0;
        let mut lbfgs_evaluations: u64 = 0;
        let mut lbfgs_interval = match p.lbfgs.params() {
            Some(lb) if self.from_jammed || !lb.jammed_only => lb.after,
            _ => u64::MAX,
        };
        let mut next_lbfgs = lbfgs_interval;
        // The minimisation's end, with the counts so far.
        macro_rules! finish {
            ($energy:expr, $force_sq:expr, $reason:expr) => {
                return Ok(MinimizeOutcome {
                    steps,
                    energy: $energy,
                    force_sq: $force_sq,
                    reason: $reason,
                    newton_iterations,
                    lbfgs_evaluations,
                    plateau_escapes,
                    dt_cuts,
                })
            };
        }
        // FIRE again from rest, after a second-order attempt gave up.
        macro_rules! from_rest {
            () => {
                v.fill(0.0);
                dt = p.dt_init;
                alpha = alpha_start;
                positive_steps = 0;
                continue;
            };
        }
        loop {
            if let Some(pc) = precon
                && steps.is_multiple_of(pc.refresh)
            {
                blocked = blocks.rebuild(obj, inv_m, pc);
            }
            let [force_sq, minus_power, v_norm_sq, f_norm_sq] = if blocked {
                blocks.sums(g, v, w)
            } else {
                step_sums(g, v, inv_m, mass, unit)
            };
            if !(energy.is_finite() && force_sq.is_finite()) {
                return Err(Error::NonFinite {
                    phi: obj.phi(),
                    what: format!("V = {energy}, sum |dV/dq|^2 = {force_sq}"),
                });
            }
            if let Some(reason) = p.stop(energy, force_sq, g, bodies) {
                finish!(energy, force_sq, reason);
            }
            if let Some(f) = forecast.as_mut()
                && steps >= f.next
                && f.sample(steps, energy)
            {
                finish!(energy, force_sq, StopReason::Forecast);
            }
            if steps + lbfgs_evaluations >= p.max_steps {
                let stride = n / obj.bodies().max(1);
                let (worst_body, worst_share, rotational_share) =
                    residual_shares(g, stride, obj.translations_per_body());
                return Err(Error::NotConverged {
                    steps: steps + lbfgs_evaluations,
                    phi: obj.phi(),
                    energy_per_particle: energy / bodies,
                    force_sq,
                    worst_body,
                    worst_share,
                    rotational_share,
                });
            }
            if steps >= next_newton
                && let Some(nw) = &p.newton
            {
                let before = energy;
                let run = crate::newton::attempt(
                    obj,
                    g,
                    energy,
                    nw,
                    &mut self.newton_work,
                    |e, f, g| p.stop(e, f, g, bodies),
                )?;
                newton_iterations += run.iterations;
                energy = run.energy;
                if let NewtonEnd::Converged(reason) = run.end {
                    finish!(energy, run.force_sq, reason);
                }
                if run.end == NewtonEnd::Unavailable {
                    // No Hessian (the state is untouched): FIRE alone.
                    next_newton = u64::MAX;
                    continue;
                }
                // On a plateau with negative curvature: along the lowest
                // mode, and the next attempt soon.
                let mut pushed = false;
                if run.end == NewtonEnd::Indefinite
                    && p.escape_plateaus
                    && steps >= crate::newton::PLATEAU_AFTER
                    && before > crate::newton::PLATEAU_FALL * attempt_energy
                    && plateau_escapes < crate::newton::PLATEAU_MOVES
                    && let Some((e, moved)) =
                        crate::newton::escape_plateau(obj, g, energy, nw, &mut self.newton_work)
                {
                    energy = e;
                    pushed = moved;
                    plateau_escapes += u64::from(moved);
                }
                attempt_energy = before;
                // Back to FIRE, from rest; the next attempt comes later.
                newton_interval = if pushed {
                    nw.after
                } else {
                    newton_interval.saturating_mul(2)
                };
                next_newton = steps.saturating_add(newton_interval);
                from_rest!();
            }
            if steps >= next_lbfgs
                && let Some(lb) = p.lbfgs.params()
            {
                let budget = p.max_steps - (steps + lbfgs_evaluations);
                let run = crate::lbfgs::attempt(
                    obj,
                    g,
                    energy,
                    lb,
                    (&mut self.lbfgs_work, blocks),
                    budget,
                    |e, f, g| p.stop(e, f, g, bodies),
                )?;
                lbfgs_evaluations += run.evaluations;
                energy = run.energy;
                if let LbfgsEnd::Converged(reason) = run.end {
                    finish!(energy, run.force_sq, reason);
                }
                // L-BFGS may have rebuilt the blocks with its own settings.
                if lb.blocks
                    && let Some(pc) = precon
                {
                    blocked = blocks.rebuild(obj, inv_m, pc);
                }
                // Back to FIRE, from rest; the next attempt comes after
                // twice as many FIRE steps (at least 100).
                lbfgs_interval = lbfgs_interval.max(50).saturating_mul(2);
                next_lbfgs = steps.saturating_add(lbfgs_interval);
                from_rest!();
            }
            if steps >= next_dt_check {
                next_dt_check = steps.saturating_add(crate::stable_dt::STABLE_DT_AFTER);
                match crate::stable_dt::omega_max_sq(obj, inv_m, &mut self.stable_dt_work)? {
                    Some(w2) => {
                        let capped = crate::stable_dt::capped(dt_max, w2);
                        if capped < dt_max {
                            dt_max = capped;
                            dt = dt.min(dt_max);
                            dt_cuts += 1;
                        }
                    }
                    // No Hessian: no check again.
                    None => next_dt_check = u64::MAX,
                }
            }
            // Power P = F·v with F = −g.
            let power = -minus_power;
            match p.variant {
                FireVariant::Fire => {
                    // Mixing (P > 0) or a stop (P ≤ 0), then the Euler step,
                    // fused: v ← c v − (s + Δt) g/m, with c and s from the rule.
                    let (keep, steer) = if power > 0.0 {
                        let steer = if f_norm_sq > 0.0 {
                            alpha * (v_norm_sq / f_norm_sq).sqrt()
                        } else {
                            0.0
                        };
                        let keep = 1.0 - alpha;
                        positive_steps += 1;
                        if positive_steps > n_min {
                            dt = (dt * p.f_inc).min(dt_max);
                            alpha *= p.f_alpha;
                        }
                        (keep, steer)
                    } else {
                        positive_steps = 0;
                        dt *= p.f_dec;
                        alpha = alpha_start;
                        (0.0, 0.0)
                    };
                    let kick = steer + dt;
                    if blocked {
                        // The same step in the metric of the blocks: g/m → M⁻¹g.
                        for ((va, da), wa) in v.iter_mut().zip(dq.iter_mut()).zip(w.iter()) {
                            *va = keep * *va - kick * wa;
                            *da = dt * *va;
                        }
                    } else if unit {
                        // Bit for bit the general loop: `x · 1 = x`.
                        for ((va, da), ga) in v.iter_mut().zip(dq.iter_mut()).zip(g.iter()) {
                            *va = keep * *va - kick * ga;
                            *da = dt * *va;
                        }
                    } else {
                        for (((va, da), ga), ma) in
                            v.iter_mut().zip(dq.iter_mut()).zip(g.iter()).zip(inv_m)
                        {
                            *va = keep * *va - kick * ga * ma;
                            *da = dt * *va;
                        }
                    }
                }
                FireVariant::Fire2 => {
                    if power > 0.0 {
                        positive_steps += 1;
                        if positive_steps > n_min {
                            dt = (dt * p.f_inc).min(dt_max);
                            alpha *= p.f_alpha;
                        }
                    } else {
                        positive_steps = 0;
                        // No shrinking during the initial delay (Guénolé et al.).
                        if steps >= n_min as u64 && dt * p.f_dec >= p.dt_min {
                            dt *= p.f_dec;
                        }
                        alpha = alpha_start;
                        // Half a step back, then restart from rest.
                        for a in 0..n {
                            dq[a] = -0.5 * dt * v[a];
                            v[a] = 0.0;
                        }
                        obj.displace(dq);
                    }
                    // Euler velocity update, then mixing with the new velocity.
                    let mut lanes = [0.0; LANES];
                    for a in 0..n {
                        v[a] -= dt * g[a] * inv_m[a];
                        lanes[a % LANES] += v[a] * v[a] * mass[a];
                    }
                    let (keep, steer) = if power > 0.0 && f_norm_sq > 0.0 {
                        (
                            1.0 - alpha,
                            alpha * (lanes.iter().sum::<f64>() / f_norm_sq).sqrt(),
                        )
                    } else {
                        (1.0, 0.0)
                    };
                    for (((va, da), ga), ma) in
                        v.iter_mut().zip(dq.iter_mut()).zip(g.iter()).zip(inv_m)
                    {
                        *va = keep * *va - steer * ga * ma;
                        *da = dt * *va;
                    }
                }
            }
            obj.displace(dq);
            energy = obj.energy_gradient(g);
            steps += 1;
        }
    }
}

/// `max_a g_a²`.
#[cold]
#[inline(never)]
fn max_sq(g: &[f64]) -> f64 {
    g.iter().fold(0.0, |m, x| if x * x > m { x * x } else { m })
}

/// Independent partial sums per reduction: floating-point addition is not
/// reassociated by the compiler, so one accumulator would serialise every
/// reduction on the adder's latency. The order is fixed, so results are
/// deterministic.
const LANES: usize = 4;

/// `[Σ g², Σ g v, Σ m v², Σ g²/m]` in one pass; `unit`: every mass is 1.
#[inline(never)]
fn step_sums(g: &[f64], v: &[f64], inv_m: &[f64], mass: &[f64], unit: bool) -> [f64; 4] {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() {
        // SAFETY: the CPU has AVX2 (checked at run time); same code, same bits.
        return unsafe {
            if unit {
                step_sums_avx2::<true>(g, v, inv_m, mass)
            } else {
                step_sums_avx2::<false>(g, v, inv_m, mass)
            }
        };
    }
    if unit {
        step_sums_portable::<true>(g, v, inv_m, mass)
    } else {
        step_sums_portable::<false>(g, v, inv_m, mass)
    }
}

/// [`step_sums_portable`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn step_sums_avx2<const UNIT: bool>(
    g: &[f64],
    v: &[f64],
    inv_m: &[f64],
    mass: &[f64],
) -> [f64; 4] {
    step_sums_portable::<UNIT>(g, v, inv_m, mass)
}

/// NOTE: kept out of FIRE's loop (`step_sums` is never inlined), so that the
/// sixteen partial sums stay in registers: inlined, they spilled to the
/// stack. One lane loop per sum, so that each sum is one vector register.
/// With unit masses (`UNIT`, spheres) the mass streams are not read:
/// `x · 1 = x` exactly, so the sums are bit for bit the general ones, and
/// `Σ g²/m` is `Σ g²`.
#[inline(always)]
fn step_sums_portable<const UNIT: bool>(
    g: &[f64],
    v: &[f64],
    inv_m: &[f64],
    mass: &[f64],
) -> [f64; 4] {
    let (mut gg, mut gv, mut vv, mut ff) = ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
    let blocks = g.len() / LANES;
    for k in 0..blocks {
        let r = k * LANES..(k + 1) * LANES;
        let (g4, v4) = (&g[r.clone()], &v[r.clone()]);
        for l in 0..LANES {
            gg[l] += g4[l] * g4[l];
        }
        for l in 0..LANES {
            gv[l] += g4[l] * v4[l];
        }
        if UNIT {
            for l in 0..LANES {
                vv[l] += v4[l] * v4[l];
            }
        } else {
            let (im4, m4) = (&inv_m[r.clone()], &mass[r]);
            for l in 0..LANES {
                vv[l] += v4[l] * v4[l] * m4[l];
            }
            for l in 0..LANES {
                ff[l] += g4[l] * g4[l] * im4[l];
            }
        }
    }
    for a in blocks * LANES..g.len() {
        gg[0] += g[a] * g[a];
        gv[0] += g[a] * v[a];
        if UNIT {
            vv[0] += v[a] * v[a];
        } else {
            vv[0] += v[a] * v[a] * mass[a];
            ff[0] += g[a] * g[a] * inv_m[a];
        }
    }
    if UNIT {
        ff = gg;
    }
    [gg, gv, vv, ff].map(|l| (l[0] + l[1]) + (l[2] + l[3]))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The step at which the forecast of window `(1, 2)` (`V`, one body)
    /// ends a minimisation whose `V` after `s` steps is `v(s)`, if it does
    /// within `limit` steps.
    fn forecast_end(v: impl Fn(f64) -> f64, limit: u64) -> Option<u64> {
        let mut f = Forecast::new(1.0, FORECAST_NEAR * 2.0);
        (0..limit).find(|&s| s >= f.next && f.sample(s, v(s as f64)))
    }

    /// The forecast's cases, on `V` in units of `energy_low`: a geometric
    /// decay to 0 from within ten times the window is ended at the first
    /// sample (from the fifth on) where it has as many steps to go to the
    /// edge as it has taken (Aitken's limit is exact for it), well above the
    /// edge, and so is a fall that does not slow;
    /// a decay to 1.5 (in the window: a jammed state) is not, nor one to
    /// 0.5 that starts 100 times above the window, until it has come within
    /// ten times it, nor a plateau that falls by round-off, nor a state that
    /// rises.
    #[test]
    fn the_unjamming_forecast_ends_decays_below_the_window_only() {
        let tau = 20_000.0;
        let geometric = |limit: f64, a: f64| move |s: f64| limit + a * (-s / tau).exp();
        let v = geometric(0.0, 19.0 * 2f64.powf(0.5));
        let end = forecast_end(v, 1_000_000).unwrap();
        let expected = (4..)
            .map(|k| FORECAST_AFTER + k * FORECAST_EVERY)
            .find(|&s| tau * v(s as f64).ln() <= s as f64 + 1e-6)
            .unwrap();
        assert_eq!(end, expected);
        assert!(v(end as f64) > 4.0, "{}", v(end as f64));
        assert!(forecast_end(|s| 19.0 - s * 1e-4, 1_000_000).is_some());
        assert_eq!(forecast_end(geometric(1.5, 18.0), 1_000_000), None);
        let from_far = forecast_end(geometric(0.5, 2000.0), 1_000_000).unwrap();
        assert!(geometric(0.5, 2000.0)(from_far as f64) <= 20.0);
        assert_eq!(forecast_end(|s| 5.0 - s * 1e-15, 1_000_000), None);
        assert_eq!(forecast_end(|s| 5.0 + s * 1e-6, 1_000_000), None);
    }

    /// V = Σ k_a x_a² / 2 with very different stiffnesses and masses.
    struct Quadratic {
        x: Vec<f64>,
        k: Vec<f64>,
        inv_m: Vec<f64>,
    }

    impl Objective for Quadratic {
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
            let mut e = 0.0;
            for a in 0..self.x.len() {
                grad[a] = self.k[a] * self.x[a];
                e += 0.5 * self.k[a] * self.x[a] * self.x[a];
            }
            e
        }
        fn displace(&mut self, dq: &[f64]) {
            for (x, d) in self.x.iter_mut().zip(dq) {
                *x += d;
            }
        }
        fn phi(&self) -> f64 {
            0.0
        }
        fn stiffness_blocks(&mut self, blocks: &mut Vec<f64>) -> bool {
            // One body: its block is the whole (diagonal) Hessian.
            diagonal_block(&self.k, blocks)
        }
        fn hessian_entries(&mut self, e: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
            e.extend(
                self.k
                    .iter()
                    .enumerate()
                    .map(|(a, &k)| (a as u32, a as u32, k)),
            );
            Ok(true)
        }
    }

    /// One body whose stiffness block is `diag(k)` (test wells).
    pub(crate) fn diagonal_block(k: &[f64], blocks: &mut Vec<f64>) -> bool {
        let f = k.len();
        blocks.clear();
        blocks.resize(f * f, 0.0);
        for a in 0..f {
            blocks[a * f + a] = k[a];
        }
        true
    }

    /// Both variants reach the force criterion on an anisotropic quadratic
    /// well; the criterion itself (Σ g² < 1e-20) is what is asserted.
    #[test]
    fn both_variants_minimise_a_quadratic() {
        for params in [FireParams::default(), FireParams::fire2()] {
            let mut q = Quadratic {
                x: vec![1.0, -2.0, 0.5, 3.0],
                k: vec![1.0, 0.1, 5.0, 0.01],
                inv_m: vec![1.0, 1.0, 10.0, 0.1],
            };
            let mut fire = Fire::new(FireParams {
                energy_tol: 1e-300,
                force_tol: 1e-20,
                force_criterion: ForceCriterion::Sum,
                ..params
            });
            let out = fire.minimize(&mut q).unwrap();
            assert_eq!(out.reason, StopReason::Force);
            let g: f64 = q.x.iter().zip(&q.k).map(|(x, k)| (k * x).powi(2)).sum();
            assert!(g < 1e-20, "{g}");
        }
    }

    /// With the stiffness as its mass, FIRE sees every mode at one
    /// frequency: on a well whose stiffnesses span four decades it must
    /// converge in fewer than a third of the plain FIRE's steps, to the
    /// same criterion (plain FIRE crawls along the softest mode, `k = 10⁻⁴`).
    #[test]
    fn block_masses_relax_an_ill_conditioned_well_faster() {
        let well = || Quadratic {
            x: vec![1.0, -2.0, 0.5, 3.0],
            k: vec![1.0, 1e-4, 5.0, 1e-3],
            inv_m: vec![1.0; 4],
        };
        let steps = |masses: Masses| {
            let mut q = well();
            let out = Fire::new(FireParams {
                energy_tol: 1e-300,
                force_tol: 1e-20,
                force_criterion: ForceCriterion::Sum,
                newton: None,
                masses,
                ..FireParams::default()
            })
            .minimize(&mut q)
            .unwrap();
            assert_eq!(out.reason, StopReason::Force);
            let g: f64 = q.x.iter().zip(&q.k).map(|(x, k)| (k * x).powi(2)).sum();
            assert!(g < 1e-20, "{g}");
            out.steps
        };
        let (plain, blocks) = (
            steps(Masses::Plain),
            steps(Masses::Blocks(PreconParams::default())),
        );
        assert!(3 * blocks < plain, "blocks {blocks} steps, plain {plain}");
    }

    /// A well with one mode of `ω² = 55` (the stability bound of FIRE's
    /// step `2/ω = 0.27`, below the default `Δt_max = 0.5`), a soft one
    /// (`k = 10⁻⁴`) and one of `k = 1`: without `stable_dt` FIRE keeps exciting the stiff
    /// mode and does not converge in 4·10⁵ steps; with it, one check
    /// lowers `Δt_max` to `1.5/ω` and FIRE converges soon after it, to the
    /// same criterion.
    #[test]
    fn stable_dt_ends_the_crawl_of_a_step_above_the_stiff_bound() {
        let run = |stable_dt: bool| {
            let mut q = Quadratic {
                x: vec![1.0, -2.0, 0.3],
                k: vec![55.0, 1e-4, 1.0],
                inv_m: vec![1.0; 3],
            };
            let out = Fire::new(FireParams {
                energy_tol: 1e-300,
                force_tol: 1e-24,
                force_criterion: ForceCriterion::Sum,
                newton: None,
                max_steps: 400_000,
                stable_dt,
                ..FireParams::default()
            })
            .minimize(&mut q);
            (out, q.x)
        };
        assert!(matches!(run(false).0, Err(Error::NotConverged { .. })));
        let (out, x) = run(true);
        let out = out.unwrap();
        assert_eq!(out.dt_cuts, 1);
        assert!(
            out.steps < 2 * crate::stable_dt::STABLE_DT_AFTER,
            "{} steps",
            out.steps
        );
        let g: f64 = (55.0 * x[0]).powi(2) + (1e-4 * x[1]).powi(2) + x[2].powi(2);
        assert!(g < 1e-24, "{g}");
    }

    #[test]
    fn step_cap_gives_an_error() {
        let mut q = Quadratic {
            x: vec![1.0],
            k: vec![1.0],
            inv_m: vec![1.0],
        };
        let mut fire = Fire::new(FireParams {
            energy_tol: 1e-300,
            force_tol: 1e-300,
            max_steps: 10,
            ..FireParams::default()
        });
        assert!(matches!(
            fire.minimize(&mut q),
            Err(Error::NotConverged { steps: 10, .. })
        ));
    }

    /// The residual's largest body share and rotational share: three bodies
    /// of two translations and one rotation each.
    #[test]
    fn residual_shares_find_the_body_and_the_rotations() {
        let g = [0.0, 0.0, 3.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let (body, share, rotational) = residual_shares(&g, 3, 2);
        assert_eq!(body, 0);
        assert!((share - 90.0).abs() < 1e-12 && (rotational - 90.0).abs() < 1e-12);
        let g = [0.0, 2.0, 0.0, 0.0, 0.0, 1.0];
        assert_eq!(residual_shares(&g, 3, 3), (0, 80.0, 0.0));
        assert_eq!(residual_shares(&[0.0; 4], 2, 2), (0, 0.0, 0.0));
    }
}
