//! Random pairs for the tests of this crate (each test file that needs
//! them declares `#[path = "support/random.rs"] mod random;`, so not
//! every item is used by every file).
#![allow(dead_code)]

use jamkit_core::{Pair, Rotation2, Vector};

/// Seeded uniform numbers in `[0, 1)`.
pub struct Uniform(rand_chacha::ChaCha8Rng);

impl Uniform {
    pub fn new(seed: u64) -> Self {
        use rand::SeedableRng;
        Self(rand_chacha::ChaCha8Rng::seed_from_u64(seed))
    }

    pub fn next(&mut self) -> f64 {
        use rand::RngExt;
        self.0.random::<f64>()
    }
}

/// A random pair near contact: sizes in [0.5, 0.7], any angles and
/// direction, centres from a 10 % overlap to 5 % apart.
pub fn random_pair(u: &mut Uniform) -> Pair<2, Rotation2> {
    let pi = std::f64::consts::PI;
    let (si, sj) = (0.5 + 0.2 * u.next(), 0.5 + 0.2 * u.next());
    let (ti, tj) = (pi - 2.0 * pi * u.next(), pi - 2.0 * pi * u.next());
    let dir = 2.0 * pi * u.next();
    let r = (si + sj) * (0.9 + 0.15 * u.next());
    Pair::new(
        si,
        Rotation2::new(ti),
        sj,
        Rotation2::new(tj),
        Vector::<2>::new(r * dir.cos(), r * dir.sin()),
    )
}

/// The pair moved: centres by up to `dr`, bodies turned by up to `dt` rad.
pub fn nudged(p: &Pair<2, Rotation2>, u: &mut Uniform, dr: f64, dt: f64) -> Pair<2, Rotation2> {
    let mut q = *p;
    q.r_ij += Vector::<2>::new(dr * (2.0 * u.next() - 1.0), dr * (2.0 * u.next() - 1.0));
    q.o_i = q.o_i.turned(dt * (2.0 * u.next() - 1.0));
    q.o_j = q.o_j.turned(dt * (2.0 * u.next() - 1.0));
    q
}
