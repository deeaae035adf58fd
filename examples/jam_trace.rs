use jamkit_core::{Packing, Potential, SizeDistribution};
use jamkit_engine::{Fire, FireParams, Scene};
use jamkit_sphere::Sphere;
use rand::SeedableRng;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let dtmax: f64 = args[2].parse().unwrap();
    let v2 = args[3] == "2";
    let mut fp = if v2 {
        FireParams::fire2()
    } else {
        FireParams::default()
    };
    fp.dt_max = dtmax;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let p = Packing::<2, Sphere>::random(Sphere, sizes, 0.1, &mut rng).unwrap();
    let mut scene = Scene::new(p, Potential::Harmonic, 0.3);
    let mut fire = Fire::new(fp);
    let mut eps = 1e-3;
    let mut total = 0;
    let mut k = 0;
    loop {
        let out = fire.minimize(&mut scene).unwrap();
        total += out.steps;
        let e = out.energy / n as f64;
        if out.steps > 2000 || k % 100 == 0 {
            println!(
                "{k} phi={:.10} eps={eps:.2e} steps={} V/N={e:.3e} F2={:.2e} {:?}",
                scene.phi(),
                out.steps,
                out.force_sq,
                out.reason
            );
        }
        if e > 1e-16 && e < 2e-16 {
            break;
        }
        if (e > 1e-16) == (eps > 0.0) {
            eps = -0.5 * eps;
        }
        let phi = scene.phi();
        scene.set_phi(phi + eps);
        k += 1;
    }
    println!("total {total}");
}
