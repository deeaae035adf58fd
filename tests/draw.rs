//! `jamkit draw` and `jamkit draw-shape` through the binary: pictures of
//! freshly jammed packings (disks and near-disks; 3D spheres, dimers and
//! `harmonic` near-spheres) in SVG and PNG, shape panels (3D bodies too),
//! and clear errors (never panics) for what cannot be drawn.

use std::path::{Path, PathBuf};

use crate::common;
use common::jamkit;

/// Jam one packing of 16 bodies into `dir` and return its file.
fn jam(dir: &Path, extra: &[&str]) -> PathBuf {
    let mut args = vec![
        "run",
        "experiments/quickstart.ron",
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "particles=16",
        "--set",
        "samples=1",
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join("packings"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files.pop().unwrap()
}

/// Draw `packing` to SVG and PNG; check both files, and return the SVG.
fn draw_both(packing: &Path, dir: &Path) -> String {
    let svg = dir.join("packing.svg");
    let png = dir.join("packing.png");
    for (out, size) in [(&svg, "400"), (&png, "300")] {
        let (code, stdout, err) = jamkit(&[
            "draw",
            packing.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--size",
            size,
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(stdout.contains("16 "), "{stdout}");
        assert!(
            std::fs::metadata(out).unwrap().len() > 0,
            "{}",
            out.display()
        );
    }
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("</svg>"));
    // At least one filled polygon per body (more with periodic images).
    assert!(text.matches("<polygon").count() >= 16, "{text}");
    text
}

#[test]
fn draw_binary_disks_to_svg_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let packing = jam(&dir.path().join("run"), &[]);
    draw_both(&packing, dir.path());
}

#[test]
fn draw_near_disks_to_svg_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let packing = jam(
        &dir.path().join("run"),
        &[
            "--set",
            "family=fourier",
            "--set",
            r#"params={"n": 3, "delta": 0.2}"#,
        ],
    );
    draw_both(&packing, dir.path());
}

#[test]
fn draw_the_tutorial_family() {
    // `lobed` (docs/tutorials/new-shape-rust.md) draws through the registry
    // alone.
    let dir = tempfile::tempdir().unwrap();
    let packing = jam(
        &dir.path().join("run"),
        &[
            "--set",
            "family=lobed",
            "--set",
            r#"params={"delta": 0.2, "kappa": 2.0}"#,
        ],
    );
    draw_both(&packing, dir.path());
}

#[test]
fn draw_refuses_what_it_cannot_draw() {
    let dir = tempfile::tempdir().unwrap();
    let packing = jam(&dir.path().join("run"), &[]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&packing).unwrap()).unwrap();
    let out = dir.path().join("x.svg");
    let out = out.to_str().unwrap();
    for (key, value, message) in [
        ("dim", serde_json::json!(4), "dim = 4: only 2D and 3D"),
        // A 2D record labelled 3D: its box has two edges.
        ("dim", serde_json::json!(3), "box = ["),
        ("family", serde_json::json!("dimer"), "family `dimer`"),
    ] {
        let mut bad = json.clone();
        bad[key] = value;
        let path = dir.path().join(format!("bad_{key}.json"));
        std::fs::write(&path, bad.to_string()).unwrap();
        let (code, _, err) = jamkit(&["draw", path.to_str().unwrap(), "-o", out]);
        assert_eq!(code, 1, "{err}");
        assert!(
            err.starts_with("error: ") && err.contains(message) && !err.contains("panicked"),
            "{err}"
        );
    }
    let (code, _, err) = jamkit(&["draw", packing.to_str().unwrap(), "-o", out, "--cut"]);
    assert_eq!(code, 1);
    assert!(err.contains("--cut: only for 3D"), "{err}");
    let (code, _, err) = jamkit(&["draw", packing.to_str().unwrap(), "-o", "x.jpg"]);
    assert_eq!(code, 1);
    assert!(err.contains(".svg or .png"), "{err}");
    let (code, _, err) = jamkit(&["draw", "no/such/packing.json", "-o", out]);
    assert_eq!(code, 1);
    assert!(err.contains("no/such/packing.json"), "{err}");
}

