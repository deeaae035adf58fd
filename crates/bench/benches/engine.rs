//! `cargo bench`: the engine's hot paths.
//!
//! * `energy_gradient/N`: one energy-and-gradient evaluation of binary disks
//!   at φ = 0.84 (random, overlapping), N = 256 … 16384: must grow linearly.
//! * `energy_gradient_near_disks/N`: the same for the paper's near-disks
//!   (`fourier`, n = 2, Δ = 0.1, φ = 0.86), N = 256 and 1024.
//! * `jam_disks/256`: one whole N = 256 packing with the paper's protocol.
//! * `energy_gradient_harmonic/{FirstOrder,Exact,ExactJoint}`: one
//!   energy-and-gradient evaluation of N = 128 `harmonic` near-spheres
//!   (`Ŷ_22`, Δ = 0.1, φ = 0.66, random, overlapping) with the first-order
//!   and the exact gap, the latter by the nested and the joint solver
//!   (docs/reports/performance.md, "Where the time of a packing goes").
//! * `exact_pair/{first_order,cold,warm}`: one pair evaluation (gap and
//!   gradient) of `fourier` near-disks (n = 2, Δ = 0.1) near contact, by
//!   the paper's first-order gap, and by the exact gap started cold (from
//!   the first-order guesses, `Shape::contacts`) and warm (from the memo
//!   of the same pair before a move of 1e-6, `Shape::contacts_warm`;
//!   `warm_unmoved`: from the memo of the same configuration).
//! * `nonconvex_pair/{convex_exact,arcs}`: one pair evaluation (gap and
//!   gradient, `Shape::contacts`) of `fourier` near-disks with n = 16 near
//!   contact, by the exact gap of a convex outline (Δ = 0.05, below the
//!   convex limit 1/(n + 1/n) ≈ 0.062) and by the arcs of a non-convex one
//!   (Δ = 0.1, `jamkit_planar::arcs`).
//!
//! The N = 1024 packing benchmark is `jamkit bench packing` (one packing is
//! seconds long, too long for criterion's repetitions).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Fire, FireParams, JamParams, Objective, Scene, jam};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::hint::black_box;

fn disks(n: usize, phi: f64, seed: u64) -> Scene<2, Sphere> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let packing = Packing::<2, Sphere>::random(Sphere, sizes, phi, &mut rng).unwrap();
    Scene::new(packing, Potential::Harmonic, 0.2)
}

fn energy_gradient(c: &mut Criterion) {
    let mut group = c.benchmark_group("energy_gradient");
    for n in [256, 1024, 4096, 16384] {
        let mut scene = disks(n, 0.84, 1);
        let mut grad = vec![0.0; scene.dof()];
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(scene.energy_gradient(&mut grad)))
        });
    }
    group.finish();
}

fn energy_gradient_near_disks(c: &mut Criterion) {
    let mut group = c.benchmark_group("energy_gradient_near_disks");
    let shape = NearDisk::fourier(&FourierParams {
        n: 2,
        delta: 0.1,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    for n in [256, 1024] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let sizes = SizeDistribution::default().sample(n, &mut rng);
        let packing = Packing::<2, NearDisk>::random(shape.clone(), sizes, 0.86, &mut rng).unwrap();
        let mut scene = Scene::new(packing, Potential::Harmonic, 0.21);
        let mut grad = vec![0.0; scene.dof()];
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(scene.energy_gradient(&mut grad)))
        });
    }
    group.finish();
}

fn jam_disks(c: &mut Criterion) {
    let mut group = c.benchmark_group("jam_disks");
    group.sample_size(10);
    group.bench_function("256", |b| {
        b.iter(|| {
            let mut scene = disks(256, 0.1, 1);
            let mut fire = Fire::new(FireParams::default());
            black_box(jam(&mut scene, &mut fire, &JamParams::default()).unwrap())
        })
    });
    group.finish();
}

fn energy_gradient_harmonic(c: &mut Criterion) {
    use jamkit_core::gap_model::GapModel;
    use jamkit_harmonic::{Harmonic, HarmonicParams};
    let mut group = c.benchmark_group("energy_gradient_harmonic");
    use jamkit_harmonic::ExactSolver;
    let cases = [
        (GapModel::FirstOrder, ExactSolver::Nested, "FirstOrder"),
        (GapModel::Exact, ExactSolver::Nested, "Exact"),
        (GapModel::Exact, ExactSolver::Joint, "ExactJoint"),
    ];
    for (gap, exact_solver, name) in cases {
        let shape = Harmonic::new(&HarmonicParams {
            l: Some(2),
            m: Some(2),
            modes: None,
            delta: 0.1,
            inertia: None,
            gap,
            exact_solver,
        })
        .unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let sizes = SizeDistribution::default().sample(128, &mut rng);
        let packing = Packing::<3, Harmonic>::random(shape, sizes, 0.66, &mut rng).unwrap();
        let mut scene = Scene::new(packing, Potential::Harmonic, 0.2);
        let mut grad = vec![0.0; scene.dof()];
        group.bench_function(name, |b| {
            b.iter(|| black_box(scene.energy_gradient(&mut grad)))
        });
    }
    group.finish();
}

