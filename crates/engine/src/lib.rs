//! # jamkit-engine
//!
//! Turns a [`Packing`](jamkit_core::Packing) into something that can be
//! relaxed and jammed:
//!
//! * [`neighbors`]: a cell list with a Verlet skin, rebuilt only when some
//!   body has moved more than half the skin, so one evaluation costs `O(N)`;
//! * [`scene`]: the energy `V = Σ v(h)` and its gradient in all generalised
//!   coordinates, in one fused pass over the neighbour list;
//! * [`objective`]: what the minimisers see of a scene ([`Objective`]);
//! * [`fire`]: the FIRE minimiser (Bitzek et al. 2006) and FIRE 2.0
//!   (Guénolé et al. 2020), with a mass per coordinate;
//! * [`newton`]: a second-order finish for FIRE (Newton steps with the
//!   analytic [`hessian`], assembled sparse and factorised by faer);
//! * [`precon`]: FIRE with each body's own stiffness block as its mass
//!   (block preconditioning);
//! * [`protocol`]: the paper's compress/decompress bisection to the jamming
//!   point, compression to a packing fraction or a pressure, and to a
//!   packing fraction above its own jamming point;
//! * [`saddle`]: the saddle escape after the bisection;
//! * [`stable_dt`]: FIRE's `Δt_max` kept below the stiffest mode's
//!   stability bound in a minimisation that does not converge;
//! * [`cell`]: a packing in a deformed periodic cell ([`cell::Strained`]),
//!   and [`stabilise`]: the shear stabilisation that relaxes that cell's
//!   shape.
//!
//! Everything is generic over the dimension `D` and the family `S`, so the
//! pair loop is compiled once per family with no dynamic dispatch.

mod balls;
pub mod cell;
pub mod check;
pub mod fire;
pub mod hessian;
mod lanes;
pub mod lbfgs;
pub mod neighbors;
pub mod newton;
pub mod objective;
pub mod precon;
pub mod protocol;
pub mod saddle;
pub mod scene;
mod scene_objective;
pub mod simd;
mod slots;
pub mod stabilise;
pub mod stable_dt;

pub use fire::{
    Fire, FireParams, FireVariant, ForceCriterion, Masses, MinimizeOutcome, Progress,
    ProgressSnapshot,
};
pub use lbfgs::{LbfgsChoice, LbfgsParams};
pub use neighbors::NeighborList;
pub use newton::NewtonParams;
pub use objective::{Objective, StopReason};
pub use precon::PreconParams;
pub use protocol::{
    AboveJamOutcome, AboveJamParams, JamParams, JamSearch, PressureParams, ProtocolOutcome, Work,
    above_jam, compress_to_phi, compress_to_pressure, energy_slope, extrapolated_step, jam,
};
pub use scene::Scene;

/// Binary disks (`SizeDistribution::default`) at random in a periodic box
/// at packing fraction `phi`, harmonic, skin 0.2: the scene of the tests.
#[cfg(test)]
fn random_disks(n: usize, phi: f64, seed: u64) -> Scene<2, jamkit_sphere::Sphere> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = jamkit_core::SizeDistribution::default().sample(n, &mut rng);
    let packing =
        jamkit_core::Packing::random(jamkit_sphere::Sphere, sizes, phi, &mut rng).unwrap();
    Scene::new(packing, jamkit_core::Potential::Harmonic, 0.2)
}
