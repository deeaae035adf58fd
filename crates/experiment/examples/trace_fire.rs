//! Is the energy FIRE minimises smooth along its path? Load a packing file
//! (typically a `packings/<id>.failed.json`) and continue FIRE from it,
//! checking every step:
//!
//! * `ΔV` against the trapezoid `−½ (F_k + F_{k+1})·Δq` of the reported
//!   forces (a force that is the energy's gradient leaves `O(|Δq|³)`);
//! * the contacts of every pair, by count and gap: a pair whose number of
//!   overlapping contacts changes, or whose deepest gap jumps, between two
//!   evaluations;
//! * on a step that misses the trapezoid by more than a tenth of its `ΔV`
//!   (`fourier` near-disks): the pairs whose contacts changed, with their
//!   contacts and, from a file, every stationary point of their arcs by
//!   brute force; in the `jam` mode also the two pairs whose own `ΔV`
//!   misses the trapezoid of their own gradient most. Only misses above
//!   `TRACE_MIN_JUMP` (default 10⁻¹³) are explained.
//!
//! ```sh
//! cargo run --release --example trace_fire -- out/x/packings/ID.failed.json [STEPS]
//! ```
//!
//! Or jam `fourier` near-disks with the exact gap from a random start
//! (sizes 0.5 and 0.7 alternating, φ from 0.6 in steps of 10⁻³, the window
//! 10⁻¹⁶ … 2·10⁻¹⁶ of V/N, a plain bisection), one line per minimisation:
//!
//! ```sh
//! cargo run --release --example trace_fire -- jam N_MODE DELTA PARTICLES SEED MAX_STEPS SECONDS
//! ```

use jamkit_core::{Pair, Shape};
use jamkit_engine::{Fire, FireParams, MinimizeOutcome, Objective, Scene};
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_format::PackingFile;
use std::collections::BTreeMap;

type Gaps = BTreeMap<(usize, usize), Vec<f64>>;
type Pairs<const D: usize, O> = BTreeMap<(usize, usize), Pair<D, O>>;
/// The last evaluation: energy, gradient, overlapping gaps, pairs.
type Last<const D: usize, O> = (f64, Vec<f64>, Gaps, Pairs<D, O>);
/// Each step's `|ΔV − trapezoid|`, evaluation and description.
type Worst = Vec<(f64, u64, String)>;
/// A pair's contacts described in detail (for the steps that jump).
type Explain<'a, const D: usize, O> = &'a dyn Fn(&Pair<D, O>) -> String;
/// A pair's own `ΔV − trapezoid` between two states of it.
type PairErr<'a, const D: usize, O> = &'a dyn Fn(&Pair<D, O>, &Pair<D, O>) -> f64;

struct Traced<'a, const D: usize, S: Shape<D>> {
    scene: &'a mut Scene<D, S>,
    last: Option<Last<D, S::Orientation>>,
    dq: Vec<f64>,
    explain: Option<Explain<'a, D, S::Orientation>>,
    pair_err: Option<PairErr<'a, D, S::Orientation>>,
    explained: u64,
    calls: u64,
    worst: Worst,
    events: u64,
    verbose: bool,
    /// Energy misses larger than this are explained pair by pair
    /// (`TRACE_MIN_JUMP`, default 1e-13).
    min_jump: f64,
}

fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", items.join(" "))
}

fn gaps_of<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> Gaps {
    gaps_pairs(scene).0
}

/// The overlapping gaps of every pair, and every pair within the bounding
/// test.
fn gaps_pairs<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
) -> (Gaps, Pairs<D, S::Orientation>) {
    let mut gaps: Gaps = BTreeMap::new();
    let mut pairs = BTreeMap::new();
    let p = scene.packing();
    let (sizes, orientations) = (p.sizes.clone(), p.orientations.clone());
    scene.for_each_contact(0.0, |i, j, d, c| {
        pairs
            .entry((i, j))
            .or_insert_with(|| Pair::new(sizes[i], orientations[i], sizes[j], orientations[j], *d));
        if c.gap < 0.0 {
            gaps.entry((i, j)).or_default().push(c.gap);
        }
    });
    for v in gaps.values_mut() {
        v.sort_by(f64::total_cmp);
    }
    (gaps, pairs)
}

