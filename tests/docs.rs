//! The manual holds: every shell command of the tutorials and how-to
//! guides runs, every page is listed in the index and no page is longer
//! than a reader can take in, and every relative link points at a file.
//!
//! The commands are the ```sh blocks of `docs/tutorials/*.md` and
//! `docs/how-to/*.md`. The blocks of one page run in order in one
//! `bash -euo pipefail`, in a scratch directory where the repository's
//! `experiments/`, `docs/` and `shapes/` are visible and `jamkit` is this
//! build's binary. The line before a block may carry
//! a directive for this test:
//!
//! * `<!-- ci: --set particles=32 --set samples=1 -->`: appended to every
//!   `jamkit run` command of the block, so that CI runs it at small size;
//! * `<!-- ci: skip: REASON -->`: not run here (a cargo or pip command, a
//!   real cluster); the reason names what covers it.
//!
//! A ```ron block after `<!-- ci: same as PATH -->` must be the shipped
//! file `PATH` as it is, so that a page that shows a file shows it whole
//! and current.

use std::path::{Path, PathBuf};
use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
/// The longest page of the manual, in lines.
const MAX_LINES: usize = 500;

/// One ```sh block: where it starts, its directive and its commands.
struct Block {
    line: usize,
    directive: Option<String>,
    lines: Vec<String>,
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The Markdown files under `dir` (recursively), sorted.
fn pages(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(pages(&p));
        } else if p.extension().is_some_and(|x| x == "md") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// The ```sh blocks of a page, with the `<!-- ci: … -->` directive on the
/// line before each, if any.
fn sh_blocks(text: &str) -> Vec<Block> {
    blocks(text, &["```sh", "```bash"])
}

/// The blocks of a page opened by one of `fences`, with their directives.
fn blocks(text: &str, fences: &[&str]) -> Vec<Block> {
    let lines: Vec<&str> = text.lines().collect();
    let mut blocks = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let fence = lines[k].trim_end();
        if fences.contains(&fence) {
            let directive = k
                .checked_sub(1)
                .map(|j| lines[j].trim())
                .and_then(|l| l.strip_prefix("<!-- ci:"))
                .and_then(|l| l.strip_suffix("-->"))
                .map(|l| l.trim().to_string());
            let start = k + 1;
            let mut end = start;
            while end < lines.len() && !lines[end].trim_start().starts_with("```") {
                end += 1;
            }
            assert!(
                end < lines.len(),
                "a ```sh block at line {start} is not closed"
            );
            blocks.push(Block {
                line: start,
                directive,
                lines: lines[start..end].iter().map(|l| l.to_string()).collect(),
            });
            k = end + 1;
        } else {
            k += 1;
        }
    }
    blocks
}

