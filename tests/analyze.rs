//! `jamkit analyze`: a sphere packing written by another code, as plain
//! `x y (z) r` text or as extended XYZ, measured as our own. The packing
//! read back is the one jamkit made (same bodies to the bit), so every
//! count must be the run's exactly; bad files are refused naming the line
//! and what was expected.

use crate::common;
use jamkit_experiment::analyze::{ReadOptions, analyze, parse_observables, read};
use jamkit_experiment::{Experiment, extxyz};
use jamkit_format::PackingFile;
use std::fmt::Write as _;

/// A jammed sphere packing of `dim` dimensions from a run, with contacts
/// and the spectrum measured.
fn jammed(dir: &std::path::Path, dim: usize) -> PackingFile {
    let text = format!(
        r#"(name: "s", family: "sphere", dim: {dim}, particles: 48, samples: 1, seed: 4,
        observables: [Contacts, Pressure, Spectrum()])"#
    );
    let e = Experiment::from_ron(&text, "inline").unwrap();
    let report = common::run_ok(&e, dir, 1);
    report.packings[0].clone()
}

/// The same file as another code would write it: `# box …`, then one
/// `x y (z) r` line per body (shortest round-trip form, as `%r` in Python).
fn plain_text(p: &PackingFile) -> String {
    let mut s = String::from("# written by another code\n# box");
    for l in &p.box_edges {
        let _ = write!(s, " {l:?}");
    }
    s.push('\n');
    for (x, r) in p.positions.iter().zip(&p.radii) {
        let cols: Vec<String> = x.iter().chain([r]).map(|v| format!("{v:?}")).collect();
        s += &(cols.join(" ") + "\n");
    }
    s
}

#[test]
fn plain_text_and_extended_xyz_give_the_runs_own_measures() {
    for dim in [2, 3] {
        let dir = tempfile::tempdir().unwrap();
        let ours = jammed(dir.path(), dim);
        let txt = dir.path().join("other.txt");
        std::fs::write(&txt, plain_text(&ours)).unwrap();
        let xyz = dir.path().join("other.xyz");
        std::fs::write(&xyz, extxyz::frame(&ours).unwrap()).unwrap();
        let observables = parse_observables("[Contacts, Pressure, Spectrum()]").unwrap();
        for path in [&txt, &xyz] {
            let file = read(path, &ReadOptions::default()).unwrap();
            assert_eq!((file.dim, file.particles), (dim, 48), "{}", path.display());
            assert_eq!(file.positions, ours.positions);
            assert_eq!(file.radii, ours.radii);
            let (got, force, _) = analyze(file, &observables).unwrap();
            let (m, want) = (&got.measures, &ours.measures);
            assert_eq!(
                (m.n_contacts, m.n_rattlers, m.iso_margin),
                (want.n_contacts, want.n_rattlers, want.iso_margin),
                "{dim}D {}",
                path.display()
            );
            assert_eq!(m.z_j, want.z_j);
            approx::assert_relative_eq!(got.phi, ours.phi, max_relative = 1e-12);
            approx::assert_relative_eq!(
                got.energy_per_particle,
                ours.energy_per_particle,
                max_relative = 1e-9
            );
            // A jammed packing: forces at the minimiser's tolerance.
            assert!(force < 1e-10, "largest force {force:e}");
            let (s, w) = (
                m.spectrum.as_ref().unwrap(),
                want.spectrum.as_ref().unwrap(),
            );
            assert_eq!(s.zero_modes, w.zero_modes);
            approx::assert_relative_eq!(s.lambda_max, w.lambda_max, max_relative = 1e-9);
        }
    }
}

#[test]
fn bad_files_are_refused_naming_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let err = |name: &str, text: &str, options: ReadOptions| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        read(&path, &options).unwrap_err().to_string()
    };
    let e = err("a.txt", "# box 4 4\n1 1 0.5\n2 2\n", ReadOptions::default());
    assert!(e.contains("line 3") && e.contains("expected 3"), "{e}");
    let e = err("b.txt", "1 1 0.5\n2 2 0.5\n", ReadOptions::default());
    assert!(e.contains("--box"), "{e}");
    let e = err("c.txt", "# box 4 4\n1 1 nan\n", ReadOptions::default());
    assert!(e.contains("line 2") && e.contains("finite"), "{e}");
    let e = err("d.txt", "# box 4 4\n1 1 -0.5\n", ReadOptions::default());
    assert!(e.contains("radii[0]") && e.contains("positive"), "{e}");
    let e = err(
        "e.xyz",
        "1\nLattice=\"4 0 0 0 4 0 0 0 4\" Properties=species:S:1:pos:R:3\nA 1 1 1\n",
        ReadOptions::default(),
    );
    assert!(e.contains("radius"), "{e}");
    let e = err(
        "f.xyz",
        "2\nLattice=\"4 0 0 0 4 0 0 0 4\" Properties=species:S:1:pos:R:3:radius:R:1\nA 1 1 1 0.5\n",
        ReadOptions::default(),
    );
    assert!(e.contains("line 4") && e.contains("1 of 2"), "{e}");
    let e = err(
        "g.xyz",
        "1\nProperties=pos:R:3:radius:R:1\n1 1 1 0.5\n",
        ReadOptions::default(),
    );
    assert!(e.contains("Lattice"), "{e}");
    assert!(
        parse_observables("[Contact]")
            .unwrap_err()
            .to_string()
            .contains("--observables")
    );
}
