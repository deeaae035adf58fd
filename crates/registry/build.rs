//! The registry's list of families, read from the manifests: every
//! dependency of this crate whose path lies under `shapes/` is a family
//! crate, and the family types it registers are those its own manifest
//! lists under `[package.metadata.jamkit] families`. The list goes to
//! `$OUT_DIR/families.rs` as one `families![…]` invocation, in the order
//! of the dependencies (the order of `jamkit shapes` and of the families
//! reference page). A family crate that lists no families is a build
//! error naming it.

use std::path::{Path, PathBuf};

fn read(path: &Path) -> toml::Table {
    println!("cargo::rerun-if-changed={}", path.display());
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.parse()
        .unwrap_or_else(|e| panic!("{} is not valid TOML: {e}", path.display()))
}

fn main() {
    let dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let manifest = read(&dir.join("Cargo.toml"));
    let dependencies = manifest
        .get("dependencies")
        .and_then(|d| d.as_table())
        .expect("crates/registry/Cargo.toml has [dependencies]");
    let mut types = Vec::new();
    for (name, dependency) in dependencies {
        let Some(path) = dependency.get("path").and_then(|p| p.as_str()) else {
            continue;
        };
        if !path.contains("shapes/") {
            continue;
        }
        let family_manifest = dir.join(path).join("Cargo.toml");
        let families = read(&family_manifest)
            .get("package")
            .and_then(|p| p.get("metadata"))
            .and_then(|m| m.get("jamkit"))
            .and_then(|j| j.get("families"))
            .and_then(|f| f.as_array())
            .cloned()
            .unwrap_or_default();
        if families.is_empty() {
            panic!(
                "{}: a family crate lists its family types under \
                 [package.metadata.jamkit] families = [\"NameFamily\"]",
                family_manifest.display()
            );
        }
        let krate = name.replace('-', "_");
        for family in families {
            let family = family.as_str().unwrap_or_else(|| {
                panic!("{}: families are type names", family_manifest.display())
            });
            types.push(format!("    {krate}::{family},\n"));
        }
    }
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it")).join("families.rs");
    let text = format!("families![\n{}];\n", types.concat());
    std::fs::write(&out, text).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
}
