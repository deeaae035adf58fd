//! FIRE's time step against the stiffest mode ([`crate::FireParams::stable_dt`]).
//!
//! FIRE's semi-implicit Euler step is stable on a vibration of angular
//! frequency `ω` only while `Δt < 2/ω`, and it crawls well before that
//! bound: the stiffest mode is then never damped, FIRE's power test keeps
//! halving `Δt` and growing it back to `Δt_max`, and the residual force
//! sits on that mode. A jammed disk packing has `ω_max² ≈ 5.4`, so the
//! default `Δt_max = 0.5` is far below the bound; two non-convex outlines
//! that overlap along flanks of nearly the same curvature can make a mode
//! ten times stiffer (`ω_max² ≈ 55` in a near-disk packing of `n = 16`,
//! `Δ = 0.3`, where `Δt_max = 0.5` is 1.86 times the bound and FIRE did
//! not converge in 3·10⁵ steps; with `Δt_max` = 0.23 it converges in 6000).
//!
//! A minimisation that has not converged after [`STABLE_DT_AFTER`] FIRE
//! steps (and again every [`STABLE_DT_AFTER`] steps) estimates `ω_max²`,
//! the largest eigenvalue of `M^{-1/2} H M^{-1/2}`, by power iteration on
//! the analytic Hessian, and lowers `Δt_max` to [`STABLE_DT_FRACTION`]
//! `· 2/ω_max` where it is above that. A minimisation that converges
//! sooner, or whose `Δt_max` is already below, is untouched bit for bit.

use crate::objective::Objective;
use jamkit_core::Result;

/// FIRE steps of a minimisation before its first check of `Δt_max`
/// against the stiffest mode, and between two checks.
pub const STABLE_DT_AFTER: u64 = 20_000;

/// The largest `Δt_max` a check leaves, as a fraction of the stability
/// bound `2/ω_max`: 0.75, that is `Δt_max ≤ 1.5/ω_max`. (The stalled
/// near-disk state above converges at 0.86 of the bound and not at 0.97.)
pub const STABLE_DT_FRACTION: f64 = 0.75;

/// Power iterations of one estimate of `ω_max²` at most.
const ITERATIONS: usize = 200;

/// The power iteration stops when its Rayleigh quotient changes by less
/// than this, relative.
const REL_TOL: f64 = 1e-4;

/// Work buffers of [`omega_max_sq`], reused across checks.
#[derive(Clone, Debug, Default)]
pub struct StableDtWork {
    entries: Vec<(u32, u32, f64)>,
    x: Vec<f64>,
    y: Vec<f64>,
}

/// The largest eigenvalue of `M^{-1/2} H M^{-1/2}` at `obj`'s current
/// state (`inv_m` the inverse masses), by power iteration from a fixed
/// start, so the same state gives the same estimate. An estimate from
/// below: the Rayleigh quotient of the last iterate. `None` where the
/// objective has no Hessian or the Hessian vanishes.
pub fn omega_max_sq<O: Objective>(
    obj: &mut O,
    inv_m: &[f64],
    w: &mut StableDtWork,
) -> Result<Option<f64>> {
    w.entries.clear();
    if !obj.hessian_entries(&mut w.entries)? {
        return Ok(None);
    }
    let n = inv_m.len();
    // A = D H D with D = M^{-1/2}: scale the entries once.
    for e in w.entries.iter_mut() {
        e.2 *= (inv_m[e.0 as usize] * inv_m[e.1 as usize]).sqrt();
    }
    // A start with a share of every coordinate, fixed (a Weyl sequence).
    w.x.clear();
    w.x.extend((0..n).map(|a| 0.5 + ((a as f64) * 0.618_033_988_749_895).fract()));
    w.y.resize(n, 0.0);
    let mut rayleigh = 0.0;
    for _ in 0..ITERATIONS {
        let norm = w.x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 || !norm.is_finite() {
            return Ok(None);
        }
        w.x.iter_mut().for_each(|v| *v /= norm);
        w.y.fill(0.0);
        for &(r, c, h) in &w.entries {
            w.y[r as usize] += h * w.x[c as usize];
        }
        let next: f64 = w.x.iter().zip(&w.y).map(|(a, b)| a * b).sum();
        std::mem::swap(&mut w.x, &mut w.y);
        let done = (next - rayleigh).abs() <= REL_TOL * next.abs();
        rayleigh = next;
        if done {
            break;
        }
    }
    Ok((rayleigh > 0.0).then_some(rayleigh))
}

