//! Real solid harmonics as polynomials, and the sphere averages the family
//! needs.
//!
//! A real spherical harmonic of degree `l` is the restriction to the unit
//! sphere of a homogeneous harmonic polynomial of degree `l` (a *solid
//! harmonic*). With `m ≥ 0`, `(x + iy)^m = A_m + i B_m` and
//!
//! ```text
//! Π_l^m(z, r²) = Σ_{k=0}^{⌊(l−m)/2⌋} (−1)^k 2^{−l} C(l,k) C(2l−2k, l) (l−2k)!/(l−2k−m)! r^{2k} z^{l−2k−m},
//! ```
//!
//! the real solid harmonics are `Π_l^0` (`m = 0`, equal to `r^l P_l(z/r)`),
//! `Π_l^m A_m` (`m > 0`, the `cos mφ` one) and `Π_l^{|m|} B_{|m|}`
//! (`m < 0`, the `sin |m|φ` one): `r^l P_l^{|m|}(cos θ) cos mφ` (resp.
//! `sin |m|φ`) without the Condon–Shortley phase, up to a positive factor.
//! The factor does not matter here: the family rescales every harmonic so
//! that its largest slope on the sphere is 1 ([`Poly::max_slope_and_bound`]).
//!
//! Polynomials are lists of monomials `a x^i y^j z^k`; their value,
//! gradient and Hessian at a point are exact sums over the list (degree
//! ≤ [`LMAX`]: at most 45 monomials). The sphere average of a monomial is
//! exact, `⟨x^a y^b z^c⟩ = (a−1)!! (b−1)!! (c−1)!! / (a+b+c+1)!!` when
//! `a, b, c` are all even and 0 otherwise, so averages of products of
//! harmonics (`⟨F²⟩`, `⟨F³⟩`: the volume) are exact too.

use jamkit_core::{Matrix, Vector};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Largest degree `l` the family accepts.
pub const LMAX: u32 = 8;

/// A polynomial in `x, y, z`: monomials `(coefficient, [i, j, k])`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Poly {
    terms: Vec<(f64, [u8; 3])>,
    /// The largest exponent of any variable (the powers a jet needs),
    /// kept with the terms: the pair loop asked for it on every call.
    top: usize,
}

