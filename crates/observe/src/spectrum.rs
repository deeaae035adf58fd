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
use jamkit_core::{Error, Result};
use serde::{Deserialize, Serialize};

/// How to bin and read the density of states.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DosParams {
    /// Modes with `ω` at or below this are zero modes.
    pub omega_zero: f64,
    /// Lowest bin edge of `D(ω)`.
    pub omega_min: f64,
    /// Highest bin edge of `D(ω)`.
    pub omega_max: f64,
    /// Log-spaced bins per decade.
    pub bins_per_decade: usize,
    /// `D(ω_*)` (the paper: 0.1).
    pub d_star: f64,
    /// `ω_*` is sought below this (the paper: 0.1).
    pub omega_star_below: f64,
}

impl Default for DosParams {
    fn default() -> Self {
        Self {
            omega_zero: 1e-5,
            omega_min: 1e-5,
            omega_max: 10.0,
            bins_per_decade: 10,
            d_star: 0.1,
            omega_star_below: 0.1,
        }
    }
}

impl DosParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        for (name, v) in [
            ("omega_zero", self.omega_zero),
            ("omega_min", self.omega_min),
            ("omega_max", self.omega_max),
            ("d_star", self.d_star),
            ("omega_star_below", self.omega_star_below),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::invalid(
                    format!("{prefix}.{name}"),
                    v,
                    "must be positive and finite",
                ));
            }
        }
        if !(self.omega_max > self.omega_min) {
            return Err(Error::invalid(
                format!("{prefix}.omega_max"),
                self.omega_max,
                format!("must exceed omega_min = {:e}", self.omega_min),
            ));
        }
        if !(1..=1000).contains(&self.bins_per_decade) {
            return Err(Error::invalid(
                format!("{prefix}.bins_per_decade"),
                self.bins_per_decade,
                "must lie between 1 and 1000",
            ));
        }
        Ok(())
    }

    /// Bin edges, log-spaced from `omega_min` to (at least) `omega_max`.
    pub fn edges(&self) -> Vec<f64> {
        let decades = (self.omega_max / self.omega_min).log10();
        let bins = (decades * self.bins_per_decade as f64).ceil().max(1.0) as usize;
        (0..=bins)
            .map(|k| self.omega_min * 10f64.powf(k as f64 / self.bins_per_decade as f64))
            .collect()
    }
}

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

/// `ω = √max(λ, 0)`.
pub fn frequency(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt()
}

/// A histogram of frequencies, accumulated over packings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DosHistogram {
    /// Bin edges (length `counts.len() + 1`).
    pub edges: Vec<f64>,
    /// Modes per bin (zero modes excluded).
    pub counts: Vec<u64>,
    /// Modes above the zero threshold but outside the bins.
    pub outside: u64,
    /// Zero modes (`ω ≤ omega_zero`).
    pub zero_modes: u64,
    /// Every mode counted, zero modes included (`N_dof`, summed).
    pub modes: u64,
}

impl DosHistogram {
    /// An empty histogram with `params`' bins.
    pub fn new(params: &DosParams) -> Self {
        let edges = params.edges();
        Self {
            counts: vec![0; edges.len() - 1],
            edges,
            outside: 0,
            zero_modes: 0,
            modes: 0,
        }
    }

    /// Count the modes with eigenvalues `lambdas`.
    pub fn add(&mut self, lambdas: &[f64], params: &DosParams) {
        let (lo, per_decade) = (self.edges[0], params.bins_per_decade as f64);
        for &l in lambdas {
            self.modes += 1;
            let w = frequency(l);
            if w <= params.omega_zero {
                self.zero_modes += 1;
                continue;
            }
            let k = ((w / lo).log10() * per_decade).floor();
            // NOTE: a frequency on an edge may land one bin off through
            // round-off in log10; the edges are only a binning convention.
            if k >= 0.0 && (k as usize) < self.counts.len() {
                self.counts[k as usize] += 1;
            } else {
                self.outside += 1;
            }
        }
    }

    /// Add another histogram with the same bins.
    pub fn merge(&mut self, other: &DosHistogram) -> Result<()> {
        if other.edges != self.edges {
            return Err(Error::Unsupported(
                "density-of-states histograms with different bins cannot be merged".into(),
            ));
        }
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        self.outside += other.outside;
        self.zero_modes += other.zero_modes;
        self.modes += other.modes;
        Ok(())
    }

