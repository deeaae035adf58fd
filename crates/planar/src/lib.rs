//! # jamkit-planar: the 2D near-disk toolkit
//!
//! What the planar families share beyond the `Shape` contract, kept out of
//! `jamkit-core` (which neither the engine nor the observables need it):
//!
//! * [`profiled`]: [`Profiled<P>`](profiled::Profiled), the whole `Shape`
//!   of a near-disk from its profile `P` alone, with the first-order gap,
//!   or the second-order or exact one for a profile with a third derivative
//!   (`lobed`, `fourier` and `fourier_sum` are profiles; a new near-disk
//!   family is a profile and its parameters);
//! * [`first_order`]: the paper's first-order near-disk gap with its second
//!   derivatives, for any profile `R(θ)/R⁰ = 1 + Δ P(θ)` given by `P`, `P'`
//!   and `P''` at the two bodies' angles (used by `fourier`, `fourier_sum`
//!   and `lobed`);
//! * [`gap2d`]: the second-order near-disk gap and the exact gap of convex
//!   outlines (support functions), with second derivatives (used by the
//!   near-disks' `SecondOrder` and `Exact` gap models and by `ellipse`);
//! * [`arcs`]: the exact gap of smooth non-convex outlines, split at their
//!   inflection points into arcs, with several contacts per pair (the
//!   near-disks' `Exact` gap model beyond convexity).
//!
//! The planar orientation type itself, [`jamkit_core::Rotation2`], lives in
//! core beside the `Shape` trait.

pub mod arcs;
pub mod first_order;
pub mod gap2d;
pub mod profiled;

/// Seeded uniform numbers in `[0, 1)` for the tests.
#[cfg(test)]
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    move || rng.random::<f64>()
}
