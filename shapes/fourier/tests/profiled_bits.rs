//! `fourier` and `fourier_sum` against the shared near-disk
//! (`jamkit_planar::profiled::Profiled`) with the same profile: which of
//! their numbers agree bit for bit, and where they part.
//!
//! [`FourierProfile`] gives `Profiled` the profile `F(ψ) = Σ a_k sin(n_k ψ
//! + b_k)` with `NearDisk`'s own operations (`e^{inA}` by the same
//! products, the modes summed in the same order), so that what differs is
//! what `Profiled` does around the profile: the orientation type, the
//! direction of the line of centres, the bounding radius and the area.

use jamkit_core::math::{Unit, cmul};
use jamkit_core::{
    Angle, BodyOrientation, Contact, GapHessian, Pair, Rotation2, Shape, ShapeExt, Vector,
};
use jamkit_fourier::{FourierParams, FourierSumParams, Mode, NearDisk};
use jamkit_planar::first_order;
use jamkit_planar::profiled::{NearDiskProfile, Profiled};

/// `F = Σ a_k sin(n_k ψ + b_k)` as a `NearDiskProfile`, with `NearDisk`'s
/// operations for `e^{inA}`, `F` and `F'`.
#[derive(Clone, Debug, PartialEq)]
struct FourierProfile {
    modes: Vec<Mode>,
    phases: Vec<Unit>,
}

impl FourierProfile {
    fn new(modes: Vec<Mode>) -> Self {
        let phases = modes.iter().map(|m| (m.b.cos(), m.b.sin())).collect();
        Self { modes, phases }
    }
}

fn csq(z: Unit) -> Unit {
    (z.0 * z.0 - z.1 * z.1, 2.0 * (z.0 * z.1))
}

/// `z^n` with `NearDisk`'s products (straight-line for n ≤ 6, else binary).
fn cpow(z: Unit, n: u32) -> Unit {
    match n {
        1 => z,
        2 => csq(z),
        3 => cmul(csq(z), z),
        4 => csq(csq(z)),
        5 => cmul(csq(csq(z)), z),
        6 => cmul(csq(csq(z)), csq(z)),
        mut n => {
            let (mut z, mut acc) = (z, (1.0, 0.0));
            while n > 0 {
                if n & 1 == 1 {
                    acc = cmul(acc, z);
                }
                z = cmul(z, z);
                n >>= 1;
            }
            acc
        }
    }
}

impl NearDiskProfile for FourierProfile {
    const FAMILY: &'static str = "fourier";
    // `NearDisk` flips both signs for body j, whatever the modes.
    const HALF_TURN_SYMMETRIC: bool = false;

    fn value_slope(&self, cos: f64, sin: f64) -> (f64, f64) {
        let e = (cos, sin);
        if let [m] = self.modes[..]
            && m.b == 0.0
        {
            let p = cpow(e, m.n);
            return (m.a * p.1, m.a * m.n as f64 * p.0);
        }
        let mut out = (0.0, 0.0);
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let mut p = cpow(e, m.n);
            if m.b != 0.0 {
                p = cmul(p, phase);
            }
            out.0 += m.a * p.1;
            out.1 += m.a * m.n as f64 * p.0;
        }
        out
    }

    fn curvature(&self, cos: f64, sin: f64) -> f64 {
        let mut out = 0.0;
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let n = m.n as f64;
            let p = cmul(cpow((cos, sin), m.n), phase);
            out -= m.a * n * n * p.1;
        }
        out
    }

    fn range(&self) -> (f64, f64) {
        let bound: f64 = self.modes.iter().map(|m| m.a.abs()).sum();
        (-bound, bound)
    }

    fn moments(&self) -> (f64, f64) {
        let mut mean_f2 = 0.0;
        for p in &self.modes {
            for q in &self.modes {
                if p.n == q.n {
                    mean_f2 += 0.5 * p.a * q.a * (p.b - q.b).cos();
                }
            }
        }
        (0.0, mean_f2)
    }

    fn describe(&self) -> String {
        format!("{:?}", self.modes)
    }
}

