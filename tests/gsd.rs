//! `jamkit export … -o FILE.gsd`: a GSD file of HOOMD's schema, read back
//! by the file layer's own reader (`jamkit_format::gsd::read`, which checks
//! the header, the index order and that every chunk lies in the file).
//! Numbers are float32, so they are compared to the packing file's to
//! float32 rounding: `|x_gsd − x| ≤ 2⁻²³ · L` for coordinates in a box of
//! edge `L` (half an ulp of the largest coordinate, `L/2`, plus the
//! rounding of the shift by `L/2`), `2⁻²³` relative for sizes and
//! quaternion components (of magnitude ≤ 1).

use jamkit_format::gsd::{self, File};
use std::path::{Path, PathBuf};

use crate::common;

const F32: f64 = f32::EPSILON as f64;

fn run_and_export(file: &str, out: &Path, sets: &[&str]) -> File {
    common::run_cli(file, out, sets);
    let target: PathBuf = out.with_extension("gsd");
    let (code, text, err) = common::export(out, &target);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("frames in"), "{text}");
    gsd::read(&std::fs::read(&target).unwrap()).unwrap()
}

fn packings(dir: &Path) -> Vec<serde_json::Value> {
    common::packing_paths(dir)
        .iter()
        .map(|p| serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap())
        .collect()
}

fn floats(f: &File, frame: usize, name: &str) -> Vec<f64> {
    f.chunk(frame, name)
        .unwrap_or_else(|| panic!("{name}"))
        .floats()
        .unwrap()
}

fn unsigned(f: &File, frame: usize, name: &str) -> Vec<u64> {
    f.chunk(frame, name).unwrap().unsigned().unwrap()
}

fn shapes(f: &File, frame: usize) -> Vec<serde_json::Value> {
    f.chunk(frame, "particles/type_shapes")
        .unwrap()
        .rows_as_strings()
        .unwrap()
        .iter()
        .map(|s| serde_json::from_str(s).unwrap())
        .collect()
}

fn vec_of(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// `d` brought to the nearest periodic image in a box of edge `l`.
fn image(d: f64, l: f64) -> f64 {
    d - l * (d / l).round()
}

/// `q v q*` for `q = (w, x, y, z)`.
fn rotate(q: &[f64], v: [f64; 3]) -> [f64; 3] {
    let (w, u) = (q[0], [q[1], q[2], q[3]]);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    std::array::from_fn(|k| v[k] + w * t[k] + ut[k])
}

/// Frame `k` against packing `p`: header, box, count, centres (in
/// `[−L/2, L/2)`, the packing's modulo `L`), sizes, types by size.
fn check_frame(f: &File, k: usize, p: &serde_json::Value) {
    assert_eq!(f.schema, "hoomd");
    assert_eq!(f.schema_version, (1, 4));
    assert!(f.application.starts_with("jamkit"), "{}", f.application);
    let dim = p["dim"].as_u64().unwrap() as usize;
    let n = p["particles"].as_u64().unwrap() as usize;
    let l = vec_of(&p["box"]);
    assert_eq!(unsigned(f, k, "configuration/step"), [k as u64]);
    assert_eq!(unsigned(f, k, "configuration/dimensions"), [dim as u64]);
    assert_eq!(unsigned(f, k, "particles/N"), [n as u64]);
    let b = floats(f, k, "configuration/box");
    for a in 0..3 {
        let want = if a < dim { l[a] as f32 as f64 } else { 0.0 };
        assert_eq!(b[a], want);
        assert_eq!(b[3 + a], 0.0);
    }
    let pos = floats(f, k, "particles/position");
    assert_eq!(pos.len(), 3 * n);
    let radii = vec_of(&p["radii"]);
    for i in 0..n {
        let r = vec_of(&p["positions"][i]);
        for a in 0..3 {
            let x = pos[3 * i + a];
            if a >= dim {
                assert_eq!(x, 0.0);
                continue;
            }
            let half = b[a] / 2.0;
            assert!(x >= -half && x < half, "{x} outside ±{half}");
            let off = image(x + l[a] / 2.0 - r[a], l[a]).abs();
            assert!(off <= F32 * l[a], "body {i}: {x} against {}", r[a]);
        }
    }
    let diameter = floats(f, k, "particles/diameter");
    let typeid = unsigned(f, k, "particles/typeid");
    let types = f
        .chunk(k, "particles/types")
        .unwrap()
        .rows_as_strings()
        .unwrap();
    for i in 0..n {
        assert_eq!(diameter[i], (2.0 * radii[i]) as f32 as f64);
        assert_eq!(types[typeid[i] as usize], format!("R{}", radii[i]));
    }
    assert_eq!(floats(f, k, "log/jamkit/phi"), [p["phi"].as_f64().unwrap()]);
}

/// A run directory of two disk packings: two frames, each the packing's
/// numbers; one `Sphere` type per size, of diameter `2R⁰`.
#[test]
fn disks_are_spheres_one_frame_per_packing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("disks");
    let f = run_and_export(
        "experiments/quickstart.ron",
        &dir,
        &["particles=32", "samples=2"],
    );
    let ps = packings(&dir);
    assert_eq!((f.frames.len(), ps.len()), (2, 2));
    for (k, p) in ps.iter().enumerate() {
        check_frame(&f, k, p);
        let shapes = shapes(&f, k);
        let types = f
            .chunk(k, "particles/types")
            .unwrap()
            .rows_as_strings()
            .unwrap();
        assert_eq!(types, ["R0.5", "R0.7"], "the binary mixture's two sizes");
        for (s, r) in shapes.iter().zip([0.5, 0.7]) {
            assert_eq!(s["type"], "Sphere");
            assert_eq!(s["diameter"].as_f64().unwrap(), 2.0 * r);
        }
        let q = floats(&f, k, "particles/orientation");
        assert!(q.chunks(4).all(|q| q == [1.0, 0.0, 0.0, 0.0]));
    }
}