#[test]
fn draw_shape_writes_one_panel_per_n() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("shapes.svg");
    let (code, stdout, err) = jamkit(&[
        "draw-shape",
        "fourier",
        "--n",
        "2,3,4,5",
        "--delta",
        "0,0.1,0.3",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("4 panel(s)"), "{stdout}");
    let text = std::fs::read_to_string(&svg).unwrap();
    for label in ["n = 2", "n = 5", "Δ = 0", "Δ = 0.1", "Δ = 0.3", "x / R⁰"] {
        assert!(text.contains(label), "{label} missing");
    }
    let (code, _, err) = jamkit(&[
        "draw-shape",
        "fourier_sum",
        "--modes",
        "[(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)]",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    // PNG carries the same text, drawn with the bundled font: a picture with
    // titles and a legend is far larger than an empty canvas.
    let png = dir.path().join("shapes.png");
    let (code, _, err) = jamkit(&["draw-shape", "-o", png.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..4], b"\x89PNG");
    assert!(bytes.len() > 10_000, "{} bytes", bytes.len());
    // Any family with an outline plots through the registry, the
    // tutorial's `lobed` included; bodies made of spheres have no R(θ).
    let (code, _, err) = jamkit(&[
        "draw-shape",
        "lobed",
        "--curve",
        "(kappa: 1.0)",
        "--curve",
        "(kappa: 4.0)",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("κ = 4"), "legend missing");
    let (code, _, err) = jamkit(&["draw-shape", "nmer", "-o", svg.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("nmer") && err.contains("spheres"), "{err}");
    let (code, _, err) = jamkit(&["draw-shape", "dimer", "-o", svg.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("must be one of"), "{err}");
}

/// Every 3D family jams (64 bodies: fewer do not fit the box twice the
/// interaction range) and draws: PNG (a real PNG, far larger
/// than an empty canvas of its size: a white 300 × 325 PNG compresses to
/// under 2 kB) and SVG (the ray-cast embedded, the key as text), the whole
/// view and the `--cut` view.
#[test]
fn draw_3d_packings_of_every_3d_family() {
    for (family, params) in [
        ("sphere", "{}"),
        ("nmer", r#"{"alpha": 1.5}"#),
        ("harmonic", r#"{"l": 2, "delta": 0.2}"#),
        ("ellipsoid", r#"{"alpha": 1.5}"#),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let family_set = format!("family={family}");
        let params_set = format!("params={params}");
        let packing = jam(
            &dir.path().join("run"),
            &[
                "--set",
                "dim=3",
                "--set",
                "particles=64",
                "--set",
                &family_set,
                "--set",
                &params_set,
            ],
        );
        let png = dir.path().join("p.png");
        let svg = dir.path().join("p.svg");
        for (out, extra) in [(&png, None), (&svg, None), (&png, Some("--cut"))] {
            let mut args = vec![
                "draw",
                packing.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--size",
                "300",
            ];
            args.extend(extra);
            let (code, stdout, err) = jamkit(&args);
            assert_eq!(code, 0, "{family}: {err}");
            assert!(
                stdout.contains(&format!("64 {family} bodies in 3D")),
                "{stdout}"
            );
        }
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..4], b"\x89PNG", "{family}");
        assert!(bytes.len() > 10_000, "{family}: {} bytes", bytes.len());
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(
            text.contains("data:image/png;base64,iVBORw0KGgo"),
            "{family}"
        );
        assert!(
            text.contains("R⁰ = 0.5") && text.contains("R⁰ = 0.7"),
            "{family}: key"
        );
    }
}

/// `draw-shape` of a 3D family: shaded bodies, one per Δ, in PNG and SVG;
/// 3D dimers with `--dim 3`; a dimension the family lacks is refused.
#[test]
fn draw_shape_draws_3d_bodies() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("bodies.svg");
    let (code, stdout, err) = jamkit(&[
        "draw-shape",
        "harmonic",
        "--panel",
        "(l: 2)",
        "--panel",
        "(l: 3, m: 2)",
        "--delta",
        "0,0.1,0.3",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("2 row(s) of 3D bodies"), "{stdout}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(text.matches("<image").count(), 6);
    assert!(text.contains("l = 3, m = 2; Δ = 0.3"), "caption missing");
    let png = dir.path().join("bodies.png");
    let (code, _, err) = jamkit(&["draw-shape", "harmonic", "-o", png.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
    // Ellipsoids through their `Surface`: oblate, the ball (α = 1, drawn as
    // a ball) and triaxial (whose `axes` replace the example's `alpha`).
    let (code, stdout, err) = jamkit(&[
        "draw-shape",
        "ellipsoid",
        "--curve",
        "(alpha: 0.5)",
        "--curve",
        "(alpha: 1.0)",
        "--curve",
        "(axes: [1.0, 1.4, 2.0])",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("1 row(s) of 3D bodies"), "{stdout}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(text.matches("<image").count(), 3);
    let (code, _, err) = jamkit(&[
        "draw-shape",
        "nmer",
        "--dim",
        "3",
        "--curve",
        "(alpha: 1.5)",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = jamkit(&[
        "draw-shape",
        "fourier",
        "--dim",
        "3",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("--dim = 3") && !err.contains("panicked"),
        "{err}"
    );
    let (code, _, err) = jamkit(&[
        "draw-shape",
        "harmonic",
        "--delta",
        "5",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("params.delta") && !err.contains("panicked"),
        "{err}"
    );
}
