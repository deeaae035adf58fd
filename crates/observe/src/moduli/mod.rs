//! Elastic moduli above jamming: the stress tensor, the strain derivatives
//! of the energy, and the shear and bulk moduli by linear response, with a
//! check by deformation.
//!
//! **Strain.** A homogeneous strain deforms the periodic cell by
//! `F = I + γ E` and carries every separation with it, `r_ij → F r_ij`
//! (the centres move affinely; the bodies' orientations do not: rigid
//! bodies are not deformed, their rotation is part of the non-affine
//! relaxation). Here `E = e_a e_bᵀ` (`a ≠ b`) is a simple shear of the
//! `(a, b)` plane (`x_a += γ x_b`) and `E = I` an isotropic dilation. A
//! gap depends on the centres only through `r_ij`, so with
//! `g = ∂h/∂r_j`, `K_rr = ∂²h/∂r_j∂r_j` and `t = E r_ij` (the
//! [`GapHessian`] contract):
//!
//! ```text
//! ∂h/∂γ = g·t,      ∂²h/∂γ² = tᵀ K_rr t,
//! ∂²h/∂γ∂r_j = K_rr t = −∂²h/∂γ∂r_i,     ∂²h/∂γ∂q_i[a] = r_qi[a]·t,
//! ```
//!
//! and for `U = Σ_c v(h_c)`
//!
//! ```text
//! U_γ  = Σ_c v' g·t,
//! A    = ∂²U/∂γ²   = Σ_c [v'' (g·t)² + v' tᵀ K_rr t]          (affine),
//! Ξ_j  = ∂²U/∂γ∂r_j = Σ_c [v'' (g·t) g + v' K_rr t]  (−Ξ_i),
//! Ξ_qi = Σ_c [v'' (g·t) ∂h/∂q_i + v' r_qi·t]                     (non-affine force field).
//! ```
//!
//! **Stress.** `σ_ab = (1/V) Σ_c v'(h_c) g_a r_b` (`V` the box volume), so
//! that `V σ_ab = U_γ` for `E = e_a e_bᵀ` and the pressure is
//! `p = −tr σ / D` ([`jamkit_engine::Scene::pressure`]).
//!
//! **Moduli.** Relaxing the coordinates `q` (translations and rotations) at
//! fixed strain, `U_min(γ)` has second derivative `A − Ξᵀ H⁺ Ξ` at a
//! minimum, with `H` the full Hessian (stiffness and stress parts, rattlers
//! removed) and `H⁺` its pseudo-inverse on the modes with `ω = √λ` above
//! `omega_zero` (the zero modes as [`crate::spectrum`] counts them: the `D`
//! global translations, and any others, which are reported). Then
//!
//! ```text
//! G_ab = (A − Ξᵀ H⁺ Ξ) / V        (simple shear of the (a, b) plane; = dσ_ab/dγ),
//! B    = (A − Ξᵀ H⁺ Ξ) / (D² V) + (D − 1) p / D     (E = I; = −V dp/dV),
//! ```
//!
//! and `G` is the mean of `G_ab` over the `D(D−1)/2` planes. `G_ab` is the
//! slope of the shear stress under simple shear (`V σ_ab = dU_min/dγ`
//! along the relaxed path, volume constant); the bulk modulus takes the
//! change of volume into account (`V = V₀(1+γ)^D`). With `v'` terms left
//! out (`A`, `Ξ` and `H` at zero force) these are the O'Hern et al. (2003)
//! moduli; at a pressure `p` the stress terms shift `G` by `O(p)`.
//!
//! **Check by deformation.** [`Strained`] is the packing in a deformed
//! periodic cell (Lees–Edwards for a simple shear): the pairs of the
//! unstrained packing with their image vectors fixed, separations
//! `F r_ij + u_j − u_i`. It is an [`Objective`], so the engine's minimiser
//! relaxes it at fixed strain; [`by_deformation`] measures
//! `G_ab = (σ_ab(+γ) − σ_ab(−γ)) / 2γ` and `B = −(p(+γ) − p(−γ)) / (2Dγ)`.
//! (The periodic box of the engine is orthorhombic and cannot be sheared,
//! hence the fixed image vectors; they stay exact while no body moves by
//! more than the pair margin, which is checked.)
//!
//! **Files.** `strain.rs`: the stress tensor and the strain derivatives;
//! this file: the moduli by linear response; `cell.rs`: the contacts and
//! strain derivatives of a [`Strained`] cell (the cell itself is the
//! engine's, `jamkit_engine::cell`); `deformation.rs`: the check by
//! deformation; `stabilise.rs`: the stiffness each step of the engine's
//! shear stabilisation (`jamkit_engine::stabilise`) measures
//! ([`cell_stiffness`]).