/// Dimers: a `SphereUnion` per size; each body's spheres, its type's
/// centres turned by its orientation about its position, are the packing
/// file's `spheres` rows (modulo the box, to float32 rounding).
#[test]
fn dimers_are_sphere_unions_that_land_on_their_spheres() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("dimers");
    let f = run_and_export(
        "experiments/sanity/dimers.ron",
        &dir,
        &["particles=16", "samples=1", "dim=2", "params.alpha=[1.5]"],
    );
    let p = &packings(&dir)[0];
    check_frame(&f, 0, p);
    let shapes = shapes(&f, 0);
    assert!(shapes.iter().all(|s| s["type"] == "SphereUnion"));
    let pos = floats(&f, 0, "particles/position");
    let q = floats(&f, 0, "particles/orientation");
    let typeid = unsigned(&f, 0, "particles/typeid");
    let l = vec_of(&p["box"]);
    let mut next = vec![0usize; 16];
    for s in p["spheres"].as_array().unwrap() {
        let s = vec_of(s);
        let body = s[3] as usize;
        let shape = &shapes[typeid[body] as usize];
        let c = vec_of(&shape["centers"][next[body]]);
        let d = shape["diameters"][next[body]].as_f64().unwrap();
        next[body] += 1;
        assert_eq!(d, 2.0 * s[2]);
        let turned = rotate(&q[4 * body..4 * body + 4], [c[0], c[1], c[2]]);
        for a in 0..2 {
            let x = pos[3 * body + a] + turned[a] + l[a] / 2.0;
            assert!(
                image(x - s[a], l[a]).abs() <= 4.0 * F32 * l[a],
                "body {body}: {x} against {}",
                s[a]
            );
        }
        assert!(turned[2].abs() < 1e-6);
    }
    assert!(next.iter().all(|&k| k == 2), "{next:?}");
}

/// Near-disks: a `Polygon` per size, counter-clockwise; turned by the
/// body's orientation, its vertex in lab direction `φ` lies at the
/// family's radius `R⁰ ρ(θ − φ)` (the outline `jamkit draw` draws), to
/// float32 rounding of the angle (`2⁻²³` relative, well under 1e-5).
#[test]
fn near_disks_are_polygons_on_their_outline() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nd");
    let f = run_and_export(
        "experiments/minimizers/near_disks.ron",
        &dir,
        &[
            "particles=16",
            "samples=1",
            "params.n=[3]",
            "params.delta=[0.2]",
        ],
    );
    let p = &packings(&dir)[0];
    check_frame(&f, 0, p);
    let outline = jamkit_draw::Outline::from_family("fourier", &p["params"]).unwrap();
    let shapes = shapes(&f, 0);
    let q = floats(&f, 0, "particles/orientation");
    let typeid = unsigned(&f, 0, "particles/typeid");
    let radii = vec_of(&p["radii"]);
    for i in 0..16 {
        let shape = &shapes[typeid[i] as usize];
        assert_eq!(shape["type"], "Polygon");
        let vertices: Vec<Vec<f64>> = shape["vertices"]
            .as_array()
            .unwrap()
            .iter()
            .map(vec_of)
            .collect();
        assert_eq!(vertices.len(), jamkit_experiment::gsd::POLYGON_VERTICES);
        let area: f64 = (0..vertices.len())
            .map(|k| {
                let (a, b) = (&vertices[k], &vertices[(k + 1) % vertices.len()]);
                0.5 * (a[0] * b[1] - a[1] * b[0])
            })
            .sum();
        assert!(area > 0.0, "counter-clockwise");
        let qi = &q[4 * i..4 * i + 4];
        assert_eq!((qi[1], qi[2]), (0.0, 0.0));
        let theta = p["orientations"][i][0].as_f64().unwrap();
        let back = 2.0 * qi[3].atan2(qi[0]);
        assert!(image(back - theta, 2.0 * std::f64::consts::PI).abs() < 1e-6);
        for v in vertices.iter().step_by(7) {
            let w = rotate(qi, [v[0], v[1], 0.0]);
            let phi = w[1].atan2(w[0]);
            let want = outline.radius(radii[i], theta, phi);
            let got = w[0].hypot(w[1]);
            assert!((got - want).abs() < 1e-5 * radii[i], "{got} against {want}");
        }
    }
}

