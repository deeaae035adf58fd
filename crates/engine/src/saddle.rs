//! Saddle escape after the jamming bisection.
//!
//! **Why.** For rigid dimers the Hessian `K + T` of the *non-rattlers*
//! (contacts of rattlers dropped) has a few eigenvalues `≈ −10⁻⁸` at the
//! end of the paper's protocol, which suggested that the bisection stops on
//! saddles (the gradient there is already below FIRE's stopping rule). This
//! module pushes the packing off such saddles. **Measured** (2D dimers
//! N = 64–128, 3D N = 64, `docs/reports/sanity.md`): the *true* Hessian
//! `∂²V/∂q∂q` (every contact) has no negative eigenvalue on any of those
//! packings; the negative modes of the other one came from dropping the
//! contacts of bodies that touch on one sphere only (three contacts in 2D),
//! which carry force. So with the default [`SaddleParams::full_hessian`]
//! the escape makes no push on them, and it is off by default
//! (`Protocol::Jam { escape_saddles }`); it stays as a check.
//!
//! **What.** While the lowest eigenvalue of the Hessian (see [`SaddleParams::full_hessian`]) is
//! below `−threshold · λ_max`, push the configuration along its eigenvector
//! (the sign that lowers the energy; the step is small, see
//! [`SaddleParams::step`]) and re-run the jamming bisection from the
//! current φ with a small initial `ε`, so that the packing ends again in the
//! same window `E_low < V/N < E_high` with the same FIRE tolerances. Stop
//! after `max_rounds` rounds.
//!
//! The push and the re-jam are sequential and depend on the configuration
//! only; the eigenvector comes from faer's dense solver,
//! whose thread-count independence was not checked (with no push made, as
//! measured, the packing is the bisection's, bit for bit).

use crate::hessian::{Hessian, HessianOptions};
use crate::{Fire, JamParams, Objective, Scene, jam};
use jamkit_core::{Error, Result, Shape};

/// Parameters of the saddle escape.
#[derive(Clone, Debug, PartialEq)]
pub struct SaddleParams {
    /// A mode is unstable when `λ < −threshold · λ_max`. The default
    /// `10⁻¹⁰` lies far above the eigensolver's noise (`~10⁻¹⁵ λ_max`) and
    /// well below the stress scale of the saddles seen (`~10⁻⁸`, with
    /// `λ_max = O(1)`).
    pub threshold: f64,
    /// First amplitude of the line search along the mode: the largest
    /// coordinate change, in units of the smallest body size (`10⁻⁶`: at
    /// `10⁻⁴` the quartic stiffening of floppy directions, `~s⁴`, already
    /// beats a curvature of `−10⁻⁸`, so the search must start below
    /// `√(10⁻⁸)`); it doubles while the energy falls.
    pub step: f64,
    /// Largest amplitude tried by the line search, in the same units.
    pub max_push: f64,
    /// Initial `ε` of the bisection after each push.
    pub eps: f64,
    /// Use the true Hessian `∂²V/∂q∂q` (every contact, rattlers kept: their
    /// rows add zero modes, never negative ones) rather than `K + T` of the
    /// non-rattlers. Measured (docs/reports/sanity.md): the negative modes
    /// of the latter are an artefact of dropping the contacts of bodies
    /// below the rattler threshold that still carry force; the true Hessian
    /// has none.
    pub full_hessian: bool,
    /// At most this many pushes.
    pub max_rounds: u32,
}

impl Default for SaddleParams {
    fn default() -> Self {
        Self {
            threshold: 1e-10,
            step: 1e-6,
            max_push: 0.1,
            eps: 1e-6,
            max_rounds: 20,
            full_hessian: true,
        }
    }
}

/// What the escape did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SaddleOutcome {
    /// Pushes made (0: the end state of the bisection was stable).
    pub rounds: u32,
    /// Whether the last state checked is still a saddle (the cap was hit).
    pub still_saddle: bool,
    /// Lowest relative eigenvalue `λ_min/λ_max` of the final state.
    pub lambda_min_rel: f64,
    /// FIRE steps of the re-run bisections.
    pub fire_steps: u64,
    /// L-BFGS evaluations of the re-run bisections.
    pub lbfgs_evaluations: u64,
    /// Minimisations of the re-run bisections.
    pub minimizations: u64,
    /// Final packing fraction.
    pub phi: f64,
    /// Final `V/N`.
    pub energy_per_particle: f64,
}