/// The block's commands as the test runs them: continuation lines joined,
/// the directive's overrides appended to each `jamkit run`.
fn script(block: &Block) -> String {
    let mut joined: Vec<String> = Vec::new();
    let mut open = false;
    for l in &block.lines {
        if open {
            let last = joined.last_mut().expect("a continued line");
            last.push(' ');
            last.push_str(l.trim());
        } else {
            joined.push(l.clone());
        }
        open = l.trim_end().ends_with('\\');
        if open {
            let last = joined.last_mut().expect("a line");
            let trimmed = last.trim_end().trim_end_matches('\\').to_string();
            *last = trimmed;
        }
    }
    let overrides = block
        .directive
        .as_deref()
        .filter(|d| d.starts_with("--"))
        .unwrap_or("");
    joined
        .into_iter()
        .map(|l| {
            if !overrides.is_empty() && l.trim_start().starts_with("jamkit run ") {
                format!("{l} {overrides}")
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The pages whose commands must run.
fn runnable_pages() -> Vec<PathBuf> {
    let root = Path::new(ROOT);
    let mut out = pages(&root.join("docs/tutorials"));
    out.extend(pages(&root.join("docs/how-to")));
    out
}

#[test]
fn every_tutorial_and_how_to_command_runs() {
    let root = Path::new(ROOT);
    let bin = Path::new(env!("CARGO_BIN_EXE_jamkit"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut ran = 0;
    let mut failures = Vec::new();
    for page in runnable_pages() {
        let name = page.strip_prefix(root).unwrap().display().to_string();
        let blocks = sh_blocks(&read(&page));
        let mut text = String::from("set -euo pipefail\n");
        for b in &blocks {
            match b.directive.as_deref() {
                Some(d) if d.starts_with("skip:") => {
                    assert!(
                        d["skip:".len()..].trim().len() > 10,
                        "{name}:{}: a skipped block must say why (`<!-- ci: skip: REASON -->`)",
                        b.line
                    );
                    continue;
                }
                Some(d) if !d.starts_with("--") => {
                    panic!(
                        "{name}:{}: unknown directive `{d}` (allowed: `skip: REASON`, or `--set …` overrides)",
                        b.line
                    )
                }
                _ => {}
            }
            text.push_str(&format!("echo '>>> {name}:{}' >&2\n", b.line));
            text.push_str(&script(b));
            text.push('\n');
            ran += 1;
        }
        let scratch = tempfile::tempdir().unwrap();
        for dir in ["experiments", "docs", "shapes"] {
            std::os::unix::fs::symlink(root.join(dir), scratch.path().join(dir)).unwrap();
        }
        let out = Command::new("bash")
            .arg("-c")
            .arg(&text)
            .current_dir(scratch.path())
            .env("PATH", &path)
            .output()
            .unwrap();
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            let at = err
                .lines()
                .rev()
                .find_map(|l| l.strip_prefix(">>> "))
                .unwrap_or("?")
                .to_string();
            let tail: Vec<&str> = err.lines().rev().take(15).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            failures.push(format!(
                "the block at {at} failed ({}):\n{}",
                out.status,
                tail.join("\n")
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    // The tutorials and how-to guides hold commands; none ran means the
    // pages or the block syntax moved.
    assert!(ran >= 10, "only {ran} blocks ran");
}

#[test]
fn directives_apply_overrides_and_join_continued_lines() {
    let page = "text\n<!-- ci: --set samples=1 -->\n```sh\njamkit run a.ron \\\n  --out x\njamkit plot x -o y\n```\n";
    let blocks = sh_blocks(page);
    assert_eq!(blocks.len(), 1);
    assert_eq!(
        script(&blocks[0]),
        "jamkit run a.ron  --out x --set samples=1\njamkit plot x -o y"
    );
}

#[test]
fn every_page_is_in_the_index_and_short() {
    let root = Path::new(ROOT);
    let index = read(&root.join("docs/README.md"));
    for page in pages(&root.join("docs")) {
        let rel = page.strip_prefix(root.join("docs")).unwrap();
        let rel = rel.display().to_string();
        if rel == "README.md" || rel.contains("speed-vs-error/") || rel.contains("report-quick/") {
            continue;
        }
        assert!(
            index.contains(&format!("({rel})")),
            "docs/{rel} is not linked from the index docs/README.md"
        );
        let n = read(&page).lines().count();
        assert!(
            n <= MAX_LINES,
            "docs/{rel} has {n} lines: a page of the manual has at most {MAX_LINES}"
        );
    }
}

/// Relative links `](path)` of the manual and the README point at files
/// that exist (anchors and web addresses are not checked).
#[test]
fn relative_links_resolve() {
    let root = Path::new(ROOT);
    let mut files = pages(&root.join("docs"));
    files.push(root.join("README.md"));
    let mut broken = Vec::new();
    for page in files {
        let text = read(&page);
        let mut in_code = false;
        for (k, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("```") {
                in_code = !in_code;
            }
            if in_code {
                continue;
            }
            let mut rest = line;
            while let Some(at) = rest.find("](") {
                rest = &rest[at + 2..];
                let Some(end) = rest.find(')') else { break };
                let target = &rest[..end];
                rest = &rest[end..];
                let target = target.split('#').next().unwrap_or("");
                if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                if !page.parent().unwrap().join(target).exists() {
                    broken.push(format!(
                        "{}:{}: {target}",
                        page.strip_prefix(root).unwrap().display(),
                        k + 1
                    ));
                }
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links to nothing:\n{}",
        broken.join("\n")
    );
}

/// A page that shows a shipped file (`<!-- ci: same as PATH -->` before a
/// ```ron block) shows it as it is.
#[test]
fn shown_files_are_the_shipped_ones() {
    let root = Path::new(ROOT);
    let mut shown = 0;
    for page in pages(&root.join("docs")) {
        for b in blocks(&read(&page), &["```ron"]) {
            let Some(path) = b
                .directive
                .as_deref()
                .and_then(|d| d.strip_prefix("same as "))
            else {
                continue;
            };
            let file = read(&root.join(path.trim()));
            assert_eq!(
                b.lines.join("\n").trim_end(),
                file.trim_end(),
                "{}:{}: the block is not {path} as shipped",
                page.display(),
                b.line
            );
            shown += 1;
        }
    }
    assert!(shown >= 1, "no page shows a shipped file");
}