impl<const D: usize, S: Shape<D>> Objective for Traced<'_, D, S> {
    fn dof(&self) -> usize {
        Objective::dof(&*self.scene)
    }
    fn bodies(&self) -> usize {
        Objective::bodies(&*self.scene)
    }
    fn inverse_masses(&self) -> &[f64] {
        Objective::inverse_masses(&*self.scene)
    }
    fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
        let e = self.scene.energy_gradient(grad);
        let (gaps, pairs) = gaps_pairs(self.scene);
        self.calls += 1;
        if let Some((e0, g0, gaps0, pairs0)) = &self.last {
            let step: f64 = self.dq.iter().map(|x| x * x).sum::<f64>().sqrt();
            if step > 0.0 {
                let pred: f64 = 0.5
                    * g0.iter()
                        .zip(grad.iter())
                        .zip(&self.dq)
                        .map(|((a, b), d)| (a + b) * d)
                        .sum::<f64>();
                let err = (e - e0) - pred;
                let mut note = String::new();
                let mut changed = Vec::new();
                for (k, v) in gaps.iter() {
                    match gaps0.get(k) {
                        Some(v0) if v0.len() == v.len() => {
                            let jump = v0
                                .iter()
                                .zip(v)
                                .map(|(a, b)| (a - b).abs())
                                .fold(0.0, f64::max);
                            if jump > 100.0 * step {
                                note += &format!(" {k:?} {}->{}", list(v0), list(v));
                                changed.push(*k);
                            }
                        }
                        other => {
                            note += &format!(
                                " {k:?} {}->{}",
                                list(&other.cloned().unwrap_or_default()),
                                list(v)
                            );
                            changed.push(*k);
                        }
                    }
                }
                for (k, v0) in gaps0.iter() {
                    if !gaps.contains_key(k) {
                        note += &format!(" {k:?} {}->[]", list(v0));
                        changed.push(*k);
                    }
                }
                // A step whose energy misses the trapezoid by more than a
                // tenth of its change: each changed pair before and after.
                if let Some(explain) = self.explain
                    && err.abs() > self.min_jump
                    && err.abs() > 0.1 * (e - e0).abs()
                    && self.explained < 12
                {
                    self.explained += 1;
                    println!(
                        "jump at eval {}: |dq| {step:.2e} dV {:.3e} err {err:.3e} V {e:.4e}",
                        self.calls,
                        e - e0
                    );
                    // With a pair's own trapezoid, the pairs that miss it
                    // most (contacts changing or not).
                    let mut shown = changed.clone();
                    if let Some(pair_err) = self.pair_err {
                        let mut errs: Vec<(f64, (usize, usize))> = pairs
                            .iter()
                            .filter_map(|(k, b)| pairs0.get(k).map(|a| (pair_err(a, b), *k)))
                            .collect();
                        errs.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
                        for (e, k) in errs.iter().take(2) {
                            println!("  pair {k:?} misses its trapezoid by {e:.3e}");
                            if !shown.contains(k) {
                                shown.push(*k);
                            }
                        }
                    }
                    for k in &shown {
                        if let (Some(a), Some(b)) = (pairs0.get(k), pairs.get(k)) {
                            println!("  pair {k:?} before: {}", explain(a));
                            println!("  pair {k:?} after:  {}", explain(b));
                        }
                    }
                }
                if !note.is_empty() {
                    self.events += 1;
                    if self.verbose && self.events <= 40 {
                        println!(
                            "eval {}: |dq| {step:.2e} dV {:.3e} err {err:.3e}:{note}",
                            self.calls,
                            e - e0
                        );
                    }
                }
                self.worst.push((
                    err.abs(),
                    self.calls,
                    format!("|dq| {step:.2e} dV {:.3e} V {e:.6e}", e - e0),
                ));
            }
        }
        self.last = Some((e, grad.to_vec(), gaps, pairs));
        self.dq.iter_mut().for_each(|x| *x = 0.0);
        e
    }
    fn displace(&mut self, dq: &[f64]) {
        for (a, b) in self.dq.iter_mut().zip(dq) {
            *a += b;
        }
        Objective::displace(self.scene, dq);
    }
    fn phi(&self) -> f64 {
        Objective::phi(&*self.scene)
    }
    fn translations_per_body(&self) -> usize {
        D
    }
    fn hessian_entries(&mut self, entries: &mut Vec<(u32, u32, f64)>) -> jamkit_core::Result<bool> {
        Objective::hessian_entries(self.scene, entries)
    }
    fn save(&mut self) {
        Objective::save(self.scene);
        self.last = None;
    }
    fn restore(&mut self) {
        Objective::restore(self.scene);
        self.last = None;
    }
    fn stiffness_blocks(&mut self, blocks: &mut Vec<f64>) -> bool {
        Objective::stiffness_blocks(self.scene, blocks)
    }
}

