//! The reference pages of the manual (`docs/reference/`) hold everything
//! the code has: every field and variant of the experiment file, every
//! command and flag of the command line, every column of the tables a run
//! writes, every registered family. Each list is read from the code, so a
//! new field, command, column or family that the reference does not name
//! fails here.

use jamkit_experiment::Experiment;
use jamkit_format::PackingFile;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::common;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn page(name: &str) -> String {
    let path = Path::new(ROOT).join("docs/reference").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `jamkit ARGS`, which must succeed: its standard output.
fn jamkit(args: &[&str]) -> String {
    let (code, out, err) = common::jamkit(args);
    assert_eq!(code, 0, "jamkit {args:?}: {err}");
    out
}

/// The names of `names` that `text` does not write as inline code.
fn missing<'a>(text: &str, names: impl IntoIterator<Item = &'a String>) -> Vec<String> {
    names
        .into_iter()
        .filter(|n| !text.contains(&format!("`{n}`")))
        .cloned()
        .collect()
}

#[test]
fn the_families_page_is_what_the_registry_generates() {
    let committed = page("families.md");
    let generated = jamkit_registry::reference_markdown();
    assert!(
        committed.trim_end() == generated.trim_end(),
        "docs/reference/families.md is not the registry's: regenerate it with \
         `jamkit shapes --markdown > docs/reference/families.md`"
    );
    for f in jamkit_registry::FAMILIES {
        assert!(
            committed.contains(&format!("\n## {}\n", f.name)),
            "{}",
            f.name
        );
    }
}

// ---------------------------------------------------------------------------
// The experiment file: its fields and variants, read from serde's own
// messages. A struct that refuses unknown fields names all of its fields
// when given one it does not know, and an enum names its variants when
// given a variant it does not know; every variant found is then put in
// place and explored in turn.

/// Fields by struct and variants by enum, as serde names them.
#[derive(Default)]
struct Schema {
    fields: BTreeMap<String, BTreeSet<String>>,
    variants: BTreeMap<String, BTreeSet<String>>,
}

const FIELD_PROBE: &str = "zz_probe_field";
const VARIANT_PROBE: &str = "ZzProbeVariant";

fn parse(text: &str) -> Result<Experiment, String> {
    Experiment::from_ron(text, "probe").map_err(|e| e.to_string())
}

/// The names between backticks after "expected one of" in a serde message.
fn expected_names(message: &str) -> Vec<String> {
    let Some(at) = message.find("expected one of") else {
        return Vec::new();
    };
    message[at..]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(String::from)
        .collect()
}

/// The name between the first pair of backticks after `marker`.
fn name_after(message: &str, marker: &str) -> Option<String> {
    let at = message.find(marker)? + marker.len();
    message[at..].split('`').nth(1).map(String::from)
}

/// Byte ranges of identifiers in RON text, outside string literals.
fn identifiers(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let (mut out, mut k, mut in_string) = (Vec::new(), 0, false);
    while k < bytes.len() {
        let c = bytes[k];
        if in_string {
            if c == b'\\' {
                k += 1;
            } else if c == b'"' {
                in_string = false;
            }
            k += 1;
        } else if c == b'"' {
            in_string = true;
            k += 1;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = k;
            while k < bytes.len() && (bytes[k].is_ascii_alphanumeric() || bytes[k] == b'_') {
                k += 1;
            }
            out.push((start, k));
        } else {
            k += 1;
        }
    }
    out
}

/// End of the balanced `( … )` group opening at `open`.
fn group_end(text: &str, open: usize) -> usize {
    let mut depth = 0;
    for (k, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return open + k + 1;
                }
            }
            _ => {}
        }
    }
    text.len()
}