fn exact_pair(c: &mut Criterion) {
    use jamkit_core::{Pair, PairMemo, Rotation2, Shape, Vector};
    use jamkit_planar::gap2d::GapModel;
    use rand::RngExt;
    let shape = |gap| {
        NearDisk::fourier(&FourierParams {
            n: 2,
            delta: 0.1,
            inertia: None,
            gap,
        })
        .unwrap()
    };
    let (first, exact) = (shape(GapModel::FirstOrder), shape(GapModel::Exact));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let pi = std::f64::consts::PI;
    let mut pairs = Vec::new();
    let mut memos: Vec<PairMemo> = Vec::new();
    let mut stills: Vec<PairMemo> = Vec::new();
    while pairs.len() < 1024 {
        let (si, sj) = (
            0.5 + 0.2 * rng.random::<f64>(),
            0.5 + 0.2 * rng.random::<f64>(),
        );
        let (ti, tj) = (
            2.0 * pi * rng.random::<f64>(),
            2.0 * pi * rng.random::<f64>(),
        );
        let dir = 2.0 * pi * rng.random::<f64>();
        let r = (si + sj) * (0.97 + 0.04 * rng.random::<f64>());
        let at = |r: f64, dt: f64| {
            Pair::new(
                si,
                Rotation2::new(ti + dt),
                sj,
                Rotation2::new(tj - dt),
                Vector::<2>::new(r * dir.cos(), r * dir.sin()),
            )
        };
        let (mut memo, mut still) = (None, None);
        let mut found = false;
        exact.contacts_warm(&at(r - 1e-6, 1e-6), 0.0, &mut memo, |_| found = true);
        exact.contacts_warm(&at(r, 0.0), 0.0, &mut still, |_| found = true);
        if found {
            pairs.push(at(r, 0.0));
            memos.push(memo);
            stills.push(still);
        }
    }
    let mut group = c.benchmark_group("exact_pair");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    let mut sum = 0.0;
    group.bench_function("first_order", |b| {
        b.iter(|| {
            for p in &pairs {
                first.contacts(p, 0.0, |c| sum += c.gap);
            }
        })
    });
    group.bench_function("cold", |b| {
        b.iter(|| {
            for p in &pairs {
                exact.contacts(p, 0.0, |c| sum += c.gap);
            }
        })
    });
    let mut scratch = memos.clone();
    group.bench_function("warm", |b| {
        b.iter(|| {
            scratch.copy_from_slice(&memos);
            for (p, m) in pairs.iter().zip(&mut scratch) {
                exact.contacts_warm(p, 0.0, m, |c| sum += c.gap);
            }
        })
    });
    group.bench_function("warm_unmoved", |b| {
        b.iter(|| {
            scratch.copy_from_slice(&stills);
            for (p, m) in pairs.iter().zip(&mut scratch) {
                exact.contacts_warm(p, 0.0, m, |c| sum += c.gap);
            }
        })
    });
    black_box(sum);
    group.finish();
}

fn nonconvex_pair(c: &mut Criterion) {
    use jamkit_core::{Pair, Rotation2, Shape, Vector};
    use jamkit_planar::gap2d::GapModel;
    use rand::RngExt;
    let pi = std::f64::consts::PI;
    let mut group = c.benchmark_group("nonconvex_pair");
    for (delta, name) in [(0.05, "convex_exact"), (0.1, "arcs")] {
        let shape = NearDisk::fourier(&FourierParams {
            n: 16,
            delta,
            inertia: None,
            gap: GapModel::Exact,
        })
        .unwrap();
        assert_eq!(shape.is_convex(), delta < 0.06, "Δ = {delta}");
        // Random pairs whose centres are within ±Δ/n of the disks' contact
        // distance (relative), kept if they touch or overlap.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut pairs = Vec::new();
        while pairs.len() < 1024 {
            let (si, sj) = (
                0.5 + 0.2 * rng.random::<f64>(),
                0.5 + 0.2 * rng.random::<f64>(),
            );
            let (ti, tj, dir) = (
                2.0 * pi * rng.random::<f64>(),
                2.0 * pi * rng.random::<f64>(),
                2.0 * pi * rng.random::<f64>(),
            );
            let r = (si + sj) * (1.0 + delta / 16.0 * (2.0 * rng.random::<f64>() - 1.0));
            let pair = Pair::new(
                si,
                Rotation2::new(ti),
                sj,
                Rotation2::new(tj),
                Vector::<2>::new(r * dir.cos(), r * dir.sin()),
            );
            let mut found = false;
            shape.contacts(&pair, 0.0, |_| found = true);
            if found {
                pairs.push(pair);
            }
        }
        group.throughput(Throughput::Elements(pairs.len() as u64));
        let mut sum = 0.0;
        group.bench_function(name, |b| {
            b.iter(|| {
                for p in &pairs {
                    shape.contacts(black_box(p), 0.0, |c| sum += c.gap + c.grad_rot_i[0]);
                }
            })
        });
        black_box(sum);
    }
    group.finish();
}

criterion_group!(
    name = benches;
    // NOTE: no plots: criterion's plotters backend panicked on a machine
    // without system fonts (the numbers are what docs/reports/performance.md uses).
    config = Criterion::default().without_plots();
    targets = energy_gradient, energy_gradient_near_disks, jam_disks, energy_gradient_harmonic, exact_pair,
        nonconvex_pair
);
criterion_main!(benches);
