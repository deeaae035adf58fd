//! `jamkit export`: extended XYZ frames hold the packing file's numbers
//! bit for bit (box, centres, sizes, angles), a unit quaternion per
//! oriented body, the ellipses' semi-axes, rigid bodies as their spheres
//! with body ids, and per-body contacts and rattler flags that add up to
//! the packing's own counts.

use std::path::{Path, PathBuf};

use crate::common;
use common::jamkit;

fn run(file: &str, out: &Path, sets: &[&str]) -> PathBuf {
    common::run_cli(file, out, sets);
    let xyz = out.with_extension("xyz");
    let (code, text, err) = common::export(out, &xyz);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("frames in"), "{text}");
    xyz
}

/// The frames of an .xyz file: (comment line, rows of columns).
fn frames(path: &Path) -> Vec<(String, Vec<Vec<String>>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let mut out = Vec::new();
    while let Some(n) = lines.next() {
        let n: usize = n.trim().parse().unwrap();
        let comment = lines.next().unwrap().to_string();
        let rows = (0..n)
            .map(|_| {
                lines
                    .next()
                    .unwrap()
                    .split_whitespace()
                    .map(String::from)
                    .collect()
            })
            .collect();
        out.push((comment, rows));
    }
    out
}

fn packing(dir: &Path, id: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(format!("packings/{id}.json"))).unwrap())
        .unwrap()
}

fn f(s: &str) -> f64 {
    s.parse().unwrap()
}

#[test]
fn disks_round_trip_with_contacts_and_rattlers() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("disks");
    let xyz = run(
        "experiments/quickstart.ron",
        &dir,
        &["particles=32", "samples=2"],
    );
    let frames = frames(&xyz);
    assert_eq!(frames.len(), 2);
    for (k, (comment, rows)) in frames.iter().enumerate() {
        let p = packing(&dir, &format!("sphere_d2_N32_s{}", k + 1));
        let l = p["box"][0].as_f64().unwrap();
        assert!(
            comment.starts_with(&format!("Lattice=\"{l} 0 0 0 {l} 0 0 0 1\"")),
            "{comment}"
        );
        assert!(comment.contains("pbc=\"T T F\""), "{comment}");
        assert_eq!(rows.len(), 32);
        let (mut contacts, mut rattlers) = (0, 0);
        for (b, r) in rows.iter().enumerate() {
            for a in 0..2 {
                assert_eq!(
                    f(&r[1 + a]).to_bits(),
                    p["positions"][b][a].as_f64().unwrap().to_bits()
                );
            }
            assert_eq!(f(&r[4]), p["radii"][b].as_f64().unwrap());
            contacts += r[5].parse::<usize>().unwrap();
            rattlers += r[6].parse::<usize>().unwrap();
        }
        let m = &p["measures"];
        assert_eq!(contacts, 2 * m["n_contacts"].as_u64().unwrap() as usize);
        assert_eq!(rattlers, m["n_rattlers"].as_u64().unwrap() as usize);
    }
}

#[test]
fn near_disks_carry_their_angle_and_a_unit_quaternion() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nd");
    let xyz = run(
        "experiments/minimizers/near_disks.ron",
        &dir,
        &[
            "particles=16",
            "samples=1",
            "params.n=[2]",
            "params.delta=[0.1]",
        ],
    );
    let (comment, rows) = &frames(&xyz)[0];
    assert!(comment.contains("orientation:R:4:angle:R:1"), "{comment}");
    let p = packing(&dir, "fourier_d2_N16_delta0.1_n2_s1");
    for (b, r) in rows.iter().enumerate() {
        let theta = p["orientations"][b][0].as_f64().unwrap();
        assert_eq!(f(&r[9]).to_bits(), theta.to_bits());
        let q: Vec<f64> = r[5..9].iter().map(|x| f(x)).collect();
        assert_eq!((q[0], q[1]), (0.0, 0.0));
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-15);
        let back = 2.0 * q[2].atan2(q[3]);
        let wrapped = (back - theta).rem_euclid(2.0 * std::f64::consts::PI);
        assert!(
            wrapped < 1e-12 || 2.0 * std::f64::consts::PI - wrapped < 1e-12,
            "{back} vs {theta}"
        );
    }
}

#[test]
fn dimers_are_their_spheres_with_body_ids() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("dimers");
    let xyz = run(
        "experiments/sanity/dimers.ron",
        &dir,
        &["particles=16", "samples=1", "dim=2", "params.alpha=[1.5]"],
    );
    let (comment, rows) = &frames(&xyz)[0];
    assert!(comment.contains("body:I:1"), "{comment}");
    let id = comment
        .split_whitespace()
        .find_map(|w| w.strip_prefix("id="))
        .unwrap();
    let p = packing(&dir, id);
    let spheres = p["spheres"].as_array().unwrap();
    assert_eq!(rows.len(), spheres.len());
    let mut seen = vec![0; 16];
    for (r, s) in rows.iter().zip(spheres) {
        assert_eq!(r[0], "S");
        assert_eq!(f(&r[1]).to_bits(), s[0].as_f64().unwrap().to_bits());
        let body: usize = r[10].parse().unwrap();
        assert_eq!(body, s[3].as_f64().unwrap() as usize);
        seen[body] += 1;
    }
    assert!(
        seen.iter().all(|&k| k == 2),
        "two spheres per dimer: {seen:?}"
    );
}

