//! The vibrational spectrum: eigenvalues of the Hessian, the density of
//! states `D(ω)`, its characteristic frequencies and the shape of each mode.
//!
//! With eigenvalues `λ_n` of the Hessian (paper, Eq. (27)),
//!
//! ```text
//! D(ω) = (1/N_dof) Σ_n δ(ω − √λ_n),
//! ```
//!
//! accumulated here on log-spaced bins of `ω` as a density per unit `ω`
//! (counts / (N_dof · bin width)), so that `∫ D dω` over all bins is the
//! fraction of modes above the zero-mode threshold. Modes with
//! `ω ≤ omega_zero` (the paper uses `10⁻⁵`) are *zero modes*: global
//! translations, rattlers and, for near-disks at φ_J, the quartic modes of a
//! hypostatic packing. They are counted apart and left out of `D(ω)`.
//! Round-off gives zero modes tiny negative `λ`; `ω = √max(λ, 0)`.
//!
//! Characteristic frequencies (the paper's definitions, thresholds
//! configurable):
//!
//! * `ω₁`: the bin centre where `D(ω)` is largest;
//! * `ω_*`: where `D` falls to `d_star = 0.1` below `omega_star_below = 0.1`:
//!   scanning down from `omega_star_below`, the first crossing of `D` below
//!   `d_star`, interpolated linearly in `log ω` between the two bins. It is
//!   the lower edge of the plateau, so it must lie above the band at `ω₁`;
//!   when the band reaches into the range (near-disks with Δ ≳ 0.03, where
//!   the paper's `ω_* ∝ Δ^{1/2}` is above 0.1), `ω_*` is undefined.
//!
//! Each mode's *participation ratio* `PR = (Σ_i w_i)² / (N_b Σ_i w_i²)` with
//! `w_i` the squared weight of the normalised eigenvector on body `i` (1 for
//! a mode spread evenly over all `N_b` bodies, `1/N_b` for one body), and its
//! *rotational share*, the weight on rotational coordinates.
//!
//! The eigensolver is faer's dense self-adjoint divide-and-conquer
//! (`docs/reports/performance.md`, "Current figures: one evaluation, one
//! spectrum, moduli", compares it with the alternatives).

use crate::hessian::Hessian;
pub use jamkit_core::records::{DosHistogram, DosParams, ZeroModes, frequency};
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};

/// Eigenvalues of `h`, ascending.
pub fn eigenvalues(h: &Hessian) -> Result<Vec<f64>> {
    if h.size == 0 {
        return Ok(Vec::new());
    }
    h.dense()
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))
}

/// `ω_max²`, the largest eigenvalue of `M^{-1/2} H M^{-1/2}`: the fastest
/// vibration of the dynamics FIRE runs (`inverse_masses` per row of `h`,
/// e.g. `Packing::inverse_masses` when no rows were removed). FIRE's Euler
/// step is stable below `Δt = 2/ω_max`.
pub fn omega_max_sq(h: &Hessian, inverse_masses: &[f64]) -> Result<f64> {
    if inverse_masses.len() != h.size {
        return Err(Error::Unsupported(format!(
            "{} inverse masses for a Hessian of {} rows",
            inverse_masses.len(),
            h.size
        )));
    }
    let mut m = h.dense();
    for r in 0..h.size {
        for c in 0..h.size {
            m[(r, c)] *= (inverse_masses[r] * inverse_masses[c]).sqrt();
        }
    }
    let w = m
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    Ok(w.last().copied().unwrap_or(0.0))
}

/// Eigenvalues (ascending) and the shape of each mode.
pub fn eigenmodes(h: &Hessian) -> Result<(Vec<f64>, Vec<ModeShape>)> {
    if h.size == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let evd = h
        .dense()
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Unsupported(format!("eigensolver failed: {e:?}")))?;
    let (u, s) = (evd.U(), evd.S());
    let values = (0..h.size).map(|n| s[n]).collect();
    // Rows come body by body; the bodies kept are the distinct runs.
    let kept_bodies = h.body.chunk_by(|a, b| a == b).count() as f64;
    let mut per_body = vec![0.0; h.body.last().map_or(0, |&b| b as usize + 1)];
    let shapes = (0..h.size)
        .map(|n| {
            per_body.fill(0.0);
            let mut rotational = 0.0;
            for a in 0..h.size {
                let w = u[(a, n)] * u[(a, n)];
                per_body[h.body[a] as usize] += w;
                if h.rotational[a] {
                    rotational += w;
                }
            }
            let (sum, sum_sq) = per_body
                .iter()
                .fold((0.0, 0.0), |(s, q), &w| (s + w, q + w * w));
            ModeShape {
                participation: sum * sum / (kept_bodies * sum_sq),
                rotational_share: rotational / sum,
            }
        })
        .collect();
    Ok((values, shapes))
}