    /// Geometric bin centres.
    pub fn centres(&self) -> Vec<f64> {
        self.edges
            .windows(2)
            .map(|w| (w[0] * w[1]).sqrt())
            .collect()
    }

    /// `D(ω)` per bin: counts / (N_dof · width).
    pub fn density(&self) -> Vec<f64> {
        let n = self.modes.max(1) as f64;
        self.counts
            .iter()
            .zip(self.edges.windows(2))
            .map(|(&c, w)| c as f64 / (n * (w[1] - w[0])))
            .collect()
    }

    /// `ω₁`: the centre of the bin where `D(ω)` is largest (`None` when
    /// every bin is empty).
    pub fn omega_1(&self) -> Option<f64> {
        let d = self.density();
        let (k, &max) = d.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
        (max > 0.0).then(|| self.centres()[k])
    }

    /// `ω_*`: scanning down from `omega_star_below`, where `D` first falls
    /// below `d_star`, interpolated in `log ω` between the two bin centres.
    /// `None` when `D` stays above `d_star` down to the band at `ω₁`, or is
    /// already below it at the top.
    pub fn omega_star(&self, params: &DosParams) -> Option<f64> {
        let (d, c) = (self.density(), self.centres());
        let top = c.iter().rposition(|&w| w < params.omega_star_below)?;
        let band = self.omega_1()?;
        if d[top] < params.d_star || c[top] <= band {
            return None;
        }
        for k in (0..top).rev() {
            if c[k] <= band {
                return None;
            }
            if d[k] < params.d_star {
                // D(c[k]) < d_star ≤ D(c[k+1]): interpolate in log ω.
                let t = (params.d_star - d[k]) / (d[k + 1] - d[k]);
                return Some((c[k].ln() + t * (c[k + 1].ln() - c[k].ln())).exp());
            }
        }
        None
    }
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

/// Zero modes (`ω ≤ omega_zero`) and where the counting of degrees of
/// freedom puts them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ZeroModes {
    /// All of them.
    pub total: u64,
    /// The `D` global translations of the periodic box.
    pub translations: u64,
    /// `f = D + rot_dof` per rattler kept in the Hessian (rattlers are
    /// decoupled, so each is free in all its coordinates).
    pub rattlers: u64,
    /// The rest, `total − translations − rattlers`: for near-disks at φ_J
    /// the quartic modes of a hypostatic packing; for spheres it should be 0.
    pub extra: i64,
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

    /// A histogram whose density is known bin by bin: ω₁ lands on the bin
    /// holding the most modes per unit ω, and ω_* on the crossing.
    #[test]
    fn characteristic_frequencies_of_a_synthetic_spectrum() {
        let params = DosParams {
            bins_per_decade: 10,
            ..DosParams::default()
        };
        let mut h = DosHistogram::new(&params);
        let centres = h.centres();
        // A narrow band of 500 modes at ω ≈ 1e-3 and a plateau from 3e-2 up.
        let mut lambdas = Vec::new();
        let band = centres.iter().position(|&w| w > 1e-3).unwrap();
        lambdas.extend(std::iter::repeat_n(centres[band].powi(2), 500));
        for (k, &w) in centres.iter().enumerate() {
            if w > 3e-2 && w < 3.0 {
                let width = h.edges[k + 1] - h.edges[k];
                let n = (2000.0 * width).round() as usize;
                lambdas.extend(std::iter::repeat_n(w * w, n));
            }
        }
        lambdas.extend([0.0, -1e-14, 1e-12]); // three zero modes
        h.add(&lambdas, &params);
        assert_eq!(h.zero_modes, 3);
        assert_eq!(h.modes as usize, lambdas.len());
        assert_eq!(h.omega_1(), Some(centres[band]));
        let star = h.omega_star(&params).unwrap();
        // The plateau starts in the first bin above 3e-2; the crossing lies
        // between that bin's centre and the one below.
        let first = centres.iter().position(|&w| w > 3e-2).unwrap();
        assert!(
            star > centres[first - 1] && star <= centres[first],
            "{star}"
        );
    }

    #[test]
    fn bad_parameters_are_named() {
        let p = DosParams {
            omega_max: 1e-6,
            ..DosParams::default()
        };
        let e = p.validate("spectrum").unwrap_err().to_string();
        assert!(e.contains("spectrum.omega_max"), "{e}");
    }

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
}
