//! What the minimisers see: an [`Objective`] (an energy of flat generalised
//! coordinates, with its Hessian and stiffness blocks where it has them),
//! and why a minimisation stopped ([`StopReason`]). FIRE, the Newton
//! finish, L-BFGS and the block masses all work through this trait, so
//! none of them knows a scene, a family or `D`.

use jamkit_core::{Error, Result};

/// Something FIRE can minimise: an energy of flat generalised coordinates.
pub trait Objective {
    /// Number of generalised coordinates.
    fn dof(&self) -> usize;
    /// Number of bodies `N` (the stopping criterion uses `V/N`).
    fn bodies(&self) -> usize;
    /// Inverse mass of every coordinate.
    fn inverse_masses(&self) -> &[f64];
    /// Energy, with the gradient written into `grad`.
    fn energy_gradient(&mut self, grad: &mut [f64]) -> f64;
    /// Move by `dq`.
    fn displace(&mut self, dq: &[f64]);
    /// Packing fraction, for error messages.
    fn phi(&self) -> f64;
    /// Translational coordinates of each body, which come first among its
    /// `dof / bodies` coordinates (for error messages; default: all).
    fn translations_per_body(&self) -> usize {
        self.dof() / self.bodies().max(1)
    }
    /// Append the Hessian `∂²V/∂q∂q` as `(row, column, value)` entries (both
    /// triangles; repeated index pairs add up) and return `Ok(true)`, or
    /// return `Ok(false)` when the objective has none (then the Newton
    /// finish is never tried). Default: none.
    fn hessian_entries(&mut self, _entries: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
        Ok(false)
    }
    /// Remember the current coordinates, for [`Objective::restore`] (used by
    /// the Newton finish's line search; needed only with a Hessian).
    fn save(&mut self) {}
    /// Go back to the coordinates of the last [`Objective::save`].
    fn restore(&mut self) {}
    /// Write each body's own block of the stiffness matrix (`bodies` blocks
    /// of `f × f`, row-major, `f = dof / bodies`; see
    /// [`crate::hessian::stiffness_blocks`]) and return `true`, or return
    /// `false` when the objective has none (then the preconditioned FIRE
    /// uses the plain masses). Default: none.
    fn stiffness_blocks(&mut self, _blocks: &mut Vec<f64>) -> bool {
        false
    }
}

/// Why a minimisation stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// `V/N` fell below `energy_tol`.
    Energy,
    /// The force criterion held.
    Force,
    /// The unjamming forecast: `V/N` decays towards a limit at or below
    /// the jamming search's `energy_low` ([`crate::fire`]).
    Forecast,
}

/// `Ok` when `value` is positive and finite, else an error naming
/// `prefix.name` (the settings' shared range check).
pub(crate) fn require_positive_finite(prefix: &str, name: &str, value: f64) -> Result<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(
            format!("{prefix}.{name}"),
            value,
            "must be positive and finite",
        ))
    }
}
