//! Errors of the engine: values with context, never panics.

use thiserror::Error;

/// Everything that can go wrong while building or relaxing a packing.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A parameter is out of its allowed range; names the field and what is allowed.
    #[error("{field} = {value}: {allowed}")]
    InvalidParameter {
        field: String,
        value: String,
        allowed: String,
    },
    /// The minimiser hit its step cap before either stopping criterion held.
    #[error(
        "FIRE did not converge in {steps} steps at phi = {phi:.12} (V/N = {energy_per_particle:.3e}, sum |dV/dq|^2 = {force_sq:.3e}, of which body {worst_body} carries {worst_share:.0}% and rotational coordinates {rotational_share:.0}%); if the residual does not fall, lower minimizer.dt_max (FIRE crawls as dt_max nears 2/omega_max, its stability limit), else raise minimizer.max_steps or loosen minimizer.force_tol"
    )]
    NotConverged {
        steps: u64,
        phi: f64,
        energy_per_particle: f64,
        force_sq: f64,
        /// The body with the largest share of `Σ (∂V/∂q)²`.
        worst_body: usize,
        /// Its share, in per cent.
        worst_share: f64,
        /// The share of all rotational coordinates, in per cent.
        rotational_share: f64,
    },
    /// The jamming bisection ran out of steps or of floating-point resolution.
    #[error("jamming search failed at phi = {phi:.15} after {steps} density changes: {reason}")]
    JammingFailed {
        phi: f64,
        steps: u64,
        reason: String,
    },
    /// The box is too small for the minimum-image convention.
    #[error(
        "the box edge {edge:.4} is shorter than twice the interaction range {range:.4} at phi = {phi:.6}: a body would meet its own periodic image; use more particles"
    )]
    BoxTooSmall { edge: f64, range: f64, phi: f64 },
    /// The family or dimension does not provide what was asked (e.g. the
    /// second derivatives of its gap, for the Hessian).
    #[error("{0}")]
    Unsupported(String),
    /// A NaN or infinity appeared in the energy or the forces.
    #[error("non-finite energy or force at phi = {phi:.12}: {what}")]
    NonFinite { phi: f64, what: String },
}

/// Result with the engine's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// The field of an [`Error::InvalidParameter`] (`params.delta`).
    pub fn field(&self) -> Option<&str> {
        match self {
            Error::InvalidParameter { field, .. } => Some(field),
            _ => None,
        }
    }

    /// What an [`Error::InvalidParameter`] says is allowed.
    pub fn allowed(&self) -> Option<&str> {
        match self {
            Error::InvalidParameter { allowed, .. } => Some(allowed),
            _ => None,
        }
    }

    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        allowed: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            field: field.into(),
            value: show_value(&value),
            allowed: allowed.into(),
        }
    }
}

/// A value as a user wrote it: numbers far from 1 in scientific notation
/// (`1e-15`, not `0.000000000000001`).
pub fn show_value(value: &dyn std::fmt::Display) -> String {
    let text = value.to_string();
    match text.parse::<f64>() {
        Ok(x) if x != 0.0 && x.is_finite() && (x.abs() < 1e-3 || x.abs() >= 1e7) => {
            format!("{x:e}")
        }
        _ => text,
    }
}
