//! A file that cannot be written is reported once, by the name the user
//! gave, and leaves no temporary file behind; a picture asked for in a
//! directory that does not exist is refused by its path; a packing file
//! whose box or sizes do not give the φ it records is refused by its path;
//! an experiment whose dense eigen-solve cannot fit in the machine's memory
//! is refused before anything runs.

use std::path::Path;

use crate::common;
use common::jamkit;

/// `jamkit export … -o nodir/x.xyz`: the message names `nodir/x.xyz` (not
/// the temporary file beside it) and gives the cause once.
#[test]
fn a_write_into_a_missing_directory_names_the_file_once() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    common::small_quickstart(&run, 1, &[]);
    let target = tmp.path().join("nodir/x.xyz");
    let (code, _, err) = common::export(&run, &target);
    assert_ne!(code, 0);
    assert!(err.contains(target.to_str().unwrap()), "{err}");
    assert!(!err.contains("x.tmp"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// A write that fails at the rename (the target is a directory) removes
/// its temporary file.
#[test]
fn a_failed_write_leaves_no_temporary_file() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("taken");
    std::fs::create_dir(&target).unwrap();
    let err = jamkit_format::write_atomic(&target, b"data").unwrap_err();
    assert!(
        err.to_string().starts_with(target.to_str().unwrap()),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("taken")]);
    assert!(Path::new(&target).is_dir());
}

/// The one packing of a 16-disk quickstart run in `dir`, its path.
fn one_packing(dir: &Path) -> std::path::PathBuf {
    let run = dir.join("run");
    common::small_quickstart(&run, 1, &[]);
    let packings = run.join("packings");
    let mut files: Vec<_> = std::fs::read_dir(&packings)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    assert_eq!(files.len(), 1);
    files.remove(0)
}

/// `jamkit draw … -o nodir/x.png` (and `.svg`), and `jamkit draw-shape`
/// (2D and 3D) the same way: refused before drawing, naming the picture by
/// the user's path and the missing directory, with no plotting library's
/// message; nothing is created. An existing directory is drawn into.
#[test]
fn a_picture_in_a_missing_directory_names_the_picture_and_the_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let packing = one_packing(tmp.path());
    let missing = tmp.path().join("nodir");
    let packing = packing.to_str().unwrap();
    for name in ["x.png", "x.svg"] {
        let target = missing.join(name);
        let target = target.to_str().unwrap();
        for args in [
            vec!["draw", packing, "-o", target],
            vec!["draw-shape", "-o", target],
            vec!["draw-shape", "harmonic", "-o", target],
        ] {
            let (code, _, err) = jamkit(&args);
            assert_ne!(code, 0, "{args:?}");
            let expected = format!(
                "{target}: cannot write the picture: the directory {} does not exist",
                missing.display()
            );
            assert!(err.contains(&expected), "{args:?}: {err}");
            assert!(!err.contains("backend") && !err.contains("Os {"), "{err}");
        }
    }
    assert!(!missing.exists());
    let drawn = tmp.path().join("x.png");
    let (code, _, err) = jamkit(&["draw", packing, "-o", drawn.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(drawn.exists());
}

/// A packing whose box (or sizes) were changed after it was written, here
/// a box edge set to 10⁻³⁰⁰ (positive and finite, so the file itself is
/// well formed) or every size 0.1% larger: `jamkit spectrum` refuses it,
/// naming the file, the φ it records and the φ its box and sizes give.
/// The same file untouched gives its spectrum.
#[test]
fn a_packing_whose_box_does_not_give_its_phi_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let packing = one_packing(tmp.path());
    let (code, _, err) = jamkit(&["spectrum", packing.to_str().unwrap(), "-o", "-"]);
    assert_eq!(code, 0, "{err}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&packing).unwrap()).unwrap();
    let phi = file["phi"].as_f64().unwrap();
    let corrupt = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut copy = file.clone();
        edit(&mut copy);
        let path = tmp.path().join(name);
        std::fs::write(&path, serde_json::to_string(&copy).unwrap()).unwrap();
        path
    };
    let tiny_box = corrupt("tiny_box.json", &|f| {
        f["box"][0] = serde_json::json!(1e-300)
    });
    let larger = corrupt("larger.json", &|f| {
        for r in f["radii"].as_array_mut().unwrap() {
            *r = serde_json::json!(r.as_f64().unwrap() * 1.001);
        }
    });
    // φ grows as R⁰ᵈ (2D here) and as 1/V.
    let box0 = file["box"][0].as_f64().unwrap();
    for (path, expected) in [
        (&tiny_box, phi * box0 / 1e-300),
        (&larger, phi * 1.001f64.powi(2)),
    ] {
        let (code, out, err) = jamkit(&["spectrum", path.to_str().unwrap(), "-o", "-"]);
        assert_ne!(code, 0, "{err}");
        assert!(out.is_empty(), "no eigenvalue is printed: {out}");
        for part in [format!("{}: ", path.display()), format!("phi = {phi}:")] {
            assert!(err.contains(&part), "{part:?} missing from: {err}");
        }
        let recomputed: f64 = err
            .split("give phi = ")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("no recomputed phi in: {err}"));
        assert!(
            (recomputed - expected).abs() <= 1e-9 * expected,
            "{recomputed} against {expected}: {err}"
        );
    }
}

/// `jamkit validate` (and `jamkit run`) of a file whose spectrum needs
/// far more memory than any machine has (10⁷ spheres in 3D: a Hessian of
/// 3·10⁷ rows, 7.2·10¹⁵ bytes a matrix): refused, naming the observable,
/// `particles`, the memory needed and this machine's, and the way out;
/// `run` makes nothing.
#[cfg(target_os = "linux")]
#[test]
fn a_spectrum_that_cannot_fit_in_memory_is_refused_at_validation() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("huge.ron");
    std::fs::write(
        &file,
        r#"(name: "huge", family: "sphere", dim: 3, particles: 10000000,
        observables: [Contacts, Spectrum()])"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    for args in [
        vec!["validate", file.to_str().unwrap()],
        vec![
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let (code, _, err) = jamkit(&args);
        assert_ne!(code, 0, "{args:?}");
        for part in [
            "observables = Spectrum:",
            "particles = 10000000, dim = 3",
            "a Hessian of 30000000 rows",
            "needs at least 14400000 GB",
            "more than this machine's memory",
            "MemTotal",
            "Spectrum has no sparse solver",
        ] {
            assert!(err.contains(part), "{args:?}: {part:?} missing from: {err}");
        }
    }
    assert!(!out.exists(), "nothing is written");
}
