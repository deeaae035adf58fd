//! Contact potentials: scalar functions `v(h)` of the gap.
//!
//! The total energy is `V = Σ_contacts v(h)`. A potential is purely repulsive
//! and vanishes for `h ≥ 0`; it knows nothing about shapes.
//!
//! * Harmonic (O'Hern et al. 2003, the paper's choice): `v = h²/2 · Θ(−h)`.
//! * Hertzian: `v = (2/5) (−h)^{5/2} · Θ(−h)`.

use serde::{Deserialize, Serialize};

/// A repulsive contact potential of the gap `h` (energy unit ε = 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Potential {
    /// `v(h) = h²/2` for `h < 0`.
    #[default]
    Harmonic,
    /// `v(h) = (2/5)(−h)^{5/2}` for `h < 0`.
    Hertzian,
}

impl Potential {
    /// `v(h)`.
    #[inline(always)]
    pub fn energy(self, h: f64) -> f64 {
        if h >= 0.0 {
            return 0.0;
        }
        match self {
            Potential::Harmonic => 0.5 * h * h,
            Potential::Hertzian => 0.4 * (-h) * (-h) * (-h).sqrt(),
        }
    }

    /// `v'(h)` (non-positive).
    #[inline(always)]
    pub fn derivative(self, h: f64) -> f64 {
        if h >= 0.0 {
            return 0.0;
        }
        match self {
            Potential::Harmonic => h,
            Potential::Hertzian => -(-h) * (-h).sqrt(),
        }
    }

    /// `v(h)` and `v'(h)` together, without a branch on the sign of `h`
    /// (the pair loop calls it for every listed pair, overlapping or not,
    /// and an unpredictable branch there costs more than the arithmetic).
    #[inline(always)]
    pub fn energy_and_derivative(self, h: f64) -> (f64, f64) {
        let overlap = h.min(0.0);
        match self {
            Potential::Harmonic => (0.5 * overlap * overlap, overlap),
            Potential::Hertzian => {
                let s = (-overlap).sqrt();
                (0.4 * overlap * overlap * s, overlap * s)
            }
        }
    }

    /// `v''(h)`.
    #[inline(always)]
    pub fn second_derivative(self, h: f64) -> f64 {
        if h >= 0.0 {
            return 0.0;
        }
        match self {
            Potential::Harmonic => 1.0,
            Potential::Hertzian => 1.5 * (-h).sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of v and v' agree with the analytic v' and v''.
    /// Step 1e-6 on |h| ~ 0.1: truncation ~1e-12, round-off ~1e-10; 1e-7 is safe.
    #[test]
    fn derivatives_match_finite_differences() {
        for p in [Potential::Harmonic, Potential::Hertzian] {
            for h in [-0.3, -0.1, -0.02] {
                let e = 1e-6;
                let d1 = (p.energy(h + e) - p.energy(h - e)) / (2.0 * e);
                let d2 = (p.derivative(h + e) - p.derivative(h - e)) / (2.0 * e);
                assert!((d1 - p.derivative(h)).abs() < 1e-7, "{p:?} v' at {h}");
                assert!(
                    (d2 - p.second_derivative(h)).abs() < 1e-7,
                    "{p:?} v'' at {h}"
                );
                let (v, dv) = p.energy_and_derivative(h);
                assert_eq!((v, dv), (p.energy(h), p.derivative(h)));
            }
        }
    }

    #[test]
    fn no_energy_without_overlap() {
        for p in [Potential::Harmonic, Potential::Hertzian] {
            for h in [0.0, 1e-300, 0.5] {
                assert_eq!(p.energy(h), 0.0);
                assert_eq!(p.derivative(h), 0.0);
            }
        }
    }
}
