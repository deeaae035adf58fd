//! # jamkit-report
//!
//! `jamkit report DIR… -o OUT`: the paper's figures regenerated from our own
//! runs, with fitted exponents beside the mean-field predictions.
//!
//! * [`data`]: the packing files of one or more runs, grouped into points
//!   `(n, Δ, N)` of the near-disk ensembles, or `(l, Δ, N)` of near-spheres
//!   with one spherical-harmonic mode (the same figures and claims in 3D);
//! * [`fit`]: power laws on log–log axes with bootstrap errors over packings;
//! * [`plot`]: figures with error bars and guide lines, SVG and PNG;
//! * [`runplot`]: `jamkit plot`, figures of any run (every family): each
//!   scanned parameter against φ_J, z_J, rattlers and pressure, D(ω), Z(h);
//! * [`accuracy`]: the comparisons of docs/reports/speed-vs-error.md, each packing
//!   against a reference packing of the same seed (gap models against
//!   `Exact`, FIRE tolerances against the tightest that converged);
//! * [`figures`]: the paper's Figs. 7–13 and the markdown summary with the
//!   table "paper's claim | our measurement | agrees?"; Fig. 5 (ellipses
//!   against `n = 2` near-disks at equal asphericity) when the runs hold
//!   `ellipse` packings.
//!
//! A figure whose data are absent (no spectrum measured, one system size
//! only, …) is skipped and the summary says so.

pub mod accuracy;
pub mod data;
mod ellipses;
pub mod figures;
pub mod fit;
pub mod plot;
pub mod runplot;

pub use figures::{Options, Report, report};

use std::path::PathBuf;

/// What can go wrong while reporting.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A directory or file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        error: std::io::Error,
    },
    /// No near-disk packing was found.
    #[error(
        "no packings of the `fourier` family (with parameters n and delta) or the `harmonic` family (with l and delta) under {0}; give the output directories of runs of experiments/paper/ or experiments/paper3d/"
    )]
    NoData(String),
    /// The runs hold near-disks and near-spheres (or several dimensions).
    #[error(
        "the runs hold packings of more than one kind ({0}): report near-disks (2D, n) and near-spheres (3D, l) in separate calls"
    )]
    Mixed(String),
    /// No packing files at all.
    #[error("no packing files under {0}; give output directories of `jamkit run` (or archives)")]
    NoPackings(String),
    /// A figure had nothing to draw.
    #[error("figure `{0}` has no finite point to draw")]
    Empty(String),
    /// The runs do not fit an accuracy comparison.
    #[error("{0}")]
    Accuracy(String),
    /// The plotting library failed.
    #[error("drawing failed: {0}")]
    Plot(String),
}
