//! Shear stabilisation (Dagois-Bohy, Tighe, Simon, Henkes & van Hecke,
//! PRL 109, 095703, 2012): a relaxed packing's cell relaxed over its shape
//! (and its volume at fixed pressure) until the deviatoric stress vanishes
//! and every small deformation is stable ([`stabilise`]). Each step needs
//! the cell's rattlers and its stiffness against the deviatoric strains,
//! measurements the caller hands in (`jamkit_observe::moduli::stabilise`
//! hands in the linear-response stiffness).

use crate::cell::{Strained, determinant, shear_planes};
use crate::fire::{Fire, FireParams};
use crate::objective::Objective;
use crate::scene::Scene;
use jamkit_core::records::ModuliParams;
use jamkit_core::{Error, Matrix, Result, Shape};
use serde::{Deserialize, Serialize};

/// What [`stabilise`] asks of the caller at each step, for the cell as it
/// is: its rattlers, its stiffness `C_kl` against the strains `E_k` it is
/// given (the second derivatives of the relaxed energy, per volume), and
/// why the stiffness fell back to a dense solve, if it did.
#[derive(Clone, Debug, PartialEq)]
pub struct CellStiffness {
    /// The rattlers, whose rows and contacts the stiffness leaves out.
    pub rattler: Vec<bool>,
    /// `C_kl`, symmetric.
    pub stiffness: Vec<Vec<f64>>,
    /// Why a sparse solve fell back to the dense one.
    pub fell_back: Option<String>,
}

/// An orthonormal basis (under `A : B = Σ A_ab B_ab`) of the symmetric
/// traceless (deviatoric) strains: the `D(D−1)/2` shears
/// `(e_a e_bᵀ + e_b e_aᵀ)/√2`, `a < b`, then the `D − 1` normal ones
/// `diag(1, …, 1, −k, 0, …)/√(k + k²)`, `k = 1 … D−1` (2D: `diag(1, −1)/√2`;
/// 3D: `diag(1, −1, 0)/√2`, `diag(1, 1, −2)/√6`).
pub fn deviatoric_basis<const D: usize>() -> Vec<Matrix<D>> {
    let mut out = Vec::new();
    for (a, b) in shear_planes::<D>() {
        let mut e = Matrix::<D>::zeros();
        e[(a, b)] = std::f64::consts::FRAC_1_SQRT_2;
        e[(b, a)] = std::f64::consts::FRAC_1_SQRT_2;
        out.push(e);
    }
    for k in 1..D {
        let mut e = Matrix::<D>::zeros();
        let norm = ((k + k * k) as f64).sqrt();
        for a in 0..k {
            e[(a, a)] = 1.0 / norm;
        }
        e[(k, k)] = -(k as f64) / norm;
        out.push(e);
    }
    out
}

/// How [`stabilise`] relaxes the cell's shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StabiliseParams {
    /// Stop when every deviatoric stress component `|σ : E_k|` is below
    /// `tol · p` and the cell's deviatoric stiffness has no negative
    /// eigenvalue.
    pub tol: f64,
    /// Give up after this many strain steps.
    pub max_iterations: u32,
    /// The largest strain step (Frobenius norm of `δ`); near jamming the
    /// step is also capped at `10 p/μ_max` ([`stabilise`]).
    pub max_step: f64,
    /// The pair list's margin (as for the moduli's check by deformation); the pairs are
    /// listed again before every step.
    pub margin: f64,
    /// How each step's stiffness applies `H⁺` (`solver`) and which modes
    /// it leaves out as zero modes (`omega_zero`). Not read from files:
    /// the runner sets them to the `Moduli` observable's, so that the
    /// stabilisation's steps and the moduli of the stabilised cell count
    /// zero modes alike.
    #[serde(skip)]
    pub moduli: ModuliParams,
}

impl Default for StabiliseParams {
    fn default() -> Self {
        Self {
            tol: 1e-6,
            max_iterations: 200,
            max_step: 1e-2,
            margin: 0.1,
            moduli: ModuliParams::default(),
        }
    }
}