/// `Δt_max` after a check: `dt_max`, or `STABLE_DT_FRACTION · 2/ω_max`
/// where that is smaller.
pub fn capped(dt_max: f64, omega_max_sq: f64) -> f64 {
    dt_max.min(STABLE_DT_FRACTION * 2.0 / omega_max_sq.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadratic energy `½ qᵀ K q` with masses.
    struct Quadratic {
        k: Vec<Vec<f64>>,
        inv_m: Vec<f64>,
    }

    impl Objective for Quadratic {
        fn dof(&self) -> usize {
            self.inv_m.len()
        }
        fn bodies(&self) -> usize {
            self.inv_m.len()
        }
        fn inverse_masses(&self) -> &[f64] {
            &self.inv_m
        }
        fn energy_gradient(&mut self, _grad: &mut [f64]) -> f64 {
            0.0
        }
        fn displace(&mut self, _dq: &[f64]) {}
        fn phi(&self) -> f64 {
            0.0
        }
        fn hessian_entries(&mut self, e: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
            for (r, row) in self.k.iter().enumerate() {
                for (c, &v) in row.iter().enumerate() {
                    if v != 0.0 {
                        e.push((r as u32, c as u32, v));
                    }
                }
            }
            Ok(true)
        }
    }

    /// A chain of springs of stiffness 1 with one spring of stiffness
    /// `stiff` and unequal masses, against the dense eigenvalues of
    /// `M^{-1/2} K M^{-1/2}` (faer). Power iteration converges on the top
    /// eigenvalue at the rate (λ₂/λ₁)²; with a gap of more than 3× the
    /// estimate is within the 10⁻³ asserted (relative).
    #[test]
    fn the_estimate_is_the_largest_eigenvalue_of_the_mass_weighted_hessian() {
        let n = 12;
        let stiff = 40.0;
        let mut k = vec![vec![0.0; n]; n];
        for a in 0..n - 1 {
            let s = if a == 5 { stiff } else { 1.0 };
            k[a][a] += s;
            k[a + 1][a + 1] += s;
            k[a][a + 1] -= s;
            k[a + 1][a] -= s;
        }
        let inv_m: Vec<f64> = (0..n).map(|a| 1.0 / (1.0 + 0.1 * a as f64)).collect();
        let dense = faer::Mat::<f64>::from_fn(n, n, |r, c| k[r][c] * (inv_m[r] * inv_m[c]).sqrt());
        let exact = *dense
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .unwrap()
            .last()
            .unwrap();
        let mut q = Quadratic {
            k,
            inv_m: inv_m.clone(),
        };
        let est = omega_max_sq(&mut q, &inv_m, &mut StableDtWork::default())
            .unwrap()
            .unwrap();
        assert!(
            (est - exact).abs() <= 1e-3 * exact,
            "power iteration {est} against the dense eigenvalue {exact}"
        );
        assert!(
            est <= exact * (1.0 + 1e-12),
            "a Rayleigh quotient is below λ_max"
        );
    }

    #[test]
    fn the_cap_is_three_quarters_of_the_stability_bound_and_never_raises() {
        assert_eq!(capped(0.5, 4.0), 0.5);
        assert!((capped(0.5, 100.0) - 0.15).abs() < 1e-15);
        assert_eq!(capped(0.1, 100.0), 0.1);
    }
}
