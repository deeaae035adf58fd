//! `H⁺` applied to strain fields by a sparse factorisation: the moduli's
//! non-affine term `Ξᵀ H⁺ Ξ` without the dense eigendecomposition of the
//! Hessian (`ModuliSolver::Sparse`, [`crate::moduli`]).
//!
//! **Zero modes.** The Hessian handed here has the rattlers' rows removed
//! already. A periodic packing's Hessian has the `D` global translations as
//! exact zero modes (every contact's rows sum to zero over a uniform
//! translation; rotations are not among them: a body's orientation is
//! measured against the fixed axes of the cell). They are removed
//! explicitly: the `D` translation rows of one body (the first) are left
//! out ("pinned"), and the rest, `H_r`, is factorised by sparse Cholesky
//! ([`jamkit_engine::newton::sparse_cholesky`], the Newton finish's).
//!
//! * If `H` has no zero mode besides the translations, `H_r` is positive
//!   definite (a null vector of `H_r`, padded with zeros, would be one of
//!   `H` with the pinned body at rest, which no translation is). Then for
//!   `b ⟂ T` (`T` the translations) the padded solution `x` of
//!   `H_r x_r = b_r` solves `H x = b` (the pinned rows hold because `b` is
//!   in the range of `H`) and `bᵀ x = bᵀ H⁺ b`: the translation part of
//!   `x` is orthogonal to `b`.
//! * `Ξ` is orthogonal to the translations in exact arithmetic (each
//!   contact adds `±Ξ_r` to its two bodies); its component along them (at
//!   round-off) is projected out first and reported as the share of `|Ξ|²`
//!   on zero modes, as the dense path does.
//! * The dense path leaves out of `H⁺` every mode with `λ ≤ ω_zero²`
//!   ([`crate::spectrum`]'s rule: `ω = √max(λ, 0) ≤ omega_zero`), so the
//!   sparse one must know that there is none besides the translations.
//!   Cholesky succeeding says `λ_{D+1}(H) ≥ λ_min(H_r) > 0` (Cauchy
//!   interlacing, `H_r` a principal submatrix of size `n − D`), not that it
//!   is above `ω_zero²`. So `λ_{D+1}` itself, the softest mode above the
//!   translations, is found by Lanczos on `P H⁺ P` (`P` the projector off
//!   the translations; each step one pair of triangular solves): its
//!   largest eigenvalue is `1/λ_{D+1}`. The sparse path is taken only when
//!   `λ_{D+1} > 2 ω_zero²`; otherwise (and when Cholesky fails: an
//!   unstable or marginal packing, or Lanczos does not converge) the
//!   caller falls back to the dense path and says why.
//!
//! The mode found by Lanczos is also the one whose share of the
//! non-affine term the moduli report (`soft_share`).

use crate::hessian::Hessian;
use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::Triplet;
use faer::sparse::linalg::solvers::Llt;
use jamkit_engine::newton::sparse_cholesky;

/// Lanczos steps at most (each a pair of triangular solves and a
/// reorthogonalisation against the steps before).
const MAX_LANCZOS: usize = 300;
/// Lanczos steps at least before convergence is accepted (so that a
/// start vector poor in the softest mode does not stop it early).
const MIN_LANCZOS: usize = 20;

/// `H⁺` of a Hessian without zero modes besides the translations.
pub(crate) struct SparseInverse {
    n: usize,
    /// Row of `H_r` of each row of `H` (`u32::MAX` for the pinned rows).
    reduced: Vec<u32>,
    llt: Llt<usize, f64>,
    /// The `D` translations, orthonormal.
    translations: Vec<Vec<f64>>,
    /// `λ_{D+1}`: the smallest eigenvalue of `H` above the translations.
    pub lambda_min: f64,
    /// Its eigenvector (normalised, orthogonal to the translations).
    pub softest: Vec<f64>,
    /// Lanczos steps taken.
    pub lanczos_steps: usize,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn axpy(c: f64, x: &[f64], y: &mut [f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += c * x;
    }
}

impl SparseInverse {
    /// Factorise `hessian` (rows: `d` translations, then the rotations,
    /// body by body) with one body's translations pinned, and find its
    /// softest mode above the translations by Lanczos to the relative
    /// residual `tol`. `Err` names why the sparse path cannot be taken.
    pub fn new(hessian: &Hessian, d: usize, lambda_zero: f64, tol: f64) -> Result<Self, String> {
        let n = hessian.size;
        let mut translations = vec![vec![0.0; n]; d];
        let mut pinned = None;
        let mut bodies = 0usize;
        let mut row = 0;
        while row < n {
            let (body, start) = (hessian.body[row], row);
            while row < n && hessian.body[row] == body {
                row += 1;
            }
            if row - start < d || hessian.rotational[start..start + d].iter().any(|&r| r) {
                return Err(format!(
                    "the rows of body {body} do not start with its {d} translations"
                ));
            }
            for (a, t) in translations.iter_mut().enumerate() {
                t[start + a] = 1.0;
            }
            pinned.get_or_insert(start);
            bodies += 1;
        }
        let Some(pinned) = pinned.filter(|_| n > d) else {
            return Err(format!(
                "{n} rows: nothing besides the translations to solve for"
            ));
        };
        let norm = 1.0 / (bodies as f64).sqrt();
        translations.iter_mut().flatten().for_each(|x| *x *= norm);
        let mut reduced = vec![u32::MAX; n];
        let mut m = 0;
        for (r, slot) in reduced.iter_mut().enumerate() {
            if !(pinned..pinned + d).contains(&r) {
                *slot = m;
                m += 1;
            }
        }
        let upper: Vec<Triplet<usize, usize, f64>> = (hessian.entries.iter())
            .filter_map(|&(r, c, v)| {
                let (r, c) = (reduced[r as usize], reduced[c as usize]);
                (r != u32::MAX && c != u32::MAX && r <= c)
                    .then(|| Triplet::new(r as usize, c as usize, v))
            })
            .collect();
        let llt = sparse_cholesky(m as usize, &upper).ok_or_else(|| {
            "sparse Cholesky failed: the Hessian with one body's translations fixed is not positive definite (a zero mode besides the translations, or a negative one)".to_string()
        })?;
        let mut inverse = Self {
            n,
            reduced,
            llt,
            translations,
            lambda_min: 0.0,
            softest: Vec::new(),
            lanczos_steps: 0,
        };
        inverse.lanczos(d, tol)?;
        if !(inverse.lambda_min > 2.0 * lambda_zero) {
            return Err(format!(
                "the softest mode above the translations has λ = {:.3e}, not above twice the zero-mode threshold ω_zero² = {lambda_zero:.3e}",
                inverse.lambda_min
            ));
        }
        Ok(inverse)
    }

