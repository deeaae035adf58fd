use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Objective, Scene};
use jamkit_sphere::Sphere;
use rand::SeedableRng;
use std::time::Instant;

fn main() {
    let n: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let skin: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.2);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let p = Packing::<2, Sphere>::random(Sphere, sizes, 0.84, &mut rng).unwrap();
    let mut scene = Scene::new(p, Potential::Harmonic, skin);
    let mut g = vec![0.0; scene.dof()];
    for round in 0..3 {
        let t = Instant::now();
        let reps = 20000;
        let mut e = 0.0;
        for _ in 0..reps {
            e += scene.energy_gradient(&mut g);
        }
        println!(
            "round {round}: {:.3} us/eval pairs={} e={e:.6e}",
            t.elapsed().as_secs_f64() * 1e6 / reps as f64,
            scene.neighbor_pairs()
        );
    }
}