mod cell;
mod deformation;
mod stabilise;
mod strain;

pub use cell::CellContacts;
pub use deformation::{
    Deformation, by_deformation, by_deformation_strained, deformation_minimizer,
};
pub use jamkit_engine::cell::Strained;
pub use jamkit_engine::stabilise::{Ensemble, StabiliseParams, Stabilised, deviatoric_basis};
pub use stabilise::{cell_stiffness, stiffness_tensor};
use strain::{Cell, FULL_HESSIAN, strain_derivatives_of};
pub use strain::{
    StrainDerivatives, shear_planes, simple_shear, strain_derivatives, stress_tensor,
};

use crate::hessian::Hessian;
use crate::pinverse::SparseInverse;
use crate::spectrum::ZeroModes;
pub use jamkit_core::records::{Moduli, ModuliParams, ModuliSolver};
use jamkit_core::{Error, Matrix, Result, Shape};
use jamkit_engine::Scene;

/// Relative residual to which Lanczos finds the softest mode for
/// [`measure`] (its eigenvector gives `soft_share`).
const LANCZOS_TOL: f64 = 1e-9;
/// The same in each strain step of [`stabilise`], where only its
/// eigenvalue is needed (to know that no mode but the translations is at
/// or below `ω_zero²`).
const LANCZOS_TOL_STEP: f64 = 1e-4;

/// The linear-response moduli of a relaxed scene; `rattler` marks the
/// rattlers, whose rows and contacts are removed.
pub fn measure<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    measure_cell(scene, rattler, params)
}

/// The linear-response moduli of a relaxed [`Strained`] cell (the same
/// definitions as [`measure`], in the deformed cell: `V` its volume, the
/// strains applied on top of its deformation); `rattler` as there.
pub fn measure_strained<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    measure_cell(cell, rattler, params)
}

/// `H⁺` of a Hessian: its modes, or a sparse factorisation.
enum PseudoInverse {
    /// Eigenvalues (ascending) and eigenvectors.
    Dense(Vec<f64>, faer::Mat<f64>),
    /// `crate::pinverse`.
    Sparse(SparseInverse),
}

impl PseudoInverse {
    /// By `solver`; with the reason when `Sparse` fell back to the dense
    /// modes.
    fn of(
        hessian: &Hessian,
        dim: usize,
        lambda_zero: f64,
        solver: ModuliSolver,
        tol: f64,
    ) -> Result<(Self, Option<String>)> {
        let fallback = match solver {
            ModuliSolver::Dense => None,
            ModuliSolver::Sparse => match SparseInverse::new(hessian, dim, lambda_zero, tol) {
                Ok(inverse) => return Ok((Self::Sparse(inverse), None)),
                Err(reason) => Some(reason),
            },
        };
        let (values, vectors) = modes(hessian)?;
        Ok((Self::Dense(values, vectors), fallback))
    }
}

/// The eigenvalues and eigenvectors of a Hessian (ascending).
fn modes(hessian: &Hessian) -> Result<(Vec<f64>, faer::Mat<f64>)> {
    let n = hessian.size;
    if n == 0 {
        return Ok((Vec::new(), faer::Mat::<f64>::zeros(0, 0)));
    }
    let evd = hessian
        .dense()
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let values: Vec<f64> = (0..n).map(|m| evd.S()[m]).collect();
    Ok((values, evd.U().to_owned()))
}

