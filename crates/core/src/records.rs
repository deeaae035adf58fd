//! The measures a packing file stores, as plain data: gap counts, the
//! density of states and its parameters, zero modes, elastic moduli and
//! their parameters. `jamkit_observe` measures them (and re-exports each
//! where it measures it: `gaps`, `spectrum`, `moduli`); `jamkit_format`
//! reads and writes them without the engine. Their serde names are those
//! of the packing files.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};

// ---------------------------------------------------------------------------
// Gaps

/// Counts of gaps below each sample point, for one packing or summed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GapCounts {
    /// Sample points (the last is `h_cut`).
    pub h: Vec<f64>,
    /// Number of gaps with `0 < gap < h[k]`.
    pub below: Vec<u64>,
}

impl GapCounts {
    /// Number of gaps below `h_cut`.
    pub fn total(&self) -> u64 {
        self.below.last().copied().unwrap_or(0)
    }

    /// Add the counts of another packing sampled at the same points.
    pub fn merge(&mut self, other: &GapCounts) -> Result<()> {
        if other.h != self.h {
            return Err(Error::Unsupported(
                "gap counts sampled at different points cannot be merged".into(),
            ));
        }
        for (a, b) in self.below.iter_mut().zip(&other.below) {
            *a += b;
        }
        Ok(())
    }

    /// `Z(h[k])` (NaN when there are no gaps at all).
    pub fn cumulative(&self) -> Vec<f64> {
        let total = self.total() as f64;
        self.below.iter().map(|&b| b as f64 / total).collect()
    }

    /// `g(h)` between consecutive sample points, normalised like `Z`
    /// (`∫₀^{h_cut} g = 1`): `(points, density)` at geometric midpoints.
    pub fn density(&self) -> (Vec<f64>, Vec<f64>) {
        let total = self.total() as f64;
        self.h
            .windows(2)
            .zip(self.below.windows(2))
            .map(|(h, b)| {
                (
                    (h[0] * h[1]).sqrt(),
                    (b[1] - b[0]) as f64 / (total * (h[1] - h[0])),
                )
            })
            .unzip()
    }
}

// ---------------------------------------------------------------------------
// Density of states

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

// ---------------------------------------------------------------------------
// Elastic moduli

/// How `Ξᵀ H⁺ Ξ` is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ModuliSolver {
    /// The dense eigendecomposition of the Hessian (`O(n³)` in its `n`
    /// rows): every mode, the zero modes and negative ones counted.
    Dense,
    /// A sparse Cholesky factorisation with one body's translations
    /// pinned, and Lanczos for the softest mode (`jamkit_observe::pinverse`): for a
    /// packing whose only zero modes are the translations and whose
    /// softest other mode has `λ > 2 ω_zero²`; otherwise the dense path is
    /// taken, and [`Moduli::dense_fallback`] says why. The default: it
    /// gives the dense path's moduli to ~10⁻¹³ at a fraction of the cost.
    #[default]
    Sparse,
}

impl ModuliSolver {
    /// Whether this is the dense path.
    pub fn is_dense(&self) -> bool {
        *self == Self::Dense
    }

    /// The solver of a packing file that names none: the dense path, the
    /// only one before the solver was recorded.
    pub fn unrecorded() -> Self {
        Self::Dense
    }
}

/// How the moduli are computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModuliParams {
    /// Modes with `ω = √λ` at or below this are zero modes, left out of
    /// `H⁺` (the same threshold as the spectrum's `dos.omega_zero`).
    pub omega_zero: f64,
    /// How `H⁺` is applied. Always written; a packing file that names
    /// none was measured on the dense path ([`ModuliSolver::unrecorded`]).
    #[serde(default = "ModuliSolver::unrecorded")]
    pub solver: ModuliSolver,
}

impl Default for ModuliParams {
    fn default() -> Self {
        Self {
            omega_zero: 1e-5,
            solver: ModuliSolver::Sparse,
        }
    }
}

impl ModuliParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.omega_zero > 0.0 && self.omega_zero.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.omega_zero"),
                self.omega_zero,
                "must be positive and finite",
            ));
        }
        Ok(())
    }
}

/// The elastic moduli of one packing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Moduli {
    /// `G`: the mean of `shear_planes`.
    pub shear: f64,
    /// `G_ab` for the planes `(0,1)` in 2D; `(0,1)`, `(0,2)`, `(1,2)` in 3D.
    pub shear_planes: Vec<f64>,
    /// `B = −V dp/dV`.
    pub bulk: f64,
    /// The affine parts `A/V` (mean over planes) of `G` …
    pub shear_affine: f64,
    /// … and `A/(D²V) + (D−1)p/D` of `B`.
    pub bulk_affine: f64,
    /// `p = −tr σ / D`.
    pub pressure: f64,
    /// Rows of the Hessian (rattlers removed).
    pub coordinates: usize,
    /// Zero modes (`ω ≤ omega_zero`, negative `λ` included, as the
    /// spectrum counts them); rattlers are removed, so `rattlers` is 0.
    pub zero_modes: ZeroModes,
    /// Modes with `λ < −omega_zero²`: the state is a saddle, not a minimum,
    /// and the moduli of the positive modes alone do not describe it.
    pub negative_modes: u64,
    /// The largest share of `|Ξ|²` (over the strains) on zero modes other
    /// than translations: a strain that such a floppy mode accommodates
    /// meets no resistance there, which `H⁺` leaves out.
    pub floppy_share: f64,
    /// For the plane of the smallest `G_ab`, the share of its non-affine
    /// term `Ξᵀ H⁺ Ξ` carried by the softest mode above the zero modes
    /// (`λ_1`, the smallest `λ > omega_zero²`). `G_ab` without that mode
    /// is `G_ab + soft_share · (non-affine term)/V`: even a small share can
    /// be what makes a small `G_ab` negative (docs/reports/elasticity.md,
    /// "Negative G in the fixed box"). `None` in packing files written
    /// before it was measured, and with no mode above the zero modes.
    #[serde(default)]
    pub soft_share: Option<f64>,
    /// With `solver: Sparse`, why the dense path was taken instead (the
    /// Cholesky factorisation failed, the softest mode is at the zero-mode
    /// threshold, …); absent when the sparse path was taken or not asked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dense_fallback: Option<String>,
}

impl Moduli {
    /// The smallest plane modulus `G_ab` (`G` in 2D): negative when the
    /// packing, stable at fixed box, is unstable to the shear of that plane.
    pub fn shear_min(&self) -> f64 {
        self.shear_planes
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cumulative_and_density_agree() {
        let c = GapCounts {
            h: vec![0.1, 1.0, 2.0],
            below: vec![2, 6, 10],
        };
        assert_eq!(c.cumulative(), vec![0.2, 0.6, 1.0]);
        let (_, g) = c.density();
        // ∫ g over [0.1, 2] = Z(2) − Z(0.1).
        let integral = g[0] * 0.9 + g[1] * 1.0;
        assert!((integral - 0.8).abs() < 1e-12);
    }

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
}