fn explore(text: &str, schema: &mut Schema, seen: &mut BTreeSet<String>) {
    let Ok(experiment) = parse(text) else { return };
    let canonical = ron::to_string(&experiment).unwrap();
    if !seen.insert(canonical.clone()) {
        return;
    }
    // Fields: a probe field right after each opening parenthesis.
    for (k, _) in canonical.match_indices('(') {
        let probe = format!(
            "{}{FIELD_PROBE}: 0,{}",
            &canonical[..=k],
            &canonical[k + 1..]
        );
        if let Err(m) = parse(&probe)
            && m.contains(&format!("`{FIELD_PROBE}`"))
            && let Some(owner) = name_after(&m, " in ")
        {
            schema
                .fields
                .entry(owner)
                .or_default()
                .extend(expected_names(&m));
        }
    }
    // `None` hides a struct: put an empty one in its place.
    for (start, end) in identifiers(&canonical) {
        if &canonical[start..end] == "None" {
            let text = format!("{}Some(()){}", &canonical[..start], &canonical[end..]);
            explore(&text, schema, seen);
        }
    }
    // Variants: replace each capitalised name by a probe, then by every
    // variant the message lists, bare and with an empty group.
    for (start, end) in identifiers(&canonical) {
        let word = &canonical[start..end];
        if !word.starts_with(|c: char| c.is_ascii_uppercase()) || word == "None" || word == "Some" {
            continue;
        }
        let group = if canonical[end..].starts_with('(') {
            group_end(&canonical, end)
        } else {
            end
        };
        let probe = format!(
            "{}{VARIANT_PROBE}{}",
            &canonical[..start],
            &canonical[group..]
        );
        let Err(m) = parse(&probe) else { continue };
        let Some(owner) = name_after(&m, "in enum") else {
            continue;
        };
        let variants = expected_names(&m);
        schema
            .variants
            .entry(owner)
            .or_default()
            .extend(variants.iter().cloned());
        for v in variants {
            for form in [v.clone(), format!("{v}()")] {
                let text = format!("{}{form}{}", &canonical[..start], &canonical[group..]);
                explore(&text, schema, seen);
            }
        }
    }
}

#[test]
fn every_experiment_field_and_variant_is_in_the_reference() {
    let mut schema = Schema::default();
    let mut seen = BTreeSet::new();
    explore(
        r#"(name: "probe", family: "sphere", particles: 16, observables: [Contacts])"#,
        &mut schema,
        &mut seen,
    );
    // The exploration must reach what the file is made of; if serde's
    // messages changed, it would find nothing and prove nothing.
    for (owner, needed) in [
        ("Experiment", "protocol"),
        ("FireParams", "force_tol"),
        ("Protocol", "AboveJam"),
        ("Observable", "Spectrum"),
    ] {
        let found = schema
            .fields
            .get(owner)
            .or_else(|| schema.variants.get(owner));
        assert!(
            found.is_some_and(|names| names.contains(needed)),
            "the exploration did not find `{owner}.{needed}`: fields {:?}, variants {:?}",
            schema.fields.keys().collect::<Vec<_>>(),
            schema.variants.keys().collect::<Vec<_>>()
        );
    }
    let text = page("experiment-file.md");
    let mut absent = Vec::new();
    for (owner, names) in schema.fields.iter().chain(&schema.variants) {
        for name in missing(&text, names) {
            absent.push(format!("{owner}: `{name}`"));
        }
    }
    assert!(
        absent.is_empty(),
        "docs/reference/experiment-file.md does not name (as `code`):\n{}",
        absent.join("\n")
    );
}

// ---------------------------------------------------------------------------
// The command line.

/// The subcommands listed under "Commands:" of a `--help` text.
fn commands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(String::from)
        .collect()
}

/// The long flags of a `--help` text (its option lines, `  -o, --out <OUT>`
/// or `      --quiet`), without `--help` and `--version`.
fn long_flags(help: &str) -> BTreeSet<String> {
    help.lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with('-'))
        .filter_map(|l| {
            let at = l.find("--")?;
            let name: String = l[at + 2..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            (!name.is_empty()).then(|| format!("--{name}"))
        })
        .filter(|w| w != "--help" && w != "--version")
        .collect()
}

