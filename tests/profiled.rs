//! A near-disk family is its profile (`jamkit_planar::profiled`): a new
//! two-mode near-disk written as a profile alone passes the conformance
//! kit, and the generic shape agrees with the `fourier` family where both
//! describe the same body — including a profile that is not symmetric
//! under a half turn (n = 3), which tests body j's `−π`.

use jamkit_core::{Angle, Shape, Vector};
use jamkit_core::{Pair, ShapeExt};
use jamkit_fourier::{FourierSumParams, Mode, NearDisk};
use jamkit_planar::profiled::{NearDiskProfile, Profiled};
use rand::{RngExt, SeedableRng};
use std::f64::consts::PI;

/// `P(φ) = a sin 2φ / 2 + b sin 3φ / 3`: the paper's modes n = 2 and 3,
/// mixed. This is the whole family a user writes (plus its parameters and
/// registration, docs/tutorials/new-shape-rust.md).
#[derive(Clone, Debug, PartialEq)]
struct TwoMode {
    a: f64,
    b: f64,
}

impl NearDiskProfile for TwoMode {
    const FAMILY: &'static str = "two_mode";
    const HALF_TURN_SYMMETRIC: bool = false;

    fn value_slope(&self, c: f64, s: f64) -> (f64, f64) {
        // sin 2φ = 2sc, cos 2φ = c² − s², sin 3φ = 3s − 4s³, cos 3φ = 4c³ − 3c.
        let (s2, c2) = (2.0 * s * c, c * c - s * s);
        let (s3, c3) = (3.0 * s - 4.0 * s * s * s, 4.0 * c * c * c - 3.0 * c);
        (
            self.a * s2 / 2.0 + self.b * s3 / 3.0,
            self.a * c2 + self.b * c3,
        )
    }

    fn curvature(&self, c: f64, s: f64) -> f64 {
        let (s2, s3) = (2.0 * s * c, 3.0 * s - 4.0 * s * s * s);
        -2.0 * self.a * s2 - 3.0 * self.b * s3
    }

    fn range(&self) -> (f64, f64) {
        // |P| ≤ |a|/2 + |b|/3.
        let m = self.a.abs() / 2.0 + self.b.abs() / 3.0;
        (-m, m)
    }

    fn describe(&self) -> String {
        format!("a = {}, b = {}", self.a, self.b)
    }
}

fn two_mode(a: f64, b: f64, delta: f64) -> Profiled<TwoMode> {
    Profiled::new(TwoMode { a, b }, delta, None).unwrap()
}

/// The kit (FD gradient and Hessian, h_ij = h_ji, invariances, a small
/// jamming run) on the user's family, with no other test code.
#[test]
fn a_two_mode_profile_passes_the_kit() {
    for (a, b, delta) in [(1.0, 0.0, 0.2), (0.0, 1.0, 0.1), (0.7, 0.5, 0.15)] {
        let done = jamkit_kit::check_family::<2, _>(two_mode(a, b, delta));
        assert!(
            done.ran.contains(&"hessian") && done.ran.contains(&"rotation"),
            "{done:?}"
        );
    }
}

/// The same body as `fourier_sum` with modes (n = 2, a/2) and (n = 3, b/3)
/// (its `F = Σ a_k sin(n_k φ + b_k)`):
/// gaps, forces and torques agree to round-off on random pairs (the two
/// compute them by different arithmetic: complex powers against the
/// profile's polynomials), and so do the area and the bounding test.
#[test]
fn the_generic_shape_is_the_fourier_family_where_they_coincide() {
    let (a, b, delta) = (0.7, 0.5, 0.15);
    let ours = two_mode(a, b, delta);
    let fourier = NearDisk::fourier_sum(&FourierSumParams {
        modes: vec![
            Mode {
                n: 2,
                a: a / 2.0,
                b: 0.0,
            },
            Mode {
                n: 3,
                a: b / 3.0,
                b: 0.0,
            },
        ],
        delta,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    approx::assert_relative_eq!(
        Shape::<2>::volume(&ours, 0.7),
        Shape::<2>::volume(&fourier, 0.7),
        max_relative = 1e-12
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut compared = 0;
    for _ in 0..500 {
        let (ti, tj) = (
            2.0 * PI * rng.random::<f64>(),
            2.0 * PI * rng.random::<f64>(),
        );
        let phi = 2.0 * PI * rng.random::<f64>();
        let r = 1.0 + 0.3 * rng.random::<f64>();
        let d = Vector::<2>::new(r * phi.cos(), r * phi.sin());
        let mine = ours.pair_contacts(
            &Pair::new(
                0.5,
                Angle::from_coords(&[ti]).unwrap(),
                0.7,
                Angle::from_coords(&[tj]).unwrap(),
                d,
            ),
            0.5,
        );
        let theirs = fourier.pair_contacts(
            &Pair::new(
                0.5,
                jamkit_core::Rotation2::from_coords(&[ti]).unwrap(),
                0.7,
                jamkit_core::Rotation2::from_coords(&[tj]).unwrap(),
                d,
            ),
            0.5,
        );
        assert_eq!(mine.len(), theirs.len());
        for (m, t) in mine.iter().zip(&theirs) {
            approx::assert_relative_eq!(m.gap, t.gap, epsilon = 1e-13);
            approx::assert_relative_eq!(m.grad_r, t.grad_r, epsilon = 1e-13);
            approx::assert_relative_eq!(m.grad_rot_i[0], t.grad_rot_i[0], epsilon = 1e-13);
            approx::assert_relative_eq!(m.grad_rot_j[0], t.grad_rot_j[0], epsilon = 1e-13);
            compared += 1;
        }
    }
    assert!(compared > 100, "{compared} contacts compared");
}

/// The checks every profiled family gets: Δ, the inertia and R > 0.
#[test]
fn bad_amplitudes_and_inertias_are_refused_by_name() {
    let field = |delta: f64, inertia: Option<f64>| {
        Profiled::new(TwoMode { a: 1.0, b: 1.0 }, delta, inertia)
            .unwrap_err()
            .field()
            .map(str::to_string)
    };
    assert_eq!(field(-0.1, None).as_deref(), Some("params.delta"));
    assert_eq!(field(f64::NAN, None).as_deref(), Some("params.delta"));
    assert_eq!(field(0.0, Some(0.0)).as_deref(), Some("params.inertia"));
    assert_eq!(field(0.1, Some(-1.0)).as_deref(), Some("params.inertia"));
    // The disk Δ = 0 turns with I = 1 unless told otherwise.
    assert!(Profiled::new(TwoMode { a: 1.0, b: 1.0 }, 0.0, None).is_ok());
    // min P = −5/6: R > 0 needs Δ < 1.2.
    assert_eq!(field(1.3, None).as_deref(), Some("params.delta"));
    assert!(Profiled::new(TwoMode { a: 1.0, b: 1.0 }, 1.1, None).is_ok());
}