/// Ellipsoids: an `Ellipsoid` per size, `a b c = (R⁰)³`; the orientation
/// is the packing file's quaternion (up to sign) to float32 rounding.
#[test]
fn ellipsoids_are_ellipsoids_with_their_quaternion() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ellipsoid");
    let f = run_and_export(
        "experiments/examples/ellipsoid.ron",
        &dir,
        &[
            "samples=1",
            "params.alpha=None",
            "params.axes=[1.0, 1.2, 1.4]",
        ],
    );
    let p = &packings(&dir)[0];
    check_frame(&f, 0, p);
    let shapes = shapes(&f, 0);
    let typeid = unsigned(&f, 0, "particles/typeid");
    let q = floats(&f, 0, "particles/orientation");
    let radii = vec_of(&p["radii"]);
    for i in 0..radii.len() {
        let s = &shapes[typeid[i] as usize];
        assert_eq!(s["type"], "Ellipsoid");
        let abc = ["a", "b", "c"].map(|k| s[k].as_f64().unwrap());
        assert!((abc[0] * abc[1] * abc[2] - radii[i].powi(3)).abs() < 1e-12);
        let want = vec_of(&p["orientations"][i]);
        let dot: f64 = (0..4).map(|k| q[4 * i + k] * want[k]).sum();
        for k in 0..4 {
            assert!((q[4 * i + k] - dot.signum() * want[k]).abs() <= 2.0 * F32);
        }
    }
}

/// Sizes drawn from `Uniform`: every body its own size, so its own type,
/// named by its size, each a `Sphere` of its diameter.
#[test]
fn uniform_sizes_give_one_type_per_body() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("uniform");
    let f = run_and_export(
        "experiments/quickstart.ron",
        &dir,
        &[
            "particles=16",
            "samples=1",
            "sizes=Uniform(min: 0.5, max: 0.7)",
        ],
    );
    let p = &packings(&dir)[0];
    check_frame(&f, 0, p);
    let radii = vec_of(&p["radii"]);
    let shapes = shapes(&f, 0);
    assert_eq!(shapes.len(), 16);
    let typeid = unsigned(&f, 0, "particles/typeid");
    for i in 0..16 {
        let s = &shapes[typeid[i] as usize];
        assert_eq!(s["type"], "Sphere");
        assert_eq!(s["diameter"].as_f64().unwrap(), 2.0 * radii[i]);
    }
}

/// A 4D packing is refused, naming its file, its dimension and what GSD
/// holds, and nothing is written.
#[test]
fn a_4d_packing_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("d4");
    common::small_quickstart(&run, 1, &["--set", "dim=4", "--set", "particles=64"]);
    let target = tmp.path().join("d4.gsd");
    let (code, _, err) = common::export(&run, &target);
    assert_ne!(code, 0);
    assert!(
        err.contains("sphere_d4_N64_s1.json") && err.contains("dim = 4: GSD holds 2D and 3D"),
        "{err}"
    );
    assert!(!target.exists());
}

/// An output path that cannot be written: the message names it, and no
/// file is left behind.
#[test]
fn an_unwritable_path_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    common::small_quickstart(&run, 1, &[]);
    let target = tmp.path().join("nodir/x.gsd");
    let (code, _, err) = common::export(&run, &target);
    assert_ne!(code, 0);
    assert!(err.contains(target.to_str().unwrap()), "{err}");
    assert!(!tmp.path().join("nodir").exists());
}
