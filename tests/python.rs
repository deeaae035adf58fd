//! The Python module (`crates/python/`, docs/how-to/python.md):
//! `tests/python/run.sh` builds its abi3 wheel with maturin, installs the
//! wheel into a venv under `target/` (numpy, pandas, pytest, ase,
//! matplotlib, nbclient and ipykernel from PyPI) with cargo off PATH, runs
//! the Python of docs/how-to/python.md, and runs `crates/python/tests`
//! with pytest, which checks the module's packings, contacts, spectra,
//! pictures and XYZ files against this build's `jamkit` command line, bit
//! for bit, and executes the notebooks of docs/notebooks.
//!
//! Building the extension takes about three minutes of CPU on a clean
//! checkout, so the test runs under CI (`CI` set, where a failure to set
//! up is a test failure) or when `JAMKIT_TEST_PYTHON` is set; otherwise it
//! says that it did not run and passes.

use std::path::Path;
use std::process::Command;

#[test]
fn the_python_module_passes_its_pytest_suite() {
    let ci = std::env::var_os("CI").is_some_and(|v| !v.is_empty());
    let asked = std::env::var_os("JAMKIT_TEST_PYTHON").is_some_and(|v| !v.is_empty());
    if !ci && !asked {
        eprintln!(
            "python test not run: set CI or JAMKIT_TEST_PYTHON to build and test crates/python/"
        );
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("bash")
        .arg(root.join("tests/python/run.sh"))
        .arg(env!("CARGO_BIN_EXE_jamkit"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "python tests failed:\n{text}\n{err}");
    // pytest's summary line, "N passed in …": all of crates/python/tests ran
    // (at least the 21 tests of test_jamkit.py and test_notebooks.py), none
    // skipped or failed.
    let summary = text.lines().last().unwrap_or_default();
    let passed: usize = summary
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(
        passed >= 21 && summary.contains(" passed") && !summary.contains("skipped"),
        "{text}"
    );
}