impl StabiliseParams {
    /// Whether every field has its default (an experiment file then
    /// leaves the settings out, so packings made before they existed
    /// resume).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return Err(Error::invalid(
                format!("{prefix}.tol"),
                self.tol,
                "must lie in (0, 1)",
            ));
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid(
                format!("{prefix}.max_iterations"),
                0,
                "must be at least 1",
            ));
        }
        if !(self.max_step > 0.0 && self.max_step <= 0.05) {
            return Err(Error::invalid(
                format!("{prefix}.max_step"),
                self.max_step,
                "must lie in (0, 0.05]",
            ));
        }
        if !(self.margin > 0.0 && self.margin.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.margin"),
                self.margin,
                "must be positive and finite",
            ));
        }
        self.moduli.validate("observables.Moduli")
    }
}

/// What [`stabilise`] holds fixed besides the particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ensemble {
    /// The volume: the energy is minimised over the deviatoric strains.
    Volume,
    /// The pressure `p*`: the enthalpy `U + p* V` is minimised over every
    /// strain (the deviatoric ones and the dilation).
    Pressure(f64),
}

/// A shear-stabilised packing ([`stabilise`]).
#[derive(Clone, Debug)]
pub struct Stabilised<const D: usize, S: Shape<D>> {
    /// The packing in its relaxed, deformed cell (rebased: strains set on
    /// it act on top of the stabilising deformation).
    pub cell: Strained<D, S>,
    /// The cell's deformation `F` from the box it started in: `det F = 1`
    /// at fixed volume; at fixed pressure (the runner's) the dilation is
    /// free and `det F` is the cell's volume over the box's, not 1.
    pub deformation: Matrix<D>,
    /// `max_k |σ : E_k| / p` at the end.
    pub residual: f64,
    /// The same in the fixed box, relaxed in the cell before any strain.
    pub residual_before: f64,
    /// What was minimised (`U`, or `U + p* V` at fixed pressure) in the
    /// fixed box and at the end.
    pub objective_before: f64,
    /// See `objective_before`.
    pub objective_after: f64,
    /// Energy in the fixed box (relaxed in the cell) and at the end.
    pub energy_before: f64,
    /// See `energy_before`.
    pub energy_after: f64,
    /// Pressure in the fixed box and at the end.
    pub pressure_before: f64,
    /// See `pressure_before`.
    pub pressure_after: f64,
    /// Strain steps taken.
    pub iterations: u32,
    /// The smallest eigenvalue of the deviatoric stiffness `C` at the end.
    pub stiffness_min: f64,
    /// Rattlers of the final cell (by count).
    pub rattler: Vec<bool>,
    /// With `solver: Sparse`, the strain steps whose stiffness fell back to
    /// the dense eigendecomposition: the step (`0`: the stiffness of the
    /// relaxed fixed box) and why (`Moduli::dense_fallback`).
    pub dense_fallbacks: Vec<(u32, String)>,
}

/// Eigenvalues (ascending) and eigenvectors (columns) of a small symmetric
/// matrix.
fn symmetric_eigen(m: &[Vec<f64>]) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    let n = m.len();
    let a = faer::Mat::<f64>::from_fn(n, n, |r, c| m[r][c]);
    let evd = a
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let values = (0..n).map(|k| evd.S()[k]).collect();
    let vectors = (0..n)
        .map(|k| (0..n).map(|r| evd.U()[(r, k)]).collect())
        .collect();
    Ok((values, vectors))
}

/// Relax a cell at fixed deformation (the cell lists its pairs again as
/// bodies move, [`Strained`]); fails when the last step moved a body too
/// far for its list ([`Strained::check_pairs`]).
fn relax_cell<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    fire: &FireParams,
) -> Result<()> {
    Fire::new(fire.clone()).minimize(cell)?;
    cell.check_pairs()
}

/// `V/N` at or below which a stabilised cell counts as unjammed (the
/// jamming window's upper edge, `protocol.energy_high`'s default).
const UNJAMMED: f64 = 2e-16;