/// One minimisation traced: its outcome, the evaluations, those with
/// contact changes, and every step's `|ΔV − trapezoid|` (largest first).
fn traced<const D: usize, S: Shape<D>>(
    fire: &mut Fire,
    scene: &mut Scene<D, S>,
    verbose: bool,
    explain: Option<Explain<'_, D, S::Orientation>>,
    pair_err: Option<PairErr<'_, D, S::Orientation>>,
) -> (jamkit_core::Result<MinimizeOutcome>, u64, u64, Worst) {
    let dof = Objective::dof(&*scene);
    let mut t = Traced {
        scene,
        last: None,
        dq: vec![0.0; dof],
        calls: 0,
        worst: Vec::new(),
        events: 0,
        verbose,
        explain,
        pair_err,
        explained: 0,
        min_jump: std::env::var("TRACE_MIN_JUMP")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1e-13),
    };
    let out = fire.minimize(&mut t);
    let mut worst = std::mem::take(&mut t.worst);
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    (out, t.calls, t.events, worst)
}

struct Trace {
    steps: u64,
    settings: FireParams,
}

impl PackingVisitor for Trace {
    type Output = ();
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) {
        let n = scene.packing().len();
        let dof = Objective::dof(&scene);
        let mut g = vec![0.0; dof];
        let e = scene.energy_gradient(&mut g);
        let gaps = gaps_of(&mut scene);
        let contacts: usize = gaps.values().map(Vec::len).sum();
        let multi = gaps.values().filter(|v| v.len() > 1).count();
        println!(
            "N = {n}, φ = {:.12}, V/N = {:.4e}, Σg² = {:.3e}, {contacts} overlapping contacts on {} pairs ({multi} with several)",
            scene.phi(),
            e / n as f64,
            g.iter().map(|x| x * x).sum::<f64>(),
            gaps.len()
        );
        let mut fire = Fire::new(FireParams {
            max_steps: self.steps,
            ..self.settings.for_family(&scene.packing().shape)
        });
        // Fourier near-disks: the contacts of a pair that jumps, and its
        // stationary points by a dense scan.
        let fourier = (&scene.packing().shape as &dyn std::any::Any)
            .downcast_ref::<jamkit_fourier::NearDisk>()
            .map(|s| s.profiled().clone());
        let explain = move |p: &Pair<D, S::Orientation>| -> String {
            match (
                &fourier,
                (p as &dyn std::any::Any).downcast_ref::<Pair<2, jamkit_fourier::Angle>>(),
            ) {
                (Some(s), Some(p)) => format!("{}\n    scan:{}", describe(s, p), scan(s, p)),
                _ => String::new(),
            }
        };
        let (out, calls, events, worst) = traced(&mut fire, &mut scene, true, Some(&explain), None);
        println!("{calls} evaluations, {events} with contact changes; largest |ΔV − trapezoid|:");
        for (err, k, s) in worst.iter().take(10) {
            println!("  eval {k}: {err:.3e} ({s})");
        }
        let e = scene.energy_gradient(&mut g);
        println!(
            "after: {}, V/N = {:.4e}, Σg² = {:.3e}",
            match out {
                Ok(o) => format!("stopped {:?} after {} steps", o.reason, o.steps),
                Err(e) => format!("{e}"),
            },
            e / n as f64,
            g.iter().map(|x| x * x).sum::<f64>()
        );
        // The body with the largest residual force, and its pairs.
        let per = dof / n;
        let (body, share) = (0..n)
            .map(|b| {
                (
                    b,
                    g[b * per..(b + 1) * per].iter().map(|x| x * x).sum::<f64>(),
                )
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        println!("body {body}: Σg² {share:.3e}, its pairs:");
        let (gaps, pairs) = gaps_pairs(&mut scene);
        for (k, p) in pairs.iter().filter(|(k, _)| k.0 == body || k.1 == body) {
            let overlaps = gaps.get(k).map_or(String::new(), |v| list(v));
            println!("  pair {k:?} {overlaps}: {}", explain(p));
        }
    }
}

/// Jam `particles` fourier near-disks (sizes 0.5 and 0.7) by a plain
/// bisection on φ (steps of 1e-3 from φ = 0.6, the window 1e-16 … 2e-16
/// of V/N), every minimisation traced.
fn jam_mode(n: u32, delta: f64, particles: usize, seed: u64, max_steps: u64, budget: f64) {
    use jamkit_fourier::{FourierParams, NearDisk};
    use rand::SeedableRng;
    let s = NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap: jamkit_planar::gap2d::GapModel::Exact,
    })
    .unwrap();
    let sizes: Vec<f64> = (0..particles)
        .map(|k| if k % 2 == 0 { 0.5 } else { 0.7 })
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let skin = 0.4 * s.bounding_radius(0.5);
    let s_explain = s.clone();
    let packing = jamkit_core::Packing::random(s, sizes, 0.6, &mut rng).unwrap();
    let mut scene = Scene::new(packing, jamkit_core::Potential::Harmonic, skin);
    let params = FireParams {
        energy_tol: 1e-16,
        force_tol: 1e-25,
        max_steps,
        ..FireParams::default()
    }
    .for_family(&scene.packing().shape);
    let mut fire = Fire::new(params);
    let profiled = s_explain.profiled().clone();
    let explain = move |p: &Pair<2, jamkit_fourier::Angle>| describe(&profiled, p);
    let s_err = s_explain.clone();
    let pair_err = move |a: &Pair<2, jamkit_fourier::Angle>, b: &Pair<2, jamkit_fourier::Angle>| {
        trapezoid_miss(&s_err, a, b)
    };
    let mut eps = 1e-3;
    let start = std::time::Instant::now();
    let dof = Objective::dof(&scene);
    for round in 0..2000 {
        let t0 = std::time::Instant::now();
        let (out, calls, events, worst) = traced(
            &mut fire,
            &mut scene,
            false,
            Some(&explain),
            Some(&pair_err),
        );
        let mut g = vec![0.0; dof];
        let e = scene.energy_gradient(&mut g) / particles as f64;
        let gaps = gaps_of(&mut scene);
        let contacts: usize = gaps.values().map(Vec::len).sum();
        let multi = gaps.values().filter(|v| v.len() > 1).count();
        let (steps, reason) = match &out {
            Ok(o) => (o.steps, format!("{:?}", o.reason)),
            Err(_) => (max_steps, "capped".into()),
        };
        println!(
            "{round}: φ {:.6} V/N {e:.3e} Σg² {:.2e} steps {steps} {reason} evals {calls} contact-events {events} contacts {contacts} multi {multi} worst-err {:.2e} [{}] {:.1}s",
            scene.phi(),
            g.iter().map(|x| x * x).sum::<f64>(),
            worst.first().map_or(0.0, |w| w.0),
            worst.first().map_or(String::new(), |w| w.2.clone()),
            t0.elapsed().as_secs_f64()
        );
        if out.is_err() || start.elapsed().as_secs_f64() > budget {
            println!(
                "stopped at φ {:.6} after {:.0} s",
                scene.phi(),
                start.elapsed().as_secs_f64()
            );
            return;
        }
        if e > 1e-16 && e < 2e-16 {
            println!("jammed at φ {:.6}", scene.phi());
            // The state, to the bit: the box's edges, then per body
            // `x y θ R⁰`.
            let p = scene.packing();
            let edges = p.bbox.edges();
            println!("box {:?} {:?}", edges[0], edges[1]);
            for k in 0..p.len() {
                let r = p.positions[k];
                let theta = p.orientations[k].theta();
                println!("body {:?} {:?} {theta:?} {:?}", r[0], r[1], p.sizes[k]);
            }
            return;
        }
        let over = e >= 2e-16;
        if over == (eps > 0.0) {
            eps *= -0.5;
        }
        let phi = scene.phi();
        scene.set_phi(phi + eps);
    }
}

