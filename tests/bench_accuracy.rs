//! `jamkit bench accuracy --quick`: the files it writes, their rows, and the
//! fitted orders of the gap models (2 for FirstOrder, 3 for SecondOrder).

mod common;
use common::jamkit;

fn rows(path: &std::path::Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').count();
    lines
        .map(|l| {
            let r: Vec<String> = l.split(',').map(String::from).collect();
            assert_eq!(r.len(), header, "{}: {l}", path.display());
            r
        })
        .collect()
}

#[test]
fn quick_accuracy_bench_writes_tables_figures_and_the_orders_of_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (code, stdout, err) = jamkit(&["bench", "accuracy", "--quick", "-o", out]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "pairs.csv",
        "slopes.csv",
        "packings.csv",
        "tolerances.csv",
        "tables.md",
        "errors_vs_delta.png",
        "errors_vs_delta.svg",
        "speed_vs_error.png",
        "speed_vs_error.svg",
        "tolerances.png",
        "tolerances.svg",
    ] {
        let p = dir.path().join(f);
        assert!(
            std::fs::metadata(&p).is_ok_and(|m| m.len() > 100),
            "{f} missing or empty"
        );
    }

    // Pairs: 3 models × n = 2…5 × 6 values of Δ. Exact is refused exactly
    // where the outline is non-convex (n = 4, 5 at Δ = 0.3), and there the
    // other models have a time but no error.
    let pairs = rows(&dir.path().join("pairs.csv"));
    assert_eq!(pairs.len(), 3 * 4 * 6);
    for r in &pairs {
        let (model, n, delta, convex) = (&r[0], &r[1], &r[2], &r[3]);
        let non_convex = delta == "0.3" && (n == "4" || n == "5");
        assert_eq!(convex == "false", non_convex, "{r:?}");
        let timed = r[4].parse::<f64>().is_ok_and(|t| t > 0.0);
        assert_eq!(timed, !(non_convex && model == "Exact"), "{r:?}");
        let has_error = r[5].parse::<f64>().is_ok_and(|e| e > 0.0);
        assert_eq!(has_error, !non_convex && model != "Exact", "{r:?}");
    }
    // SecondOrder is more accurate than FirstOrder wherever both are measured.
    for f in pairs
        .iter()
        .filter(|r| r[0] == "FirstOrder" && !r[5].is_empty())
    {
        let s = pairs
            .iter()
            .find(|r| r[0] == "SecondOrder" && r[1] == f[1] && r[2] == f[2])
            .unwrap();
        let (ef, es): (f64, f64) = (f[5].parse().unwrap(), s[5].parse().unwrap());
        assert!(es < ef, "n = {}, Δ = {}: {es} ≥ {ef}", f[1], f[2]);
    }

    // Slopes: one per approximate model and n, near the orders 2 and 3.
    let slopes = rows(&dir.path().join("slopes.csv"));
    assert_eq!(slopes.len(), 8);
    for r in &slopes {
        let slope: f64 = r[2].parse().unwrap();
        let order = if r[0] == "FirstOrder" { 2.0 } else { 3.0 };
        assert!((slope - order).abs() < 0.3, "{r:?}");
        let printed: f64 = stdout
            .lines()
            .find_map(|l| l.strip_prefix(&format!("slope {} n = {}: ", r[0], r[1])))
            .and_then(|rest| rest.split_whitespace().next()?.parse().ok())
            .unwrap_or_else(|| panic!("no printed slope for {r:?}: {stdout}"));
        assert!((printed - slope).abs() < 1e-3, "{printed} vs {r:?}");
    }

    // Packings: one per model (quick: Δ = 0.1, seed 1), from one start,
    // each converged with a packing fraction a near-disk packing can have.
    let packs = rows(&dir.path().join("packings.csv"));
    assert_eq!(packs.len(), 3);
    let start = &packs[0][5];
    for r in &packs {
        assert_eq!(&r[5], start, "same seed, same start: {r:?}");
        assert!(r.last().unwrap().is_empty(), "failed: {r:?}");
        let phi: f64 = r[8].parse().unwrap();
        assert!(phi > 0.7 && phi < 0.95, "{r:?}");
    }

    // Tolerances: 2 windows × 6 force tolerances × 2 seeds, all converged;
    // the tables name the reference setting.
    let tols = rows(&dir.path().join("tolerances.csv"));
    assert_eq!(tols.len(), 2 * 6 * 2);
    assert!(
        tols.iter().all(|r| r.last().unwrap().is_empty()),
        "{tols:?}"
    );
    let md = std::fs::read_to_string(dir.path().join("tables.md")).unwrap();
    assert!(md.contains("## Pair evaluations") && md.contains("## Tolerances"));
    assert!(md.contains("| 1e-16…2e-16 | 1e-28 | 2/2 |"), "{md}");
}

#[test]
fn bad_accuracy_options_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for args in [
        vec!["--particles", "2"],
        vec!["--packing-deltas", "0.9"],
        vec!["--packing-deltas", "nan"],
    ] {
        let mut all = vec!["bench", "accuracy", "--quick", "-o", out];
        all.extend(args.iter());
        let (code, _, err) = jamkit(&all);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && !err.contains("panicked"),
            "{err}"
        );
    }
}