/// Shear-stabilise a relaxed packing (Dagois-Bohy, Tighe, Simon, Henkes &
/// van Hecke, PRL 109, 095703, 2012): minimise its energy over the
/// coordinates **and** the cell's shape, at fixed volume (or its enthalpy
/// `U + p* V` at fixed pressure, the cell's volume free too), so that the
/// deviatoric stress vanishes (and `p = p*`) and the packing is stable to
/// every small deformation; then every shear modulus is `≥ 0`.
///
/// The cell is a [`Strained`] one (the engine's box is orthorhombic and
/// cannot be sheared); its deformation ranges over all `D(D+1)/2 − 1`
/// deviatoric strains ([`deviatoric_basis`]), and at fixed pressure also
/// over the dilation `E_0 = I/√D`. Alternating: relax the coordinates at
/// fixed cell; list the pairs again; from the generalised stress
/// `s_k = σ : E_k + p* tr E_k` and the stiffness `C` (`deviatoric_stiffness`)
/// take the step `δ = −Σ_m w_m (w_m·s)/μ_m` over the eigenpairs `(μ_m, w_m)`
/// of `C` with `μ_m > 0`, and the cap down the slope along those with
/// `μ_m ≤ 0`; cap `|δ|` at `min(max_step, max(10 p/μ_max, t))` (`μ_max`
/// the largest eigenvalue of `C`; `t` twice the last step's cap if it was
/// taken whole, else the step taken); deform the cell by
/// `F = I + Σ δ_k E_k` (at fixed volume divided by `det(…)^{1/D}`), relax,
/// and keep the step if the minimised function did not rise (by more than
/// 10⁻¹² relative round-off), else halve it (up to 20 times). Stops when
/// every `|s_k| < tol · p` (`p*` at fixed pressure) and `C` has no
/// negative eigenvalue. At fixed volume a packing can unjam (its energy
/// falls to zero: `V/N ≤ 2·10⁻¹⁶`), which is an error. `threshold`: the
/// rattler count rule.
pub fn stabilise<const D: usize, S: Shape<D>>(
    scene: &Scene<D, S>,
    ensemble: Ensemble,
    params: &StabiliseParams,
    fire: &FireParams,
    mut measure: impl FnMut(&mut Strained<D, S>, &[Matrix<D>], f64) -> Result<CellStiffness>,
) -> Result<Stabilised<D, S>> {
    params.validate("stabilise")?;
    let fire = fire.for_family(&scene.packing().shape);
    fire.validate("minimizer")?;
    let mut basis = deviatoric_basis::<D>();
    let external = match ensemble {
        Ensemble::Volume => None,
        Ensemble::Pressure(p) => {
            if !(p > 0.0 && p.is_finite()) {
                return Err(Error::invalid(
                    "pressure",
                    p,
                    "the pressure of a stabilisation at fixed pressure must be positive and finite",
                ));
            }
            basis.insert(0, Matrix::<D>::identity() / (D as f64).sqrt());
            Some(p)
        }
    };
    let bodies = scene.packing().len().max(1) as f64;
    let mut cell = Strained::new(scene, params.margin)?;
    relax_cell(&mut cell, &fire)?;
    let objective = |c: &Strained<D, S>| c.energy() + external.map_or(0.0, |p| p * c.volume());
    let energy_before = cell.energy();
    let objective_before = objective(&cell);
    let pressure_before = cell.pressure();
    if !(pressure_before > 0.0) {
        return Err(Error::invalid(
            "pressure",
            pressure_before,
            "shear stabilisation needs a packing under positive pressure (jammed)",
        ));
    }
    let stress = |c: &Strained<D, S>| -> Vec<f64> {
        let sigma = c.stress();
        (basis.iter())
            .map(|e| sigma.component_mul(e).sum() + external.map_or(0.0, |p| p * e.trace()))
            .collect()
    };
    let largest = |s: &[f64]| s.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let residual_before = largest(&stress(&cell)) / external.unwrap_or(pressure_before);
    let mut value = objective_before;
    let mut iterations = 0;
    let mut trust = 0.0_f64;
    let mut dense_fallbacks = Vec::new();
    loop {
        cell.relist()?;
        let s = stress(&cell);
        let pressure = cell.pressure();
        let reference = external.unwrap_or(pressure);
        let CellStiffness {
            rattler,
            stiffness,
            fell_back,
        } = measure(&mut cell, &basis, reference)?;
        dense_fallbacks.extend(fell_back.map(|why| (iterations, why)));
        let (mu, w) = symmetric_eigen(&stiffness)?;
        let residual = largest(&s) / reference;
        let stiffness_min = mu.first().copied().unwrap_or(0.0);
        let per_body = cell.energy() / bodies;
        if external.is_none() && !(per_body > UNJAMMED && pressure > 0.0) {
            return Err(Error::JammingFailed {
                phi: Objective::phi(&cell),
                steps: iterations as u64,
                reason: format!(
                    "the packing unjammed while its cell's shape relaxed at fixed volume (V/N = {per_body:.3e} after {iterations} strain steps, from {:.3e}): shear stabilisation at fixed volume lowered the energy to zero",
                    energy_before / bodies
                ),
            });
        }
        if residual < params.tol && stiffness_min >= 0.0 {
            let deformation = cell.total_deformation();
            return Ok(Stabilised {
                energy_after: cell.energy(),
                objective_after: objective(&cell),
                cell,
                deformation,
                residual,
                residual_before,
                objective_before,
                energy_before,
                pressure_before,
                pressure_after: pressure,
                iterations,
                stiffness_min,
                rattler,
                dense_fallbacks,
            });
        }
        if iterations >= params.max_iterations {
            return Err(Error::JammingFailed {
                phi: Objective::phi(&cell),
                steps: iterations as u64,
                reason: format!(
                    "shear stabilisation did not converge in {} strain steps (stress residual {residual:.3e} p, tolerance {:e}; smallest stiffness {stiffness_min:.3e})",
                    params.max_iterations, params.tol
                ),
            });
        }
        // The strain cap: `max_step`, and near jamming `10 p/μ_max`, ten
        // times the strain that changes the overlaps by their own size
        // (`μ_max` the stiffest strain's modulus, ~B): a larger kick along
        // a soft or unstable strain rearranges (or unjams) the packing.
        // Grown by 2 after a step taken whole (a trust region), so that a
        // long way down a soft strain takes few steps.
        let stiffest = mu.last().copied().unwrap_or(0.0);
        let base = if stiffest > 0.0 {
            params.max_step.min(10.0 * reference / stiffest)
        } else {
            params.max_step
        };
        let cap = trust.max(base).min(params.max_step);
        let mut step = vec![0.0; basis.len()];
        for (m, wm) in w.iter().enumerate() {
            let along: f64 = wm.iter().zip(&s).map(|(a, b)| a * b).sum();
            let size = if mu[m] > 0.0 {
                -along / mu[m]
            } else {
                // Down the slope (or either way on a flat one) by the cap.
                -cap * if along > 0.0 { 1.0 } else { -1.0 }
            };
            for (x, wk) in step.iter_mut().zip(wm) {
                *x += size * wk;
            }
        }
        let norm = step.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > cap {
            step.iter_mut().for_each(|x| *x *= cap / norm);
        }
        let mut accepted = false;
        for halvings in 0..20 {
            let mut f = Matrix::<D>::identity();
            for (x, e) in step.iter().zip(&basis) {
                f += e * *x;
            }
            if external.is_none() {
                f /= determinant(&f).powf(1.0 / D as f64);
            }
            let mut trial = cell.clone();
            trial.set_deformation(f);
            // The pairs of the deformed cell before it relaxes (a strain
            // of `|δ|` moves a pair's separation by `|δ| r`).
            if trial.relist().is_ok() && relax_cell(&mut trial, &fire).is_ok() {
                let v = objective(&trial);
                if v <= value + 1e-12 * value.abs() {
                    cell = trial;
                    value = v;
                    accepted = true;
                    trust = if halvings == 0 {
                        2.0 * cap
                    } else {
                        cap * 0.5_f64.powi(halvings)
                    };
                    break;
                }
            }
            step.iter_mut().for_each(|x| *x *= 0.5);
        }
        if !accepted {
            return Err(Error::JammingFailed {
                phi: Objective::phi(&cell),
                steps: iterations as u64,
                reason: format!(
                    "shear stabilisation found no strain step that lowers the energy (stress residual {residual:.3e} p, smallest stiffness {stiffness_min:.3e})"
                ),
            });
        }
        iterations += 1;
    }
}