fn measure_cell<const D: usize, C: Cell<D>>(
    scene: &mut C,
    rattler: &[bool],
    params: &ModuliParams,
) -> Result<Moduli> {
    params.validate("moduli")?;
    let hessian = scene.full_hessian(rattler)?;
    let n = hessian.size;
    let volume = scene.cell_volume();
    let lambda_zero = params.omega_zero * params.omega_zero;
    let (inverse, dense_fallback) =
        PseudoInverse::of(&hessian, D, lambda_zero, params.solver, LANCZOS_TOL)?;
    let relaxed = |d: &StrainDerivatives| match &inverse {
        PseudoInverse::Dense(values, vectors) => relaxed_dense(values, vectors, lambda_zero, d),
        PseudoInverse::Sparse(s) => relaxed_sparse(s, d),
    };
    let mut floppy_share: f64 = 0.0;
    let planes = shear_planes::<D>();
    let mut per_plane = Vec::new();
    let mut shear_affine = 0.0;
    let mut soft_share = None;
    for &(a, b) in &planes {
        let d = strain_derivatives_of(scene, rattler, &hessian, &simple_shear::<D>(a, b))?;
        let (c, share, soft) = relaxed(&d);
        floppy_share = floppy_share.max(share);
        if per_plane.iter().all(|&g| c / volume < g) {
            soft_share = soft;
        }
        per_plane.push(c / volume);
        shear_affine += d.affine / volume / planes.len() as f64;
    }
    let d = strain_derivatives_of(scene, rattler, &hessian, &Matrix::<D>::identity())?;
    let (c, share, _) = relaxed(&d);
    floppy_share = floppy_share.max(share);
    let dd = (D * D) as f64;
    // `U_γ = Σ v' g·r = −D V p` for `E = I`.
    let pressure = -d.first / (D as f64 * volume);
    let stress_term = (D as f64 - 1.0) * pressure / D as f64;
    // The sparse path is taken only when the translations are the only
    // zero modes and no mode is negative (`crate::pinverse`).
    let (total, negative_modes) = match &inverse {
        PseudoInverse::Dense(values, _) => (
            values.iter().filter(|&&l| l <= lambda_zero).count() as u64,
            values.iter().filter(|&&l| l < -lambda_zero).count() as u64,
        ),
        PseudoInverse::Sparse(_) => (D as u64, 0),
    };
    let translations = if n == 0 { 0 } else { D as u64 };
    Ok(Moduli {
        shear: per_plane.iter().sum::<f64>() / planes.len().max(1) as f64,
        shear_planes: per_plane,
        bulk: c / (dd * volume) + stress_term,
        shear_affine,
        bulk_affine: d.affine / (dd * volume) + stress_term,
        pressure,
        coordinates: n,
        zero_modes: ZeroModes {
            total,
            translations,
            rattlers: 0,
            extra: total as i64 - translations as i64,
        },
        negative_modes,
        floppy_share,
        soft_share,
        dense_fallback,
    })
}

/// `(U_min'', share of |Ξ|² on the zero modes, share of the non-affine
/// term on the softest mode)` from the dense modes: `U_min'' = A −
/// Σ_{λ > λ0} (u·Ξ)²/λ`, where translations carry none of `Ξ` (it sums to
/// zero over bodies).
fn relaxed_dense(
    values: &[f64],
    vectors: &faer::Mat<f64>,
    lambda_zero: f64,
    d: &StrainDerivatives,
) -> (f64, f64, Option<f64>) {
    let n = values.len();
    // The softest mode above the zero modes (eigenvalues ascend).
    let softest = values.iter().position(|&l| l > lambda_zero);
    let mut non_affine = 0.0;
    let (mut on_zero, mut total) = (0.0, 0.0);
    let mut on_softest = 0.0;
    for m in 0..n {
        let c: f64 = (0..n).map(|r| vectors[(r, m)] * d.xi[r]).sum();
        total += c * c;
        if values[m] > lambda_zero {
            non_affine += c * c / values[m];
            if Some(m) == softest {
                on_softest = c * c / values[m];
            }
        } else {
            on_zero += c * c;
        }
    }
    let share = if total > 0.0 { on_zero / total } else { 0.0 };
    let soft = (softest.is_some() && non_affine > 0.0).then(|| on_softest / non_affine);
    (d.affine - non_affine, share, soft)
}

/// The same as [`relaxed_dense`] by the sparse solve: `Ξ`'s component
/// along the translations (the only zero modes here) is projected out and
/// is the share, `Ξᵀ H⁺ Ξ = Ξ_P · x` with `H x = Ξ_P`, and the softest
/// mode is Lanczos's.
fn relaxed_sparse(inverse: &SparseInverse, d: &StrainDerivatives) -> (f64, f64, Option<f64>) {
    let total: f64 = d.xi.iter().map(|x| x * x).sum();
    let mut xi = d.xi.clone();
    let on_zero = inverse.project(&mut xi);
    let x = inverse.solve(&xi);
    let non_affine: f64 = xi.iter().zip(&x).map(|(a, b)| a * b).sum();
    let c: f64 = inverse.softest.iter().zip(&xi).map(|(a, b)| a * b).sum();
    let on_softest = c * c / inverse.lambda_min;
    let share = if total > 0.0 { on_zero / total } else { 0.0 };
    let soft = (non_affine > 0.0).then(|| on_softest / non_affine);
    (d.affine - non_affine, share, soft)
}
