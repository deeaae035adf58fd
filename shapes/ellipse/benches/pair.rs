//! `cargo bench -p jamkit-ellipse`: one pair's exact gap, as the energy
//! pass asks for it (`max_gap = 0`), by [`Ellipse::exact_gap`] (Halley's
//! iteration) and by [`Ellipse::exact_gap_safeguarded`] (the safeguarded
//! iteration it falls back on), each over the same 1024 random pairs of
//! sizes 0.5 and 0.7 at α = 1.1, 1.5 and 3:
//!
//! * `contact/…`: overlapping by less than 10⁻⁴ (the contacts of a packing
//!   near jamming);
//! * `reach/…`: centres uniformly between the sum of the short and the sum
//!   of the long semi-axes (the pairs whose bounding disks overlap, most of
//!   them apart).
//!
//! Throughput is in pairs.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use jamkit_core::{Pair, Vector};
use jamkit_ellipse::{Axis, Ellipse, EllipseParams};
use std::hint::black_box;

/// One pair: sizes, orientations, separation.
type Case = (f64, Axis, f64, Axis, Vector<2>);

/// A deterministic uniform stream in `[0, 1)`.
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    move || rng.random::<f64>()
}

/// 1024 pairs; `contact`: moved along the line of centres until they
/// overlap by less than 10⁻⁴.
fn cases(s: &Ellipse, contact: bool) -> Vec<Case> {
    let mut rnd = uniform(3);
    let mut out = Vec::new();
    while out.len() < 1024 {
        let (ri, rj) = if rnd() < 0.5 { (0.5, 0.7) } else { (0.7, 0.5) };
        let (oi, oj) = (Axis::new(6.3 * rnd()), Axis::new(6.3 * rnd()));
        let phi = 6.3 * rnd();
        let u = Vector::<2>::new(phi.cos(), phi.sin());
        let (bi, bj) = (s.semi_axes(ri).1, s.semi_axes(rj).1);
        let (ai, aj) = (s.semi_axes(ri).0, s.semi_axes(rj).0);
        let mut d = u * (bi + bj + (ai + aj - bi - bj) * rnd());
        if contact {
            let target = -1e-4 * rnd();
            for _ in 0..20 {
                let h = s
                    .exact_gap_safeguarded(&Pair::new(ri, oi, rj, oj, d), f64::INFINITY)
                    .unwrap()
                    .gap;
                d += u * (target - h);
            }
            let h = s
                .exact_gap_safeguarded(&Pair::new(ri, oi, rj, oj, d), f64::INFINITY)
                .unwrap()
                .gap;
            if !(h < 0.0 && h > -1e-4) {
                continue;
            }
        }
        out.push((ri, oi, rj, oj, d));
    }
    out
}

fn pair(c: &mut Criterion) {
    for (set, contact) in [("contact", true), ("reach", false)] {
        let mut group = c.benchmark_group(set);
        group.throughput(Throughput::Elements(1024));
        for aspect in [1.1, 1.5, 3.0] {
            let s = Ellipse::new(&EllipseParams {
                aspect,
                inertia: None,
            })
            .unwrap();
            let pairs = cases(&s, contact);
            // What the energy pass meets: pairs skipped, and the mean
            // iterations of the others.
            let (mut kept, mut steps, mut old_steps) = (0, 0, 0);
            for (ri, oi, rj, oj, d) in &pairs {
                if let Some(m) = s.exact_gap(*ri, oi, *rj, oj, d, 0.0) {
                    kept += 1;
                    steps += m.iterations;
                }
                if let Some(m) = s.exact_gap_safeguarded(&Pair::new(*ri, *oi, *rj, *oj, *d), 0.0) {
                    old_steps += m.iterations;
                }
            }
            eprintln!(
                "{set}/{aspect}: {kept} of 1024 pairs solved, {:.2} iterations each \
                 (safeguarded {:.2} on its own), {} fall-backs so far",
                steps as f64 / kept.max(1) as f64,
                old_steps as f64 / kept.max(1) as f64,
                jamkit_ellipse::fallbacks()
            );
            group.bench_function(format!("halley/{aspect}"), |b| {
                b.iter(|| {
                    let mut sum = 0.0;
                    for (ri, oi, rj, oj, d) in &pairs {
                        if let Some(m) = s.exact_gap(*ri, oi, *rj, oj, black_box(d), 0.0) {
                            sum += m.gap;
                        }
                    }
                    sum
                })
            });
            group.bench_function(format!("safeguarded/{aspect}"), |b| {
                b.iter(|| {
                    let mut sum = 0.0;
                    for (ri, oi, rj, oj, d) in &pairs {
                        if let Some(m) = s.exact_gap_safeguarded(
                            &Pair::new(*ri, *oi, *rj, *oj, *black_box(d)),
                            0.0,
                        ) {
                            sum += m.gap;
                        }
                    }
                    sum
                })
            });
        }
        group.finish();
    }
}

criterion_group!(
    name = benches;
    // No plots (criterion's plotters backend needs system fonts).
    config = Criterion::default().without_plots();
    targets = pair
);
criterion_main!(benches);
