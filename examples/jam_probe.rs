use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Fire, FireParams, JamParams, Scene, jam};
use jamkit_observe::summarize;
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::time::Instant;

fn run<const D: usize>(n: usize, seed: u64, fp: FireParams) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let p = Packing::<D, Sphere>::random(Sphere, sizes, 0.1, &mut rng).unwrap();
    let mut scene = Scene::new(
        p,
        Potential::Harmonic,
        std::env::var("SKIN")
            .map(|s| s.parse().unwrap())
            .unwrap_or(0.3),
    );
    let mut fire = Fire::new(fp);
    let t = Instant::now();
    let out = jam(&mut scene, &mut fire, &JamParams::default()).unwrap();
    let el = t.elapsed().as_secs_f64();
    let s = summarize(&mut scene, D + 1);
    {
        use jamkit_engine::Objective;
        let mut g = vec![0.0; scene.dof()];
        let t = Instant::now();
        let reps = 20000;
        let mut e = 0.0;
        for _ in 0..reps {
            e += scene.energy_gradient(&mut g);
        }
        println!(
            "eval: {:.3} us/eval (e={e:.3e}) pairs={}",
            t.elapsed().as_secs_f64() * 1e6 / reps as f64,
            scene.neighbor_pairs()
        );
    }
    println!(
        "D={D} N={n} seed={seed} phi={:.6} V/N={:.3e} steps={} mins={} z={:.4} iso={} ratt={} builds={} t={:.2}s us/step={:.2}",
        out.phi,
        out.energy_per_particle,
        out.fire_steps,
        out.minimizations,
        s.z_j,
        s.iso_margin,
        s.n_rattlers,
        scene.neighbor_builds(),
        el,
        el * 1e6 / out.fire_steps as f64
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let d: usize = args[1].parse().unwrap();
    let n: usize = args[2].parse().unwrap();
    let seed: u64 = args[3].parse().unwrap();
    let dtmax: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(1.0);
    let v2 = args.get(5).map(|s| s == "2").unwrap_or(false);
    let mut fp = if v2 {
        FireParams::fire2()
    } else {
        FireParams::default()
    };
    fp.dt_max = dtmax;
    if d == 2 {
        run::<2>(n, seed, fp)
    } else {
        run::<3>(n, seed, fp)
    }
}
