//! The field's tools and jamkit, both ways: `tests/interop/run.sh` installs
//! ASE and gsd from PyPI into a venv under `target/` and runs
//! `tests/interop/check.py`, which reads with `ase.io.read` the extended
//! XYZ that `jamkit export` writes for a packing of every registered family
//! in D = 2 and 3, from the family's example (N, box, positions to 1e-12,
//! radii exactly), reads with `gsd.hoomd` the GSD file it writes for each
//! (N, box, positions and orientations to float32 rounding, each type
//! shape of its family's kind: Sphere, Ellipsoid, SphereUnion, Polygon,
//! Mesh), and runs
//! `jamkit analyze` on sphere packings written by a small script as plain
//! text (the run's contacts and rattlers must come back) and by
//! `ase.io.write` (ASE's bodies and box must come back as ASE reads them;
//! ASE writes 8 decimals, too few to keep the contacts of a packing at
//! φ_J, whose overlaps are ~1e-8: docs/how-to/ovito-ase.md, "Measure a
//! sphere packing made by another code").
//!
//! It needs python3 with venv and access to PyPI. Under CI (`CI` set) a
//! failure to set that up is a test failure; elsewhere the test says it
//! did not run and passes.

use crate::common;
use jamkit_experiment::Experiment;
use jamkit_registry::{EXAMPLES, FAMILIES, params_from_ron, supports_dim};
use std::path::Path;
use std::process::Command;

#[test]
fn ase_and_gsd_read_our_exports_and_we_analyze_ase_files() {
    let ci = std::env::var_os("CI").is_some_and(|v| !v.is_empty());
    let have_python = Command::new("python3")
        .args(["-c", "import venv"])
        .status()
        .is_ok_and(|s| s.success());
    if !have_python {
        assert!(
            !ci,
            "CI must run the ASE interop test: python3 with venv is missing"
        );
        eprintln!("interop test not run: python3 with venv is missing");
        return;
    }
    let work = tempfile::tempdir().unwrap();
    // Every registered family, from its own example, in each of D = 2, 3
    // it supports (extended XYZ has three columns of positions).
    let mut runs = 0;
    for (info, example) in FAMILIES.iter().zip(EXAMPLES) {
        for dim in [2, 3] {
            if !supports_dim(info, dim) {
                continue;
            }
            let params = params_from_ron(example).unwrap();
            let params = ron::to_string(&params).unwrap();
            let name = format!("{}{dim}", info.name);
            // 24 bodies leave too small a box for 3D dimers.
            let particles = if dim == 3 { 64 } else { 24 };
            let text = format!(
                r#"(name: "{name}", family: "{}", dim: {dim}, params: {params}, particles: {particles}, samples: 1, seed: 2, observables: [Contacts])"#,
                info.name
            );
            let e = Experiment::from_ron(&text, "inline").unwrap();
            common::run_ok(&e, &work.path().join("runs").join(&name), 1);
            runs += 1;
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("bash")
        .arg(root.join("tests/interop/run.sh"))
        .arg(env!("CARGO_BIN_EXE_jamkit"))
        .arg(work.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && !ci && err.contains("pip") {
        eprintln!("interop test not run: could not install ASE and gsd\n{err}");
        return;
    }
    assert!(out.status.success(), "{text}\n{err}");
    assert!(
        text.contains(&format!("ase read {runs} packings")),
        "{text}\n{err}"
    );
    assert!(
        text.contains(&format!("gsd read {runs} packings")),
        "{text}\n{err}"
    );
    assert!(
        text.contains("analyze of files from other code: ok"),
        "{text}\n{err}"
    );
}