/// A small deterministic generator (splitmix64), uniform in `[0, 1)`.
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The numbers of a contact.
fn contact_numbers(c: &Contact<2>) -> Vec<f64> {
    vec![
        c.gap,
        c.grad_r[0],
        c.grad_r[1],
        c.grad_rot_i[0],
        c.grad_rot_j[0],
    ]
}

/// The numbers of a gap Hessian (contact, then second derivatives).
fn hessian_numbers(h: &GapHessian<2>) -> Vec<f64> {
    let mut v = contact_numbers(&h.contact);
    v.extend(h.rr.iter());
    v.extend(h.r_qi[0].iter().chain(h.r_qj[0].iter()));
    v.extend([h.qi_qi[0][0], h.qj_qj[0][0], h.qi_qj[0][0]]);
    v
}

/// Distance in units in the last place (same sign assumed; ∞ otherwise).
fn ulps(a: f64, b: f64) -> u64 {
    if a.to_bits() == b.to_bits() {
        0
    } else if a.signum() != b.signum() {
        u64::MAX
    } else {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }
}

/// Counts of differing numbers and the largest difference in ulps.
#[derive(Default, Debug)]
struct Tally {
    compared: usize,
    differing: usize,
    max_ulps: u64,
}

impl Tally {
    fn add(&mut self, a: &[f64], b: &[f64]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            self.compared += 1;
            let d = ulps(*x, *y);
            if d > 0 {
                self.differing += 1;
                self.max_ulps = self.max_ulps.max(d);
            }
        }
    }
}