/// A pair's harmonic energy `Σ ½h²` (overlapping contacts) at `b` minus
/// that at `a`, less the trapezoid of its gradients in `(r_ij, θ_i, θ_j)`.
fn trapezoid_miss(
    s: &jamkit_fourier::NearDisk,
    a: &Pair<2, jamkit_fourier::Angle>,
    b: &Pair<2, jamkit_fourier::Angle>,
) -> f64 {
    let energy = |p: &Pair<2, jamkit_fourier::Angle>| {
        let (mut v, mut g) = (0.0, [0.0; 4]);
        s.contacts(p, 0.0, |c| {
            let h = c.gap.min(0.0);
            v += 0.5 * h * h;
            for (x, d) in
                g.iter_mut()
                    .zip([c.grad_r[0], c.grad_r[1], c.grad_rot_i[0], c.grad_rot_j[0]])
            {
                *x += h * d;
            }
        });
        (v, g)
    };
    let ((va, ga), (vb, gb)) = (energy(a), energy(b));
    let dq = [
        b.r_ij[0] - a.r_ij[0],
        b.r_ij[1] - a.r_ij[1],
        b.o_i.theta() - a.o_i.theta(),
        b.o_j.theta() - a.o_j.theta(),
    ];
    let pred: f64 = (0..4).map(|k| 0.5 * (ga[k] + gb[k]) * dq[k]).sum();
    (vb - va) - pred
}

