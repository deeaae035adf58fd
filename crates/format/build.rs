//! The git commit this crate is built from, for the provenance every
//! packing file and `experiment.ron` records (`JAMKIT_GIT_COMMIT`, empty
//! outside a git checkout, e.g. when built from a source archive). A
//! `JAMKIT_GIT_COMMIT` in the build's environment wins: a packager building
//! from an archive can name the commit it came from.

use std::path::Path;
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    (out.status.success() && !text.trim().is_empty()).then(|| text.trim().to_string())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=JAMKIT_GIT_COMMIT");
    if let Ok(commit) = std::env::var("JAMKIT_GIT_COMMIT") {
        println!("cargo:rustc-env=JAMKIT_GIT_COMMIT={commit}");
        return;
    }
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_default();
    println!("cargo:rustc-env=JAMKIT_GIT_COMMIT={commit}");
    // Rebuild when HEAD moves: a new commit on the branch (its ref, loose
    // or packed) or a checkout of another branch. Only paths that exist:
    // cargo reruns a script whose watched path is missing on every build.
    let head = git(&["symbolic-ref", "-q", "HEAD"]);
    let watched = ["HEAD", "packed-refs"]
        .into_iter()
        .map(String::from)
        .chain(head);
    for path in watched {
        if let Some(p) = git(&["rev-parse", "--git-path", &path])
            && Path::new(env!("CARGO_MANIFEST_DIR")).join(&p).exists()
        {
            println!("cargo:rerun-if-changed={p}");
        }
    }
}
