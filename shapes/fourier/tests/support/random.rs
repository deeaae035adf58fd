//! Random pairs for the tests of this crate (each test file that needs
//! them declares `#[path = "support/random.rs"] mod random;`, so not
//! every item is used by every file).
#![allow(dead_code)]

use jamkit_core::{Pair, Rotation2, Vector};

/// A small deterministic generator (splitmix64), uniform in `[0, 1)`.
pub struct Uniform(pub u64);

impl Uniform {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
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