    /// Remove the translations' component from `x`; its squared norm.
    pub fn project(&self, x: &mut [f64]) -> f64 {
        let mut on = 0.0;
        for t in &self.translations {
            let c = dot(t, x);
            on += c * c;
            axpy(-c, t, x);
        }
        on
    }

    /// The `x` with `H x = b` and the pinned rows zero, for `b`
    /// orthogonal to the translations (then `bᵀ x = bᵀ H⁺ b`).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let m = self.n - self.translations.len();
        let mut rhs = Mat::<f64>::zeros(m, 1);
        for (&r, &v) in self.reduced.iter().zip(b) {
            if r != u32::MAX {
                rhs[(r as usize, 0)] = v;
            }
        }
        self.llt.solve_in_place(rhs.as_mut());
        (self.reduced.iter())
            .map(|&r| {
                if r == u32::MAX {
                    0.0
                } else {
                    rhs[(r as usize, 0)]
                }
            })
            .collect()
    }

    /// Lanczos with full reorthogonalisation on `P H⁺ P` from a fixed
    /// pseudo-random start, until the largest Ritz pair's residual
    /// `β_j |s_j|` is below `tol` times its Ritz value (after at least
    /// `MIN_LANCZOS` steps, or when the Krylov space is exhausted).
    fn lanczos(&mut self, d: usize, tol: f64) -> Result<(), String> {
        let dim = self.n - d;
        let steps = dim.min(MAX_LANCZOS);
        // A fixed start (xorshift): the result does not depend on a seed.
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut v: Vec<f64> = (0..self.n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        self.project(&mut v);
        let norm = dot(&v, &v).sqrt();
        v.iter_mut().for_each(|x| *x /= norm);
        let mut basis: Vec<Vec<f64>> = Vec::new();
        let (mut alpha, mut beta) = (Vec::new(), Vec::new());
        for j in 0..steps {
            let mut w = self.solve(&v);
            self.project(&mut w);
            alpha.push(dot(&w, &v));
            basis.push(v);
            for _ in 0..2 {
                for q in &basis {
                    let c = dot(&w, q);
                    axpy(-c, q, &mut w);
                }
            }
            let b = dot(&w, &w).sqrt();
            let exhausted = j + 1 == dim || !(b > 1e-14 * alpha[0].abs().max(alpha[j].abs()));
            if exhausted || j + 1 == steps || (j + 1 >= MIN_LANCZOS && (j + 1) % 5 == 0) {
                let (theta, s) = top_ritz(&alpha, &beta)?;
                let residual = b * s[j].abs();
                if exhausted || residual <= tol * theta {
                    if !(theta > 0.0 && theta.is_finite()) {
                        return Err(format!(
                            "Lanczos found no positive softest mode (Ritz value {theta:e} of H⁺)"
                        ));
                    }
                    let mut u = vec![0.0; self.n];
                    for (q, &c) in basis.iter().zip(&s) {
                        axpy(c, q, &mut u);
                    }
                    let norm = dot(&u, &u).sqrt();
                    u.iter_mut().for_each(|x| *x /= norm);
                    self.lambda_min = 1.0 / theta;
                    self.softest = u;
                    self.lanczos_steps = j + 1;
                    return Ok(());
                }
                if j + 1 == steps {
                    return Err(format!(
                        "Lanczos did not find the softest mode in {steps} steps (relative residual {:.1e}, asked {tol:.0e})",
                        residual / theta
                    ));
                }
            }
            beta.push(b);
            v = w;
            v.iter_mut().for_each(|x| *x /= b);
        }
        Err("Lanczos made no step".to_string())
    }
}

/// The largest eigenvalue of the tridiagonal matrix with diagonal `alpha`
/// and off-diagonal `beta`, and its eigenvector.
fn top_ritz(alpha: &[f64], beta: &[f64]) -> Result<(f64, Vec<f64>), String> {
    let j = alpha.len();
    let t = Mat::<f64>::from_fn(j, j, |r, c| {
        if r == c {
            alpha[r]
        } else if r + 1 == c || c + 1 == r {
            beta[r.min(c)]
        } else {
            0.0
        }
    });
    let evd = t
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| format!("eigensolver of the Lanczos matrix failed: {e:?}"))?;
    let top = j - 1;
    Ok((evd.S()[top], (0..j).map(|r| evd.U()[(r, top)]).collect()))
}