#[test]
fn ellipses_carry_their_semi_axes() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ell");
    let xyz = run(
        "experiments/paper/ellipses.ron",
        &dir,
        &["particles=16", "samples=1", "params.aspect=[1.5]"],
    );
    let (comment, rows) = &frames(&xyz)[0];
    assert!(comment.contains("aspherical_shape:R:3"), "{comment}");
    for r in rows {
        let (r0, a, b) = (f(&r[4]), f(&r[10]), f(&r[11]));
        assert!(
            (a / b - 1.5).abs() < 1e-12 && (a * b - r0 * r0).abs() < 1e-12,
            "{r:?}"
        );
    }
}

/// Ellipsoids carry their semi-axes along the body axes,
/// `R⁰ (ξ_x, ξ_y, ξ_z)` (unit product: `a b c = (R⁰)³`, to 1e-12), in the
/// body frame the unit quaternion `(x, y, z, w)` turns, which is the
/// packing file's `[w, x, y, z]`, bit for bit.
#[test]
fn ellipsoids_carry_their_semi_axes_and_quaternion() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ellipsoid");
    let xyz = run(
        "experiments/examples/ellipsoid.ron",
        &dir,
        &[
            "samples=1",
            "params.alpha=None",
            "params.axes=[1.0, 1.2, 1.4]",
        ],
    );
    let (comment, rows) = &frames(&xyz)[0];
    assert!(
        comment.contains("orientation:R:4:aspherical_shape:R:3"),
        "{comment}"
    );
    let id = comment
        .split("id=")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    let p = packing(&dir, id);
    let orientations = p["orientations"].as_array().unwrap();
    assert_eq!(rows.len(), orientations.len());
    for (r, o) in rows.iter().zip(orientations) {
        let (r0, a, b, c) = (f(&r[4]), f(&r[9]), f(&r[10]), f(&r[11]));
        assert!((a * b * c / r0.powi(3) - 1.0).abs() < 1e-12, "{r:?}");
        assert!(
            (c / a - 1.4).abs() < 1e-12 && (b / a - 1.2).abs() < 1e-12,
            "{r:?}"
        );
        let q: Vec<f64> = (5..9).map(|k| f(&r[k])).collect();
        let w = o.as_array().unwrap();
        for (k, x) in [1, 2, 3, 0].iter().zip(&q) {
            assert_eq!(x.to_bits(), w[*k].as_f64().unwrap().to_bits());
        }
    }
}

/// `output: (extxyz: true)` writes `packings/<id>.xyz` beside each packing,
/// the same frame as `jamkit export` of that packing; a resumed run writes
/// the ones missing and touches nothing else; without the packings'
/// configurations the option is refused, naming both fields.
#[test]
fn the_run_writes_each_packing_as_extxyz_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--set",
            "particles=16",
            "--set",
            "samples=2",
        ];
        a.extend(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |extra: &[&str]| {
        let a = args(extra);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        jamkit(&a)
    };
    let (code, _, err) = run(&["--set", "output.extxyz=true"]);
    assert_eq!(code, 0, "{err}");
    let packings = out.join("packings");
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(&packings)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    jsons.sort();
    assert!(!jsons.is_empty());
    for json in &jsons {
        let xyz = json.with_extension("xyz");
        let exported = dir.path().join("one.xyz");
        let (code, _, err) = common::export(json, &exported);
        assert_eq!(code, 0, "{err}");
        assert_eq!(
            std::fs::read_to_string(&xyz).unwrap(),
            std::fs::read_to_string(&exported).unwrap(),
            "{}",
            xyz.display()
        );
    }
    let gone = jsons[0].with_extension("xyz");
    let kept = jsons[jsons.len() - 1].with_extension("xyz");
    let kept_time = std::fs::metadata(&kept).unwrap().modified().unwrap();
    std::fs::remove_file(&gone).unwrap();
    let (code, text, err) = run(&["--set", "output.extxyz=true"]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("reused"), "{text}");
    assert!(gone.exists(), "the missing frame is written again");
    assert_eq!(
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
        kept_time
    );
    let (code, _, err) = run(&[
        "--set",
        "output.extxyz=true",
        "--set",
        "output.packings=false",
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("output.extxyz") && err.contains("output.packings = true"),
        "{err}"
    );
}
