//! # jamkit-observe
//!
//! What is measured on a packing once it is made:
//!
//! * [`contacts`]: the contact network (`h < 0`) and iterative rattler
//!   removal;
//! * [`summary`]: contact number, rattler fraction, pressure and the
//!   isostaticity margin of a jammed packing;
//! * [`hessian`]: the Hessian of the energy in all generalised coordinates
//!   (stiffness part `K` and stress part `T`), assembled sparse;
//! * [`spectrum`]: its eigenvalues, the density of states `D(ω)`, `ω₁`,
//!   `ω_*`, zero modes, participation ratios and rotational shares;
//! * [`moduli`]: the stress tensor, the strain derivatives of the energy
//!   and the shear and bulk moduli by linear response, with a check by
//!   deformation;
//! * [`gaps`]: the distribution of positive gaps between non-rattlers,
//!   `g(h)` and its cumulative `Z(h)`.

pub mod contacts;
pub mod gaps;
pub mod moduli;
mod pinverse;
pub use jamkit_engine::hessian;
pub mod spectrum;
pub mod summary;

pub use contacts::{ContactNetwork, find_rattlers, find_rattlers_by_rank};
pub use summary::{ContactCount, JammingSummary, RattlerRule, summarize, summarize_with};