/// Lowest eigenpair and `λ_max` of the true Hessian (`full`) or of `K + T`
/// of the non-rattlers, with the eigenvector spread back to the scene's
/// flat coordinates (zero on removed rattlers).
fn lowest_mode<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattlers: &mut impl FnMut(&mut Scene<D, S>) -> Vec<bool>,
    full: bool,
) -> Result<(f64, f64, Vec<f64>)> {
    let rattler = if full { Vec::new() } else { rattlers(scene) };
    let h = Hessian::of_scene(
        scene,
        &rattler,
        HessianOptions {
            stiffness_only: false,
            remove_rattlers: true,
        },
    )?;
    let mut flat = vec![0.0; scene.dof()];
    if h.size == 0 {
        return Ok((0.0, 0.0, flat));
    }
    let evd = h
        .dense()
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let (u, s) = (evd.U(), evd.S());
    let stride = scene.dof() / scene.bodies();
    // Rows come body by body, `stride` coordinates each, in FIRE's order.
    for row in 0..h.size {
        let within = row % stride;
        flat[h.body[row] as usize * stride + within] = u[(row, 0)];
    }
    Ok((s[0], s[h.size - 1], flat))
}

/// Push `scene` off saddles of `K + T` and re-jam, as described in the
/// module documentation; `rattlers` marks the rattlers of a scene (asked
/// only without [`SaddleParams::full_hessian`]).
pub fn escape_saddles<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    jam_params: &JamParams,
    params: &SaddleParams,
    mut rattlers: impl FnMut(&mut Scene<D, S>) -> Vec<bool>,
) -> Result<SaddleOutcome> {
    let mut out = SaddleOutcome {
        phi: scene.phi(),
        energy_per_particle: scene.energy() / scene.bodies() as f64,
        ..SaddleOutcome::default()
    };
    let size = scene
        .packing()
        .sizes
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let rejam = JamParams {
        eps: params.eps,
        ..jam_params.clone()
    };
    loop {
        let (lmin, lmax, mode) = lowest_mode(scene, &mut rattlers, params.full_hessian)?;
        out.lambda_min_rel = if lmax > 0.0 { lmin / lmax } else { 0.0 };
        let saddle = lmin < -params.threshold * lmax;
        out.still_saddle = saddle;
        if !saddle || out.rounds >= params.max_rounds {
            return Ok(out);
        }
        let biggest = mode.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let unit: Vec<f64> = mode.iter().map(|x| x * size / biggest).collect();
        push(scene, &unit, params);
        let o = jam(scene, fire, &rejam)?;
        out.rounds += 1;
        out.fire_steps += o.fire_steps;
        out.lbfgs_evaluations += o.lbfgs_evaluations;
        out.minimizations += o.minimizations;
        out.phi = o.phi;
        out.energy_per_particle = o.energy_per_particle;
    }
}

/// Line search along `±unit` (largest component = the smallest body size):
/// amplitudes `step · 2^k`, `k = 0, 1, …` up to `max_push`, for each sign
/// while the energy keeps falling; the configuration is left at the lowest
/// energy seen (at the start if nothing was lower). Deterministic: the
/// amplitudes and the order of trials are fixed.
fn push<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>, unit: &[f64], params: &SaddleParams) {
    let e0 = scene.energy();
    let mut best = (e0, 0.0);
    let mut moved = 0.0;
    let go_to = |scene: &mut Scene<D, S>, amp: f64, moved: &mut f64| {
        let dq: Vec<f64> = unit.iter().map(|x| x * (amp - *moved)).collect();
        scene.displace(&dq);
        *moved = amp;
        scene.energy()
    };
    for sign in [1.0, -1.0] {
        let mut last = e0;
        let mut amp = params.step;
        while amp <= params.max_push {
            let e = go_to(scene, sign * amp, &mut moved);
            if e < best.0 {
                best = (e, sign * amp);
            }
            if e > last {
                break;
            }
            last = e;
            amp *= 2.0;
        }
    }
    go_to(scene, best.1, &mut moved);
}