/// Every stationary point with `h < 0` of every pair of arcs, by brute
/// force ([`jamkit_planar::arcs::scan_stationary`], 2·10⁵ cells around the
/// circle): `C` a contact, `S` a saddle; arc indices, gap and ψ.
fn scan(
    s: &jamkit_planar::profiled::Profiled<jamkit_fourier::FourierProfile, jamkit_fourier::Angle>,
    p: &Pair<2, jamkit_fourier::Angle>,
) -> String {
    let arcs = s.arcs().unwrap_or(&[]);
    let outline = |u: (f64, f64)| s.unit_outline(u);
    let body = |size: f64, o: &jamkit_fourier::Angle| {
        let (c, si) = o.unit();
        jamkit_planar::arcs::ArcBody {
            arcs,
            outline: &outline,
            size,
            theta: si.atan2(c),
        }
    };
    let sign = |arc: usize| if arcs[arc].convex { "+" } else { "-" };
    jamkit_planar::arcs::scan_stationary(
        &body(p.size_i, &p.o_i),
        &body(p.size_j, &p.o_j),
        &p.r_ij,
        (0.0, std::f64::consts::TAU),
        200_000,
    )
    .iter()
    .map(|q| {
        format!(
            " [{} {}{}|{}{} h {:.4e} ψ {:.6}]",
            if q.contact { "C" } else { "S" },
            q.arc_i,
            sign(q.arc_i),
            q.arc_j,
            sign(q.arc_j),
            q.gap,
            q.psi
        )
    })
    .collect()
}

/// Every contact of a pair: the arcs' (arc indices, convex or concave,
/// gap, `k = g + ρ_A + ρ_B`, support points' body angles) and the core's.
fn describe(
    s: &jamkit_planar::profiled::Profiled<jamkit_fourier::FourierProfile, jamkit_fourier::Angle>,
    p: &Pair<2, jamkit_fourier::Angle>,
) -> String {
    let arcs = s.arcs().unwrap_or(&[]);
    let angle = |o: &jamkit_fourier::Angle| {
        let (c, si) = o.unit();
        si.atan2(c)
    };
    let (ti, tj) = (angle(&p.o_i), angle(&p.o_j));
    let which = |phi: f64| {
        let t = std::f64::consts::TAU;
        arcs.iter()
            .position(|a| {
                let x = a.phi.0 + (phi - a.phi.0).rem_euclid(t);
                x >= a.phi.0 && x < a.phi.1
            })
            .map_or("?".to_string(), |k| {
                format!("{k}{}", if arcs[k].convex { "+" } else { "-" })
            })
    };
    let mut out = format!(
        "sizes {} {} θ {:.9} {:.9} r ({:.12}, {:.12}):",
        p.size_i, p.size_j, ti, tj, p.r_ij[0], p.r_ij[1]
    );
    s.arc_contacts(p, 0.0, None, &mut |ac| {
        let e = ac.exact;
        let psi = e.normal.1.atan2(e.normal.0);
        let phi = |jet: &jamkit_planar::gap2d::SupportJet, beta: f64| beta + jet.d1.atan2(jet.h);
        let (pa, pb) = (
            phi(&e.jet_i, psi - ti),
            phi(&e.jet_j, psi + std::f64::consts::PI - tj),
        );
        let k = e.gap + (e.jet_i.h + e.jet_i.d2) + (e.jet_j.h + e.jet_j.d2);
        out += &format!(
            " [{}|{} h {:.4e}{} k {:.3e} ψ {:.6} φ {:.6} {:.6}]",
            which(pa),
            which(pb),
            e.gap,
            ac.saddle
                .map_or(String::new(), |sd| format!(" saddle {:.4e}", sd.gap)),
            k,
            psi,
            pa.rem_euclid(std::f64::consts::TAU),
            pb.rem_euclid(std::f64::consts::TAU)
        );
    });
    if let Some(e) = s.core_contact(p) {
        out += &format!(" [core h {:.4e}]", e.gap);
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("jam") {
        let a = |i: usize| args[i].parse::<f64>().expect("a number");
        jam_mode(
            a(2) as u32,
            a(3),
            a(4) as usize,
            a(5) as u64,
            a(6) as u64,
            a(7),
        );
        return;
    }
    let Some(path) = args.get(1) else {
        eprintln!("usage: trace_fire PACKING.json [STEPS]");
        std::process::exit(2);
    };
    let file = PackingFile::load_checked(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let steps = args.get(2).map_or(20_000, |s| s.parse().expect("a number"));
    let settings: FireParams = FireParams::default();
    reload(&file, Trace { steps, settings }).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
}
