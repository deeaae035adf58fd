//! `fourier` and `fourier_sum` as a profile of the shared near-disk
//! (`jamkit_planar::profiled::Profiled`): the numbers they give the engine
//! are those they gave as a type of their own, bit for bit, and what the
//! orientation type changes.

use jamkit_core::{
    Angle, BodyOrientation, Contact, GapHessian, Pair, Rotation2, Shape, ShapeExt, Vector,
};
use jamkit_fourier::{FourierParams, FourierSumParams, Mode, NearDisk};
use jamkit_planar::profiled::Profiled;

/// The stream of random inputs the digest of
/// [`near_disk_numbers_are_unchanged`] was recorded with (splitmix64,
/// uniform in `[0, 1)`): another stream would give other numbers.
struct Splitmix(u64);

impl Splitmix {
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
/// `fourier_sum` of three modes with phases, each also as `Profiled` of
/// the same profile with orientations `Angle<1>`.
fn shapes() -> Vec<(NearDisk, Profiled<jamkit_fourier::FourierProfile>)> {
    let mut near_disks = Vec::new();
    for n in 2..=6 {
        for delta in [0.05, 0.1, 0.2, 0.3] {
            near_disks.push(NearDisk::fourier(&FourierParams {
                n,
                delta,
                inertia: None,
                gap: Default::default(),
            }));
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
        near_disks.push(NearDisk::fourier_sum(&FourierSumParams {
            modes: modes.clone(),
            delta,
            inertia: None,
            gap: Default::default(),
        }));
    }
    near_disks
        .into_iter()
        .filter_map(Result::ok)
        .map(|nd| {
            let p = nd.profiled();
            let angled = Profiled::new(p.profile().clone(), p.delta(), None).unwrap();
            (nd, angled)
        })
        .collect()
}

/// Random pairs: sizes in [0.5, 0.7], angles in (−π, π], separations
/// between overlapping and just apart in every direction.
fn pairs(count: usize) -> Vec<(f64, f64, f64, f64, Vector<2>)> {
    let mut u = Splitmix(7);
    let pi = std::f64::consts::PI;
    (0..count)
        .map(|_| {
            let (si, sj) = (0.5 + 0.2 * u.next(), 0.5 + 0.2 * u.next());
            let (ti, tj) = (pi - 2.0 * pi * u.next(), pi - 2.0 * pi * u.next());
            let dir = 2.0 * pi * u.next();
            let r = (si + sj) * (0.8 + 0.3 * u.next());
            (
                si,
                ti,
                sj,
                tj,
                Vector::<2>::new(r * dir.cos(), r * dir.sin()),
            )
        })
        .collect()
}

/// From the same `θ`, `Rotation2` (the families' orientation) and
/// `Angle<1>` (`Profiled`'s default) hold the same `e^{iθ}`, and then the
/// contacts and gap Hessians of `fourier` equal those of `Profiled` of its
/// profile with `Angle<1>` bit for bit, as do area and bounding radius: the
/// orientation type is all that separates them (how it turns, and how the
/// file's `[θ]` reads back, `orientation_types_part_under_turns`).
#[test]
fn near_disk_equals_profiled_with_angles_bit_for_bit() {
    let pairs = pairs(20_000);
    let (mut contacts, mut hessians, mut units) =
        (Tally::default(), Tally::default(), Tally::default());
    let mut shape_numbers = Tally::default();
    for (nd, p) in shapes() {
        shape_numbers.add(
            &[nd.volume(0.6), nd.bounding_radius(0.6)],
            &[p.volume(0.6), p.bounding_radius(0.6)],
        );
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
            hessians.add(
                &hessian_numbers(&ha.unwrap()),
                &hessian_numbers(&hb.unwrap()),
            );
        }
    }
    println!("orientation e^(iθ) from θ: {units:?}");
    println!("contacts (gap, grad_r, grad_rot_i, grad_rot_j): {contacts:?}");
    println!("gap Hessians: {hessians:?}");
    println!("areas and bounding radii: {shape_numbers:?}");
    assert!(contacts.compared > 1_000_000, "{contacts:?}");
    for t in [&units, &contacts, &hessians, &shape_numbers] {
        assert_eq!(t.differing, 0, "{t:?}");
    }
}

/// How the two orientation types move apart under the same turns: after
/// `steps` random small turns (|dθ| < 10⁻³, FIRE-like), how many of the
/// `e^{iθ}` differ and by how many ulps, and the file coordinate `[θ]` of
/// each and its round trip.
#[test]
fn orientation_types_part_under_turns() {
    let mut u = Splitmix(11);
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
/// after 50 turns by `Shape::rotate`. With `nested`, the exact gap's
/// contacts and Hessians are those of the nested solve
/// (`ExactSolve::Nested`) instead of the contacts' own solve.
fn near_disk_numbers(nested: bool) -> Vec<f64> {
    use jamkit_planar::gap2d::GapModel;
    use jamkit_planar::profiled::ExactSolve;
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
        let mut shapes: Vec<NearDisk> = [
            (2, 0.1),
            (3, 0.2),
            (4, 0.05),
            (5, 0.1),
            (6, 0.02),
            (7, 0.01),
        ]
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
                if nested && gap == GapModel::Exact {
                    // `Shape::contacts`' bounding test, then the nested solve.
                    let apart = d.norm() - s.bounding_radius(si) - s.bounding_radius(sj) > 0.05;
                    if let Some(e) = s
                        .profiled()
                        .exact_solve(&pair, 0.05, ExactSolve::Nested)
                        .filter(|_| !apart)
                    {
                        out.extend(contact_numbers(&e.contact()));
                        out.extend(hessian_numbers(&e.hessian()));
                    }
                    continue;
                }
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

/// `fourier` and `fourier_sum` give the engine the numbers they gave at
/// commit 21f51e7, where they were a type of their own with a first-order,
/// second-order and exact gap of its own, bit for bit (the exact gap's by
/// the nested solve): that commit printed this digest.
#[test]
fn near_disk_numbers_are_unchanged() {
    let numbers = near_disk_numbers(true);
    let d = digest(numbers.iter().copied());
    println!("{} numbers, digest {d:016x}", numbers.len());
    assert!(numbers.len() > 100_000, "{}", numbers.len());
    assert_eq!(format!("{d:016x}"), "5d378453be1d30a9");
}

/// The exact gap's contacts and Hessians (the joint iteration within its
/// reach) against the nested solve's on the same pairs and shapes: the
/// same contacts, every number within 1e-12 of the nested one, absolute or
/// relative (the two stop within ~1e-14 rad of the optimum; the Hessian
/// divides by `k` and by the curvature numerator), the first- and
/// second-order numbers identical.
#[test]
fn exact_numbers_are_the_nested_solve_s_to_its_tolerance() {
    let (a, b) = (near_disk_numbers(false), near_disk_numbers(true));
    assert_eq!(a.len(), b.len());
    let mut differ = 0;
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-12 * (1.0 + y.abs()), "{x} against {y}");
        differ += usize::from(x != y);
    }
    // The joint iteration ran: not every number is the nested solve's.
    assert!(differ > 1000, "{differ}");
}