fn binomial(n: u32, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

fn factorial(n: u32) -> f64 {
    (1..=n).fold(1.0, |acc, i| acc * i as f64)
}

/// `(n)!!` for odd `n ≥ −1` (`(−1)!! = 1`).
fn odd_double_factorial(n: i32) -> f64 {
    let mut acc = 1.0;
    let mut k = n;
    while k > 1 {
        acc *= k as f64;
        k -= 2;
    }
    acc
}

impl Poly {
    fn from_terms(terms: Vec<(f64, [u8; 3])>) -> Self {
        let top = terms
            .iter()
            .flat_map(|(_, e)| e.iter().copied())
            .max()
            .unwrap_or(0) as usize;
        Self { terms, top }
    }

    fn from_map(map: BTreeMap<[u8; 3], f64>) -> Self {
        Self::from_terms(
            map.into_iter()
                .filter(|(_, c)| *c != 0.0)
                .map(|(e, c)| (c, e))
                .collect(),
        )
    }

    fn monomial(c: f64, e: [u8; 3]) -> Self {
        Self::from_terms(vec![(c, e)])
    }

    /// The monomials.
    pub fn terms(&self) -> &[(f64, [u8; 3])] {
        &self.terms
    }

    /// `self + other`.
    pub fn add(&self, other: &Self) -> Self {
        let mut map = BTreeMap::new();
        for (c, e) in self.terms.iter().chain(&other.terms) {
            *map.entry(*e).or_insert(0.0) += c;
        }
        Self::from_map(map)
    }

    /// `self · other`.
    pub fn mul(&self, other: &Self) -> Self {
        let mut map = BTreeMap::new();
        for (a, ea) in &self.terms {
            for (b, eb) in &other.terms {
                let e = [ea[0] + eb[0], ea[1] + eb[1], ea[2] + eb[2]];
                *map.entry(e).or_insert(0.0) += a * b;
            }
        }
        Self::from_map(map)
    }

    /// `s · self`.
    pub fn scaled(&self, s: f64) -> Self {
        Self::from_terms(self.terms.iter().map(|(c, e)| (c * s, *e)).collect())
    }

    /// The Laplacian, as a polynomial.
    pub fn laplacian(&self) -> Self {
        let mut map = BTreeMap::new();
        for (c, e) in &self.terms {
            for a in 0..3 {
                if e[a] >= 2 {
                    let mut f = *e;
                    f[a] -= 2;
                    *map.entry(f).or_insert(0.0) += c * (e[a] as f64) * (e[a] as f64 - 1.0);
                }
            }
        }
        Self::from_map(map)
    }

    /// The real solid harmonic of degree `l` and order `m` (`|m| ≤ l`),
    /// unnormalised (module documentation).
    pub fn solid_harmonic(l: u32, m: i32) -> Self {
        let am = m.unsigned_abs();
        assert!(am <= l, "|m| ≤ l");
        // Π_l^{|m|}(z, r²).
        let r2 = Self::monomial(1.0, [2, 0, 0])
            .add(&Self::monomial(1.0, [0, 2, 0]))
            .add(&Self::monomial(1.0, [0, 0, 2]));
        let mut pi = Self::default();
        let mut r2k = Self::monomial(1.0, [0, 0, 0]);
        for k in 0..=(l - am) / 2 {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            let coef = sign * 0.5f64.powi(l as i32) * binomial(l, k) * binomial(2 * l - 2 * k, l)
                / factorial(l - 2 * k - am)
                * factorial(l - 2 * k);
            let zpow = (l - 2 * k - am) as u8;
            pi = pi.add(&r2k.mul(&Self::monomial(coef, [0, 0, zpow])));
            r2k = r2k.mul(&r2);
        }
        // A_m or B_m: Re or Im of (x + iy)^m = Σ_p C(m,p) x^p (iy)^{m−p}.
        let mut azimuthal = BTreeMap::new();
        for p in 0..=am {
            let q = am - p; // power of iy: i^q
            let (re, im) = match q % 4 {
                0 => (1.0, 0.0),
                1 => (0.0, 1.0),
                2 => (-1.0, 0.0),
                _ => (0.0, -1.0),
            };
            let c = binomial(am, p) * if m >= 0 { re } else { im };
            *azimuthal.entry([p as u8, q as u8, 0]).or_insert(0.0) += c;
        }
        pi.mul(&Self::from_map(azimuthal))
    }

    /// The largest exponent of any variable (the powers a jet needs).
    #[inline(always)]
    fn top_power(&self) -> usize {
        self.top
    }

    /// `v_a^k` for `k = 0 … top` (`top ≤ LMAX`).
    #[inline(always)]
    fn powers(v: &Vector<3>, top: usize) -> [[f64; LMAX as usize + 1]; 3] {
        let mut pw = [[1.0f64; LMAX as usize + 1]; 3];
        for a in 0..3 {
            for k in 1..=top {
                pw[a][k] = pw[a][k - 1] * v[a];
            }
        }
        pw
    }

    /// Value and gradient at `v` (the pair loop's path).
    #[inline(always)]
    pub fn value_grad(&self, v: &Vector<3>) -> (f64, Vector<3>) {
        let pw = Self::powers(v, self.top_power());
        let mut val = 0.0;
        let mut g = Vector::<3>::zeros();
        for (c, e) in &self.terms {
            let (i, j, k) = (e[0] as usize, e[1] as usize, e[2] as usize);
            let (x, y, z) = (pw[0][i], pw[1][j], pw[2][k]);
            val += c * x * y * z;
            if i > 0 {
                g[0] += c * (i as f64 * pw[0][i - 1]) * y * z;
            }
            if j > 0 {
                g[1] += c * x * (j as f64 * pw[1][j - 1]) * z;
            }
            if k > 0 {
                g[2] += c * x * y * (k as f64 * pw[2][k - 1]);
            }
        }
        (val, g)
    }

    /// Value, gradient and Hessian at `v` in one pass over the monomials
    /// (the powers of `v` computed once): the exact-gap support search's
    /// path. Each sum is accumulated over the terms in the same order and
    /// each term written as the separate value/gradient and Hessian sums
    /// wrote it (`c · ∂^a x^i · ∂^b y^j · ∂^c z^k`, the falling factorials
    /// `i`, `i (i − 1)` as exact small integers, `0` below the power), so
    /// the bits are theirs.
    #[inline(always)]
    fn value_grad_hessian(&self, v: &Vector<3>) -> (f64, Vector<3>, Matrix<3>) {
        let pw = Self::powers(v, self.top_power());
        // ∂ and ∂² of v_a^k: k v_a^{k−1} and k (k − 1) v_a^{k−2} (0 below).
        let d1 = |a: usize, k: usize| {
            if k >= 1 { k as f64 * pw[a][k - 1] } else { 0.0 }
        };
        let d2 = |a: usize, k: usize| {
            if k >= 2 {
                (k * (k - 1)) as f64 * pw[a][k - 2]
            } else {
                0.0
            }
        };
        let mut val = 0.0;
        let mut g = Vector::<3>::zeros();
        let [mut h00, mut h11, mut h22, mut h01, mut h02, mut h12] = [0.0f64; 6];
        for (c, e) in &self.terms {
            let (i, j, k) = (e[0] as usize, e[1] as usize, e[2] as usize);
            let (x, y, z) = (pw[0][i], pw[1][j], pw[2][k]);
            let (dx, dy, dz) = (d1(0, i), d1(1, j), d1(2, k));
            val += c * x * y * z;
            if i > 0 {
                g[0] += c * dx * y * z;
            }
            if j > 0 {
                g[1] += c * x * dy * z;
            }
            if k > 0 {
                g[2] += c * x * y * dz;
            }
            h00 += c * d2(0, i) * y * z;
            h11 += c * x * d2(1, j) * z;
            h22 += c * x * y * d2(2, k);
            h01 += c * dx * dy * z;
            h02 += c * dx * y * dz;
            h12 += c * x * dy * dz;
        }
        let h = Matrix::<3>::new(h00, h01, h02, h01, h11, h12, h02, h12, h22);
        (val, g, h)
    }

    /// Value, gradient and (when `hessian`; else zero) Hessian at `v`.
    pub fn jet(&self, v: &Vector<3>, hessian: bool) -> (f64, Vector<3>, Matrix<3>) {
        if hessian {
            self.value_grad_hessian(v)
        } else {
            let (val, g) = self.value_grad(v);
            (val, g, Matrix::<3>::zeros())
        }
    }

    /// Value at `v`.
    pub fn value(&self, v: &Vector<3>) -> f64 {
        self.jet(v, false).0
    }

    /// The slope on the unit sphere at the unit vector `v`: the norm of the
    /// tangential gradient `|(1 − v vᵀ) ∇P(v)|`.
    pub fn slope(&self, v: &Vector<3>) -> f64 {
        let (_, g, _) = self.jet(v, false);
        (g - v * v.dot(&g)).norm()
    }

    /// The exact sphere average `⟨P⟩ = (1/4π) ∫ P dΩ`.
    pub fn sphere_mean(&self) -> f64 {
        self.terms
            .iter()
            .filter(|(_, e)| e.iter().all(|k| k % 2 == 0))
            .map(|(c, e)| {
                let num: f64 = e
                    .iter()
                    .map(|&k| odd_double_factorial(k as i32 - 1))
                    .product();
                let total: i32 = e.iter().map(|&k| k as i32).sum();
                c * num / odd_double_factorial(total + 1)
            })
            .sum()
    }

    /// The largest slope on the unit sphere of the solid harmonic of order
    /// `m` that `self` is, and the largest `|P|` there, as a certain upper
    /// bound.
    ///
    /// A real harmonic `N Θ(θ) cos mφ` has `|∇_S|² = N² [Θ'² cos² mφ +
    /// (mΘ/sin θ)² sin² mφ]`, largest over `φ` at `cos mφ = ±1` or
    /// `sin mφ = ±1`: so the slope is largest on one of the meridians
    /// `φ = 0`, `φ = π/(2|m|)` (for `sin |m|φ` the same two), and `|P|` is
    /// largest on one of them too. Each is scanned on 4096 + 1 latitudes,
    /// and the best of each refined by golden sections (to 10⁻¹³ in θ).
    /// The bound on `|P|` is the scanned maximum plus `S h / 2`, `S` the
    /// largest slope and `h` the scan's step: along a meridian `|∂_θ P| ≤ S`.
    pub fn max_slope_and_bound(&self, m: i32) -> (f64, f64) {
        let meridians = if m == 0 {
            vec![0.0]
        } else {
            vec![0.0, PI / (2.0 * m.unsigned_abs() as f64)]
        };
        let steps = 4096;
        let h = PI / steps as f64;
        let point = |theta: f64, phi: f64| {
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            Vector::<3>::new(st * cp, st * sp, ct)
        };
        let mut slope = 0.0f64;
        let mut value = 0.0f64;
        for &phi in &meridians {
            let f = |t: f64| self.slope(&point(t, phi));
            let mut best = (0.0, f64::NEG_INFINITY);
            for k in 0..=steps {
                let t = k as f64 * h;
                let s = f(t);
                if s > best.1 {
                    best = (t, s);
                }
                value = value.max(self.value(&point(t, phi)).abs());
            }
            // Golden-section refinement on [t − h, t + h].
            let (mut a, mut b) = ((best.0 - h).max(0.0), (best.0 + h).min(PI));
            let r = 0.5 * (5f64.sqrt() - 1.0);
            while b - a > 1e-13 {
                let (c, d) = (b - r * (b - a), a + r * (b - a));
                if f(c) > f(d) {
                    b = d;
                } else {
                    a = c;
                }
            }
            slope = slope.max(best.1).max(f(0.5 * (a + b)));
        }
        (slope, value + slope * h / 2.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Every solid harmonic is harmonic (its Laplacian vanishes to
    /// round-off of its coefficients) and homogeneous of degree `l`, and
    /// harmonics of different `(l, m)` are orthogonal on the sphere
    /// (exact monomial averages, so to round-off): together, the `2l + 1`
    /// of each degree are a basis of the real spherical harmonics.
    #[test]
    fn solid_harmonics_are_harmonic_homogeneous_and_orthogonal() {
        let all: Vec<(u32, i32, Poly)> = (2..=LMAX)
            .flat_map(|l| (-(l as i32)..=l as i32).map(move |m| (l, m, Poly::solid_harmonic(l, m))))
            .collect();
        for (l, m, p) in &all {
            let scale = p.terms.iter().fold(0.0f64, |s, (c, _)| s.max(c.abs()));
            assert!(scale > 0.0, "({l}, {m}) is zero");
            for (c, _) in p.laplacian().terms() {
                assert!(c.abs() < 1e-12 * scale, "({l}, {m}): Laplacian term {c}");
            }
            for (_, e) in p.terms() {
                assert_eq!(e.iter().map(|&k| k as u32).sum::<u32>(), *l);
            }
            assert!(p.sphere_mean().abs() < 1e-14 * scale);
        }
        for (a, (l1, m1, p1)) in all.iter().enumerate() {
            let n1 = p1.mul(p1).sphere_mean();
            assert!(n1 > 0.0);
            for (l2, m2, p2) in &all[a + 1..] {
                let n2 = p2.mul(p2).sphere_mean();
                let overlap = p1.mul(p2).sphere_mean() / (n1 * n2).sqrt();
                assert!(
                    overlap.abs() < 1e-12,
                    "({l1}, {m1}) and ({l2}, {m2}) overlap {overlap}"
                );
            }
        }
    }

    /// `Π_2^0 = (3z² − r²)/2`, `Π_2^2 A_2 = 3 (x² − y²)`,
    /// `Π_2^{1} B_1 = 3 y z` (the textbook forms), and the monomial average
    /// `⟨z²⟩ = 1/3`, `⟨x² y² z²⟩ = 1/105`.
    #[test]
    fn low_order_forms_and_averages_are_the_textbook_ones() {
        let v = Vector::<3>::new(0.3, -0.4, 0.5);
        let r2 = v.norm_squared();
        assert_relative_eq!(
            Poly::solid_harmonic(2, 0).value(&v),
            1.5 * v[2] * v[2] - 0.5 * r2,
            epsilon = 1e-15
        );
        assert_relative_eq!(
            Poly::solid_harmonic(2, 2).value(&v),
            3.0 * (v[0] * v[0] - v[1] * v[1]),
            epsilon = 1e-15
        );
        assert_relative_eq!(
            Poly::solid_harmonic(2, -1).value(&v),
            3.0 * v[1] * v[2],
            epsilon = 1e-15
        );
        assert_relative_eq!(
            Poly::monomial(1.0, [0, 0, 2]).sphere_mean(),
            1.0 / 3.0,
            epsilon = 1e-16
        );
        assert_relative_eq!(
            Poly::monomial(1.0, [2, 2, 2]).sphere_mean(),
            1.0 / 105.0,
            epsilon = 1e-16
        );
    }

    /// The polynomial's gradient and Hessian against central differences
    /// of its value (ε = 1e-5: truncation ε²|P'''| ~ 1e-9 for coefficients
    /// ~10², round-off 1e-16·10²/ε ~ 1e-9; bound 1e-6 of the scale).
    #[test]
    fn jet_matches_finite_differences() {
        let v = Vector::<3>::new(0.31, -0.62, 0.72);
        for (l, m) in [(2, 0), (3, -2), (5, 4), (6, 1), (8, -8)] {
            let p = Poly::solid_harmonic(l, m);
            let (_, g, h) = p.jet(&v, true);
            let eps = 1e-5;
            let scale = 1.0 + g.amax() + h.amax();
            for a in 0..3 {
                let mut e = Vector::<3>::zeros();
                e[a] = eps;
                let fd = (p.value(&(v + e)) - p.value(&(v - e))) / (2.0 * eps);
                assert!((fd - g[a]).abs() < 1e-6 * scale, "({l},{m}) grad {a}");
                let (_, gp, _) = p.jet(&(v + e), false);
                let (_, gm, _) = p.jet(&(v - e), false);
                for b in 0..3 {
                    let fd = (gp[b] - gm[b]) / (2.0 * eps);
                    assert!((fd - h[(a, b)]).abs() < 1e-6 * scale, "({l},{m}) hess");
                }
            }
        }
    }

    /// The largest slope from the two meridians against a scan of the
    /// whole sphere (200 × 400 points): the scan never exceeds it (1e-12),
    /// and comes within 1e-3 of it (its grid misses the maximum by
    /// ~ (π/200)² · curvature); the bound on |P| holds on the scan.
    #[test]
    fn max_slope_matches_a_scan_of_the_sphere() {
        for (l, m) in [(2, 0), (2, 2), (3, 1), (3, -3), (4, 2), (6, -5), (6, 0)] {
            let p = Poly::solid_harmonic(l, m);
            let (s, bound) = p.max_slope_and_bound(m);
            let (mut scan, mut vmax) = (0.0f64, 0.0f64);
            for i in 0..=200 {
                let t = PI * i as f64 / 200.0;
                for j in 0..400 {
                    let f = 2.0 * PI * j as f64 / 400.0;
                    let v = Vector::<3>::new(t.sin() * f.cos(), t.sin() * f.sin(), t.cos());
                    scan = scan.max(p.slope(&v));
                    vmax = vmax.max(p.value(&v).abs());
                }
            }
            assert!(scan <= s * (1.0 + 1e-12), "({l},{m}): scan {scan} > {s}");
            assert!(scan >= s * (1.0 - 1e-3), "({l},{m}): scan {scan} ≪ {s}");
            assert!(vmax <= bound, "({l},{m}): |P| {vmax} > bound {bound}");
        }
    }
}