/// How a mode is spread over bodies and coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeShape {
    /// Participation ratio, in `[1/N_b, 1]`.
    pub participation: f64,
    /// Share of the mode's weight on rotational coordinates, in `[0, 1]`.
    pub rotational_share: f64,
}

/// The spectrum of one packing, with its zero modes sorted by origin.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Eigenvalues, ascending.
    pub eigenvalues: Vec<f64>,
    /// Shape of each mode (when eigenvectors were asked for).
    pub modes: Option<Vec<ModeShape>>,
    /// The frequencies binned for `D(ω)`.
    pub histogram: DosHistogram,
    /// Zero modes, by origin.
    pub zero: ZeroModes,
}

impl Spectrum {
    /// The softest non-zero mode: the index of the lowest eigenvalue with
    /// `ω > omega_zero` and its shape (`None` without eigenvectors or
    /// without such a mode).
    pub fn softest(&self, omega_zero: f64) -> Option<(usize, ModeShape)> {
        let modes = self.modes.as_ref()?;
        let n = self
            .eigenvalues
            .iter()
            .position(|&l| frequency(l) > omega_zero)?;
        Some((n, modes[n]))
    }
}

/// Assemble the Hessian of `scene`, diagonalise it and bin its frequencies.
pub fn measure<const D: usize, S: jamkit_core::Shape<D>>(
    scene: &mut jamkit_engine::Scene<D, S>,
    rattler: &[bool],
    options: crate::hessian::HessianOptions,
    with_modes: bool,
    params: &DosParams,
) -> Result<Spectrum> {
    let hessian = Hessian::of_scene(scene, rattler, options)?;
    let (eigenvalues, modes) = if with_modes {
        let (l, m) = eigenmodes(&hessian)?;
        (l, Some(m))
    } else {
        (self::eigenvalues(&hessian)?, None)
    };
    let mut histogram = DosHistogram::new(params);
    histogram.add(&eigenvalues, params);
    let f = (D + scene.packing().shape.rot_dof()) as u64;
    let rattlers_kept = if options.remove_rattlers {
        0
    } else {
        rattler.iter().filter(|&&r| r).count() as u64
    };
    let (translations, rattlers) = (D as u64, f * rattlers_kept);
    let total = histogram.zero_modes;
    Ok(Spectrum {
        eigenvalues,
        modes,
        histogram,
        zero: ZeroModes {
            total,
            translations,
            rattlers,
            extra: total as i64 - (translations + rattlers) as i64,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn omega_max_weights_rows_by_their_masses() {
        // diag(4, 9) with masses 1 and 4: ω² = 4 and 9/4, so 4 (not 9).
        let h = Hessian {
            size: 2,
            body: vec![0, 0],
            rotational: vec![false, true],
            entries: vec![(0, 0, 4.0), (1, 1, 9.0)],
        };
        assert_eq!(omega_max_sq(&h, &[1.0, 0.25]).unwrap(), 4.0);
        assert!(omega_max_sq(&h, &[1.0]).is_err());
    }

    #[test]
    fn softest_is_the_first_mode_above_the_zero_threshold() {
        // Two bodies, (x, θ) each: diag(0, 4) and diag(1, 9). The modes are
        // the unit vectors; λ = 0 is a zero mode, λ = 1 (ω = 1) the softest,
        // on body 1's translation alone: PR = 1/2, rotational share 0.
        let h = Hessian {
            size: 4,
            body: vec![0, 0, 1, 1],
            rotational: vec![false, true, false, true],
            entries: vec![(0, 0, 0.0), (1, 1, 4.0), (2, 2, 1.0), (3, 3, 9.0)],
        };
        let (eigenvalues, modes) = eigenmodes(&h).unwrap();
        let params = DosParams::default();
        let mut spectrum = Spectrum {
            histogram: DosHistogram::new(&params),
            eigenvalues,
            modes: Some(modes),
            zero: ZeroModes {
                total: 1,
                translations: 0,
                rattlers: 0,
                extra: 1,
            },
        };
        let (n, mode) = spectrum.softest(1e-5).unwrap();
        assert_eq!(n, 1);
        assert!((spectrum.eigenvalues[n] - 1.0).abs() < 1e-12);
        assert!((mode.participation - 0.5).abs() < 1e-12, "{mode:?}");
        assert!(mode.rotational_share.abs() < 1e-12, "{mode:?}");
        // A threshold above ω = 1 leaves λ = 4: body 0's rotation.
        let (n, mode) = spectrum.softest(1.5).unwrap();
        assert!((spectrum.eigenvalues[n] - 4.0).abs() < 1e-12);
        assert!((mode.rotational_share - 1.0).abs() < 1e-12, "{mode:?}");
        assert!(
            spectrum.softest(10.0).is_none(),
            "every mode is below ω = 10"
        );
        spectrum.modes = None;
        assert!(spectrum.softest(1e-5).is_none(), "no eigenvectors");
    }
}
