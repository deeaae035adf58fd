//! The stiffness of a [`Strained`] cell against the deviatoric strains, by
//! linear response: what each step of the engine's shear stabilisation
//! ([`jamkit_engine::stabilise`]) measures ([`cell_stiffness`]).

use jamkit_core::records::ModuliParams;
use jamkit_core::{Matrix, Result, Shape};
use jamkit_engine::cell::Strained;
use jamkit_engine::stabilise::CellStiffness;

use super::cell::CellContacts;
use super::*;

/// The stiffness of a relaxed cell along the strains `basis`: the second
/// derivative per volume of its relaxed energy plus `P V` along
/// `F = I + Σ δ_k E_k`,
/// `C_kl = (A_kl − Ξ_kᵀ H⁺ Ξ_l) / V + P (tr E_k tr E_l − tr E_k E_l)`
/// (`A_kl` by polarisation of the affine terms). At fixed volume (the
/// deviatoric basis, `F` normalised to `det F = 1`) `P` is the cell's own
/// pressure `p` and the last term is `−p δ_kl`: the normalisation's
/// second-order isotropic strain `|δ|²/(2D)` meets `U_γ(I) = −D V p`. At
/// fixed pressure `P = p*`, the enthalpy's `p* V`.
pub(super) fn deviatoric_stiffness<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
    basis: &[Matrix<D>],
    volume_pressure: f64,
) -> Result<(Vec<Vec<f64>>, Option<String>)> {
    let hessian = cell.full_hessian(rattler)?;
    let n = hessian.size;
    let lambda_zero = params.omega_zero * params.omega_zero;
    let (inverse, fallback) =
        PseudoInverse::of(&hessian, D, lambda_zero, params.solver, LANCZOS_TOL_STEP)?;
    let kk = basis.len();
    let mut single = Vec::new();
    for e in basis {
        single.push(strain_derivatives_of(cell, rattler, &hessian, e)?);
    }
    // `Ξ_kᵀ H⁺ Ξ_l`.
    let mut non_affine = vec![vec![0.0; kk]; kk];
    match &inverse {
        PseudoInverse::Dense(values, vectors) => {
            let coefficients = |xi: &[f64]| -> Vec<f64> {
                (0..n)
                    .map(|m| (0..n).map(|r| vectors[(r, m)] * xi[r]).sum())
                    .collect()
            };
            let c: Vec<Vec<f64>> = single.iter().map(|d| coefficients(&d.xi)).collect();
            for k in 0..kk {
                for l in k..kk {
                    non_affine[k][l] = (0..n)
                        .filter(|&m| values[m] > lambda_zero)
                        .map(|m| c[k][m] * c[l][m] / values[m])
                        .sum();
                }
            }
        }
        PseudoInverse::Sparse(s) => {
            let projected: Vec<Vec<f64>> = (single.iter())
                .map(|d| {
                    let mut xi = d.xi.clone();
                    s.project(&mut xi);
                    xi
                })
                .collect();
            let solved: Vec<Vec<f64>> = projected.iter().map(|xi| s.solve(xi)).collect();
            for k in 0..kk {
                for l in k..kk {
                    non_affine[k][l] = (projected[k].iter().zip(&solved[l]))
                        .map(|(a, b)| a * b)
                        .sum();
                }
            }
        }
    }
    let volume = cell.volume();
    let mut out = vec![vec![0.0; kk]; kk];
    for k in 0..kk {
        for l in k..kk {
            let affine = if k == l {
                single[k].affine
            } else {
                let both = strain_derivatives_of(cell, rattler, &hessian, &(basis[k] + basis[l]))?;
                0.5 * (both.affine - single[k].affine - single[l].affine)
            };
            // `P ∂²det(I + Σ δ E)/∂δ_k∂δ_l = P (tr E_k tr E_l − tr E_k E_l)`.
            let volume_term = volume_pressure
                * (basis[k].trace() * basis[l].trace() - (basis[k] * basis[l]).trace());
            let v = (affine - non_affine[k][l]) / volume + volume_term;
            out[k][l] = v;
            out[l][k] = v;
        }
    }
    Ok((out, fallback))
}

/// The stiffness `C_kl` of a relaxed cell along the strains `basis`, as
/// [`stabilise`] uses it in each step (`volume_pressure` the `P` there:
/// the cell's pressure at fixed volume, `p*` at fixed pressure), with the
/// reason when `params.solver` is `Sparse` and the dense path was taken.
pub fn stiffness_tensor<const D: usize, S: Shape<D>>(
    cell: &mut Strained<D, S>,
    rattler: &[bool],
    params: &ModuliParams,
    basis: &[Matrix<D>],
    volume_pressure: f64,
) -> Result<(Vec<Vec<f64>>, Option<String>)> {
    params.validate("moduli")?;
    deviatoric_stiffness(cell, rattler, params, basis, volume_pressure)
}

/// The measurement a shear stabilisation
/// ([`jamkit_engine::stabilise::stabilise`]) asks at each step: the cell's
/// rattlers by count (`threshold`) and its stiffness by linear response with
/// `params` ([`stiffness_tensor`]).
pub fn cell_stiffness<const D: usize, S: Shape<D>>(
    threshold: usize,
    params: &ModuliParams,
) -> impl FnMut(&mut Strained<D, S>, &[Matrix<D>], f64) -> Result<CellStiffness> + '_ {
    move |cell, basis, reference| {
        let rattler = cell.rattlers(threshold);
        let (stiffness, fell_back) =
            deviatoric_stiffness(cell, &rattler, params, basis, reference)?;
        Ok(CellStiffness {
            rattler,
            stiffness,
            fell_back,
        })
    }
}