/// The section of `text` under the heading line `heading`, to the next
/// heading of the same level.
fn section<'a>(text: &'a str, heading: &str) -> Option<&'a str> {
    let start = text.find(&format!("\n{heading}\n"))? + 1;
    let rest = &text[start + heading.len()..];
    let end = rest.find("\n## ").map_or(rest.len(), |k| k + 1);
    Some(&rest[..end])
}

#[test]
fn every_command_and_flag_is_in_the_reference() {
    let text = page("cli.md");
    let top = jamkit(&["--help"]);
    let names = commands(&top);
    assert!(names.len() >= 10, "commands found: {names:?}");
    let mut absent = Vec::new();
    for name in names {
        let heading = format!("## jamkit {name}");
        let Some(body) = section(&text, &heading) else {
            absent.push(format!("no heading `{heading}`"));
            continue;
        };
        let help = jamkit(&[name.as_str(), "--help"]);
        let mut flags = long_flags(&help);
        for sub in commands(&help) {
            if !body.contains(&sub) {
                absent.push(format!("jamkit {name} {sub}"));
            }
            flags.extend(long_flags(&jamkit(&[
                name.as_str(),
                sub.as_str(),
                "--help",
            ])));
        }
        for flag in flags {
            if !body.contains(&format!("`{flag}")) && !body.contains(&format!("{flag} ")) {
                absent.push(format!("jamkit {name} {flag}"));
            }
        }
    }
    assert!(
        absent.is_empty(),
        "docs/reference/cli.md lacks:\n{}",
        absent.join("\n")
    );
}

// ---------------------------------------------------------------------------
// The tables a run writes.

/// The packings of a small run of `experiment` (RON) into `dir`.
fn run(dir: &Path, experiment: &str) -> Vec<PackingFile> {
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("e.ron");
    std::fs::write(&file, experiment).unwrap();
    let out = dir.join("out");
    jamkit(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let mut files: Vec<PackingFile> = std::fs::read_dir(out.join("packings"))
        .unwrap()
        .map(|e| PackingFile::load(&e.unwrap().path()).expect("a packing file"))
        .collect();
    files.sort_by(|a, b| a.id.cmp(&b.id));
    files
}

fn header(csv: &str) -> Vec<String> {
    csv.lines()
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect()
}

#[test]
fn every_column_is_in_the_reference() {
    let scratch = tempfile::tempdir().unwrap();
    // Every observable, L-BFGS and the saddle escape on jammed disks …
    let jammed = run(
        &scratch.path().join("a"),
        r#"(name: "columns", family: "sphere", particles: 16, samples: 1,
            protocol: Jam(escape_saddles: true),
            minimizer: (lbfgs: Some(())),
            observables: [Contacts, Pressure, Spectrum(), Gaps()])"#,
    );
    // … and the moduli of a shear-stabilised cell above jamming.
    let mut above = run(
        &scratch.path().join("b"),
        r#"(name: "columns", family: "sphere", particles: 16, samples: 1,
            protocol: AboveJam(delta_phi: 1e-2, shear_stabilised: true),
            observables: [Contacts, Pressure, Moduli()])"#,
    );
    // A packing that was jammed again on its way up: its `left` list.
    let jam = above[0]
        .measures
        .jam_point
        .as_mut()
        .expect("a jamming point");
    jam.left.push(jam.phi);
    let mut files = jammed;
    files.extend(above);
    let groups = vec![("all".to_string(), files.iter().collect::<Vec<_>>())];
    let mut columns = BTreeSet::new();
    columns.extend(header(&jamkit_format::results_csv(&files, &[])));
    columns.extend(header(&jamkit_format::summary_csv(&groups)));
    columns.extend(header(&jamkit_format::dos_csv(&groups)));
    columns.extend(header(&jamkit_format::gaps_csv(&groups)));
    for needed in ["phi_j", "omega_1", "lbfgs_evals", "jam_rejams", "gaps"] {
        assert!(columns.contains(needed), "{needed} not among {columns:?}");
    }
    let absent = missing(&page("output-files.md"), &columns);
    assert!(
        absent.is_empty(),
        "docs/reference/output-files.md does not name (as `code`) the columns {absent:?}"
    );
}
