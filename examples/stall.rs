//! Diagnose a stalled minimisation: `cargo run --release --example stall -- FILE.failed.json [steps]`.
use jamkit_core::Shape;
use jamkit_engine::{Fire, FireParams, Objective, Scene};
use jamkit_experiment::record::PackingFile;
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_observe::hessian::{Hessian, HessianOptions};

struct Diag {
    steps: u64,
}

impl PackingVisitor for Diag {
    type Output = ();
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) {
        let n = scene.packing().len();
        let k = scene.packing().shape.rot_dof();
        let stride = D + k;
        let mut g = vec![0.0; n * stride];
        let e = scene.energy_gradient(&mut g);
        let fsq: f64 = g.iter().map(|x| x * x).sum();
        println!("N={n} D={D} k={k} phi={:.12} V/N={:.3e} |g|^2={:.3e}", scene.phi(), e / n as f64, fsq);
        // gap histogram near zero
        let mut small = Vec::new();
        let mut n_contacts = 0;
        scene.for_each_contact(1e-6, |i, j, _, c| {
            if c.gap < 0.0 {
                n_contacts += 1;
            }
            if c.gap.abs() < 1e-6 {
                small.push((c.gap, i, j));
            }
        });
        small.sort_by(|a, b| a.0.abs().partial_cmp(&b.0.abs()).unwrap());
        println!("contacts {n_contacts}; |gap|<1e-6: {}", small.len());
        for (gap, i, j) in small.iter().take(12) {
            println!("  gap {gap:+.3e} bodies {i} {j}");
        }
        // per-body residual
        let mut per: Vec<(f64, usize)> = (0..n)
            .map(|b| (g[b * stride..(b + 1) * stride].iter().map(|x| x * x).sum::<f64>(), b))
            .collect();
        per.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
        for (w, b) in per.iter().take(5) {
            println!("  body {b}: share {:.3} g={:?}", w / fsq, &g[b * stride..(b + 1) * stride]);
        }
        // Hessian, full
        if std::env::var("NOHESS").is_ok() { return self.run(scene); }
        let h = Hessian::of_scene(&mut scene, &[], HessianOptions::default()).unwrap();
        {
            let inv_m = scene.packing().inverse_masses();
            let mut d = h.dense();
            for r in 0..h.size { for c in 0..h.size { d[(r, c)] *= (inv_m[r] * inv_m[c]).sqrt(); } }
            let w = d.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
            let top = w[h.size - 1];
            println!("mass-weighted omega_max^2 = {top:.4} -> 2/omega_max = {:.4}; top 5 {:?}", 2.0 / top.sqrt(), &w[h.size - 5..]);
        }
        let evd = h.dense().self_adjoint_eigen(faer::Side::Lower).unwrap();
        let (u, s) = (evd.U(), evd.S());
        let m = h.size;
        let lam: Vec<f64> = (0..m).map(|i| s[i]).collect();
        let neg = lam.iter().filter(|&&l| l < -1e-12).count();
        println!("hessian size {m}; lambda<-1e-12: {neg}; lowest: {:?}", &lam[..12.min(m)]);
        // gradient projection per mode
        let mut proj: Vec<(f64, f64, usize)> = (0..m)
            .map(|a| {
                let c: f64 = (0..m).map(|r| u[(r, a)] * g[r]).sum();
                (c * c, lam[a], a)
            })
            .collect();
        let bands = [-1.0, -1e-12, 1e-12, 1e-9, 1e-6, 1e-3, 1e9];
        for w in bands.windows(2) {
            let sh: f64 = proj.iter().filter(|p| p.1 >= w[0] && p.1 < w[1]).map(|p| p.0).sum();
            let cnt = proj.iter().filter(|p| p.1 >= w[0] && p.1 < w[1]).count();
            println!("  lambda in [{:e},{:e}): {cnt} modes, gradient share {:.3e}", w[0], w[1], sh / fsq);
        }
        proj.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
        for (c2, l, a) in proj.iter().take(8) {
            // mode's main body and rotational share
            let mut best = (0.0, 0usize);
            let mut rot = 0.0;
            for r in 0..m {
                let w = u[(r, *a)] * u[(r, *a)];
                if w > best.0 {
                    best = (w, r / stride);
                }
                if r % stride >= D {
                    rot += w;
                }
            }
            println!(
                "  mode {a}: lambda {l:+.3e} grad share {:.3e} newton dist {:.3e} main body {} ({:.2}) rot {:.2}",
                c2 / fsq,
                c2.sqrt() / l.abs().max(1e-300),
                best.1,
                best.0,
                rot
            );
        }
        self.run(scene);
    }
}

impl Diag {
    fn run<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) {
        let n = scene.packing().len();
        let stride = D + scene.packing().shape.rot_dof();
        if self.steps > 0 {
            let dt_max: f64 = std::env::var("DTMAX").ok().map(|s| s.parse().unwrap()).unwrap_or(0.5);
            let base = if std::env::var("FIRE2").is_ok() { FireParams::fire2() } else { FireParams::default() };
            let mut fire = Fire::new(FireParams {
                max_steps: 10_000,
                dt_max,
                ..base
            });
            for round in 0..(self.steps / 10_000) {
                let r = fire.minimize(&mut scene);
                let mut g2 = vec![0.0; n * stride];
                let e = scene.energy_gradient(&mut g2);
                let f: f64 = g2.iter().map(|x| x * x).sum();
                println!("round {round}: {:?} V/N {:.4e} |g|^2 {:.3e}", r.as_ref().map(|o| o.steps).map_err(|_| "cap"), e / n as f64, f);
                if r.is_ok() {
                    break;
                }
            }
        }
        let _ = scene.inverse_masses();
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let file = PackingFile::load_checked(std::path::Path::new(&args[1])).unwrap();
    let steps = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0);
    reload(&file, Diag { steps }).unwrap();
}