/// The shapes compared: `fourier` for n = 2…6 and Δ = 0.05…0.3, and a
/// `fourier_sum` of three modes with phases.
fn shapes() -> Vec<(NearDisk, Profiled<FourierProfile>)> {
    let mut out = Vec::new();
    for n in 2..=6 {
        for delta in [0.05, 0.1, 0.2, 0.3] {
            let nd = NearDisk::fourier(&FourierParams {
                n,
                delta,
                inertia: None,
                gap: Default::default(),
            });
            let Ok(nd) = nd else { continue };
            let m = Mode {
                n,
                a: 1.0 / n as f64,
                b: 0.0,
            };
            let p = Profiled::new(FourierProfile::new(vec![m]), delta, None).unwrap();
            out.push((nd, p));
        }
    }
    let modes = vec![
        Mode {
            n: 2,
            a: 0.4,
            b: 0.3,
        },
        Mode {
            n: 3,
            a: 0.2,
            b: -1.0,
        },
        Mode {
            n: 5,
            a: 0.05,
            b: 2.0,
        },
    ];
    for delta in [0.05, 0.2] {
        let nd = NearDisk::fourier_sum(&FourierSumParams {
            modes: modes.clone(),
            delta,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        let p = Profiled::new(FourierProfile::new(modes.clone()), delta, None).unwrap();
        out.push((nd, p));
    }
    out
}

/// Random pairs: sizes in [0.5, 0.7], angles in (−π, π], separations
/// between overlapping and just apart in every direction.
fn pairs(count: usize) -> Vec<(f64, f64, f64, f64, Vector<2>)> {
    let mut u = Uniform(7);
    let pi = std::f64::consts::PI;
    (0..count)
        .map(|_| {
            let (si, sj) = (0.5 + 0.2 * u.next(), 0.5 + 0.2 * u.next());
            let (ti, tj) = (pi - 2.0 * pi * u.next(), pi - 2.0 * pi * u.next());
            let dir = 2.0 * pi * u.next();
            let r = (si + sj) * (0.8 + 0.3 * u.next());
            (si, ti, sj, tj, Vector::<2>::new(r * dir.cos(), r * dir.sin()))
        })
        .collect()
}

/// With the same orientation bits (`e^{iθ}` of `Rotation2::new(θ)` and
/// `Angle::<1>::new(θ)`), `Profiled`'s first-order contacts equal
/// `NearDisk`'s bit for bit: the same phases `e^{iA}` (a complex product
/// with `u` either way), the same profile values, the same gap and
/// gradient expressions. This asserts that, and prints how the Hessians,
/// areas and bounding radii compare.
#[test]
fn profiled_contacts_equal_near_disk_contacts_bit_for_bit() {
    let pairs = pairs(20_000);
    let (mut contacts, mut hessians, mut units) =
        (Tally::default(), Tally::default(), Tally::default());
    let (mut areas, mut radii) = (Tally::default(), Tally::default());
    let (mut hessian_contacts, mut by_division) = (Tally::default(), Tally::default());
    for (nd, p) in shapes() {
        areas.add(&[nd.volume(0.6)], &[p.volume(0.6)]);
        radii.add(&[nd.bounding_radius(0.6)], &[p.bounding_radius(0.6)]);
        for &(si, ti, sj, tj, d) in &pairs {
            let (ri, rj) = (Rotation2::new(ti), Rotation2::new(tj));
            let (ai, aj) = (Angle::<1>::new(ti), Angle::<1>::new(tj));
            units.add(
                &[ri.unit().0, ri.unit().1, rj.unit().0, rj.unit().1],
                &[ai.unit().0, ai.unit().1, aj.unit().0, aj.unit().1],
            );
            let a = nd.pair_contacts(&Pair::new(si, ri, sj, rj, d), f64::INFINITY);
            let b = p.pair_contacts(&Pair::new(si, ai, sj, aj, d), f64::INFINITY);
            contacts.add(&contact_numbers(&a[0]), &contact_numbers(&b[0]));
            let (mut ha, mut hb) = (None, None);
            nd.gap_hessians(&Pair::new(si, ri, sj, rj, d), f64::INFINITY, |h| {
                ha = Some(h)
            })
            .unwrap();
            p.gap_hessians(&Pair::new(si, ai, sj, aj, d), f64::INFINITY, |h| {
                hb = Some(h)
            })
            .unwrap();
            let (ha, hb) = (ha.unwrap(), hb.unwrap());
            hessians.add(&hessian_numbers(&ha), &hessian_numbers(&hb));
            hessian_contacts.add(&contact_numbers(&ha.contact), &contact_numbers(&hb.contact));
            // Profiled's Hessian with the phases taken from `r_ij / r`
            // (NearDisk's) instead of `r_ij · (1/r)`.
            let u = d / d.norm();
            let phase = |o: &Angle<1>| {
                let (c, s) = o.unit();
                (c * u[0] + s * u[1], s * u[0] - c * u[1])
            };
            let ((ci, sn_i), (cj, sn_j)) = (phase(&ai), phase(&aj));
            let profile = |(c, s): (f64, f64)| {
                let (value, slope) = p.profile().value_slope(c, s);
                first_order::Profile {
                    value,
                    slope,
                    curvature: p.profile().curvature(c, s),
                }
            };
            let hc = first_order::gap_hessian(
                &d,
                si,
                sj,
                p.delta(),
                profile((ci, sn_i)),
                profile((-cj, -sn_j)),
            );
            by_division.add(&hessian_numbers(&ha), &hessian_numbers(&hc));
        }
    }
    println!("orientation e^(iθ) from θ: {units:?}");
    println!("contacts (gap, grad_r, grad_rot_i, grad_rot_j): {contacts:?}");
    println!("gap Hessians: {hessians:?}");
    println!("gap Hessians' contacts: {hessian_contacts:?}");
    println!("gap Hessians, phases from r_ij / r: {by_division:?}");
    println!("areas: {areas:?}");
    println!("bounding radii: {radii:?}");
    assert_eq!(units.differing, 0, "{units:?}");
    assert_eq!(contacts.differing, 0, "{contacts:?}");
}

/// How the two orientation types move apart under the same turns: after
/// `steps` random small turns (|dθ| < 10⁻³, FIRE-like), how many of the
/// `e^{iθ}` differ and by how many ulps, and the file coordinate `[θ]` of
/// each and its round trip.
#[test]
fn orientation_types_part_under_turns() {
    let mut u = Uniform(11);
    let (mut after, mut trip_r, mut trip_a) =
        (Tally::default(), Tally::default(), Tally::default());
    for _ in 0..2000 {
        let t0 = std::f64::consts::PI * (2.0 * u.next() - 1.0);
        let (mut r, mut a) = (Rotation2::new(t0), Angle::<1>::new(t0));
        for _ in 0..100 {
            let dt = 1e-3 * (2.0 * u.next() - 1.0);
            r = r.turned(dt);
            a = a.turned(dt);
        }
        after.add(&[r.unit().0, r.unit().1], &[a.unit().0, a.unit().1]);
        let r2 = Rotation2::from_coords(&BodyOrientation::to_coords(&r)).unwrap();
        let a2 = Angle::<1>::from_coords(&BodyOrientation::to_coords(&a)).unwrap();
        trip_r.add(&[r.unit().0, r.unit().1], &[r2.unit().0, r2.unit().1]);
        trip_a.add(&[a.unit().0, a.unit().1], &[a2.unit().0, a2.unit().1]);
    }
    println!("e^(iθ) after 100 turns, Rotation2 against Angle<1>: {after:?}");
    println!("Rotation2 through the file's [θ] and back: {trip_r:?}");
    println!("Angle<1> through the file's [θ] and back: {trip_a:?}");
    // The two ways of turning differ (Taylor product against θ + sin_cos).
    assert!(after.differing > 0, "{after:?}");
    // Angle<1> keeps θ itself, so its round trip is exact.
    assert_eq!(trip_a.differing, 0, "{trip_a:?}");
}

/// FNV-1a over the bits of a list of numbers.
fn digest(numbers: impl IntoIterator<Item = f64>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for x in numbers {
        for b in x.to_bits().to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// Every number `fourier` and `fourier_sum` give the engine, for the three
/// gap models: area, bounding radius, inertia, contacts and gap Hessians of
/// 2000 random pairs per shape (deep overlaps to apart), and orientations
/// after 50 turns by `Shape::rotate`.
fn near_disk_numbers() -> Vec<f64> {
    use jamkit_planar::gap2d::GapModel;
    let mut out = Vec::new();
    let pairs = pairs(2000);
    let modes = vec![
        Mode {
            n: 2,
            a: 0.4,
            b: 0.3,
        },
        Mode {
            n: 3,
            a: 0.2,
            b: -1.0,
        },
        Mode {
            n: 7,
            a: 0.05,
            b: 0.0,
        },
    ];
    for gap in [GapModel::FirstOrder, GapModel::SecondOrder, GapModel::Exact] {
        let mut shapes: Vec<NearDisk> = [(2, 0.1), (3, 0.2), (4, 0.05), (5, 0.1), (6, 0.02), (7, 0.01)]
            .into_iter()
            .map(|(n, delta)| {
                NearDisk::fourier(&FourierParams {
                    n,
                    delta,
                    inertia: None,
                    gap,
                })
                .unwrap()
            })
            .collect();
        shapes.push(
            NearDisk::fourier_sum(&FourierSumParams {
                modes: modes.clone(),
                delta: 0.15,
                inertia: Some(0.3),
                gap,
            })
            .unwrap(),
        );
        for s in &shapes {
            out.extend([s.volume(0.7), s.bounding_radius(0.7), s.rot_inertia(0.7)[0]]);
            for &(si, ti, sj, tj, d) in &pairs {
                let pair = Pair::new(si, Rotation2::new(ti), sj, Rotation2::new(tj), d);
                for c in s.pair_contacts(&pair, 0.05) {
                    out.extend(contact_numbers(&c));
                }
                s.gap_hessians(&pair, 0.05, |h| out.extend(hessian_numbers(&h)))
                    .unwrap();
            }
            let mut o = Rotation2::new(0.3);
            for k in 0..50 {
                s.rotate(&mut o, &[1e-3 * (k as f64 - 20.0)]);
                out.extend([o.unit().0, o.unit().1]);
            }
        }
    }
    out
}

/// `fourier` and `fourier_sum` give the engine the numbers they gave as a
/// type of their own (before they became a profile of the shared
/// near-disk), bit for bit: the digest below was printed by that code.
#[test]
fn near_disk_numbers_are_unchanged() {
    let numbers = near_disk_numbers();
    let d = digest(numbers.iter().copied());
    println!("{} numbers, digest {d:016x}", numbers.len());
    assert!(numbers.len() > 100_000, "{}", numbers.len());
    assert_eq!(format!("{d:016x}"), "5d378453be1d30a9");
}
