//! `jamkit plot DIR… -o OUT`: figures of any run, whatever its family.
//!
//! `jamkit report` draws the paper's figures, which need near-disks with
//! `n` and `Δ`. This module draws what every run has: the packings are
//! grouped into points (family, dimension, `N`, parameters), and each
//! *scanned* quantity — a parameter, `N` or the dimension `d` that takes more than one value
//! in the runs — goes on the x axis of one figure per observable:
//!
//! * φ_J, `z_J` (and `z_corr` where rotational rattlers make it differ),
//!   the rattler fraction, the pressure, the moduli `G`, `B` (where
//!   `Moduli` was measured; with `shear_stabilised` also the fixed box's
//!   `G`, before the stabilisation) and `z − z_J` (where `AboveJam` recorded its
//!   jamming point), as the mean over the point's
//!   packings with the standard error as error bar; one series per value
//!   of the other scanned quantities (and per family), with its label;
//! * the pooled `D(ω)` of each point where `Spectrum` was measured, and
//!   the pooled cumulative gap distribution `Z(h)` where `Gaps` was, one
//!   curve per point (zero modes left out of `D(ω)`).
//!
//! The protocol's target (`Pressure`'s pressure, `Phi`'s φ, `AboveJam`'s
//! δφ) is a coordinate like a parameter, so runs of one file at several
//! targets are points along it.
//!
//! A run of one point (nothing scanned) is drawn packing by packing,
//! against the seed. An x axis is logarithmic when all its values are
//! positive and span a factor of 20 or more. A quantity that was not measured (no `Contacts`,
//! no `Pressure`) is skipped, and the index says so.

use crate::ReportError;
use crate::data::packing_paths;
use crate::plot::{Figure, Series};
use jamkit_core::stats::mean_sem;
use jamkit_format::{PackingFile, pooled_histogram};
use jamkit_observe::gaps::GapCounts;
use plotters::prelude::SeriesLabelPosition;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `plot` wrote.
#[derive(Clone, Debug)]
pub struct Plots {
    /// Figure files (without extension: each has `.svg` and `.png`).
    pub figures: Vec<PathBuf>,
    /// The scanned quantities found.
    pub scanned: Vec<String>,
    /// `OUT/index.md`: what each figure shows, and what was skipped.
    pub index: String,
}

/// One point of the runs: its coordinates and its packings.
struct Point {
    family: String,
    /// `N`, then every parameter, by name (numbers only; text parameters
    /// such as a gap model go into `tags`).
    coords: BTreeMap<String, f64>,
    tags: BTreeMap<String, String>,
    files: Vec<PackingFile>,
}

impl Point {
    /// A label of the coordinates other than `skip`.
    fn label(&self, scanned: &[String], skip: &str, families: bool) -> String {
        let mut parts: Vec<String> = Vec::new();
        if families {
            parts.push(self.family.clone());
        }
        for name in scanned.iter().filter(|n| n.as_str() != skip) {
            if let Some(v) = self.coords.get(name) {
                parts.push(format!("{} = {}", axis_name(name), short(*v)));
            } else if let Some(t) = self.tags.get(name) {
                parts.push(format!("{name} = {t}"));
            }
        }
        if parts.is_empty() {
            "all packings".into()
        } else {
            parts.join(", ")
        }
    }
}

/// `0.001` rather than `1e-3` for labels, whichever is shorter.
fn short(v: f64) -> String {
    let plain = format!("{v}");
    let sci = format!("{v:e}");
    if sci.len() < plain.len() { sci } else { plain }
}

/// How a coordinate is written on an axis.
fn axis_name(name: &str) -> String {
    match name {
        "particles" => "N".into(),
        "dim" => "d".into(),
        "delta" => "Δ".into(),
        "alpha" => "α".into(),
        "kappa" => "κ".into(),
        "seed" => "seed (one packing each)".into(),
        "target_pressure" => "p (target)".into(),
        "target_phi" => "φ (target)".into(),
        "delta_phi" => "δφ = φ − φ_J".into(),
        other => other.into(),
    }
}

/// Read every packing file in `dirs` (each a run or an archive; a packing
/// present in several is taken once) and group them into points.
fn load(dirs: &[PathBuf]) -> Result<Vec<Point>, ReportError> {
    let mut seen = std::collections::BTreeSet::new();
    let mut points: Vec<Point> = Vec::new();
    for dir in dirs {
        for path in packing_paths(dir)? {
            let Some(file) = PackingFile::load(&path) else {
                continue;
            };
            // The same packing in a run and its archive is taken once;
            // runs that differ in a setting the id does not name (the
            // target pressure of each of several runs) are all kept.
            if !seen.insert((file.id.clone(), file.settings.to_string())) {
                continue;
            }
            let mut coords = BTreeMap::from([
                ("dim".to_string(), file.dim as f64),
                ("particles".to_string(), file.particles as f64),
            ]);
            let mut tags = BTreeMap::new();
            if let Some(map) = file.params.as_object() {
                for (k, v) in map {
                    match v {
                        serde_json::Value::Number(x) => {
                            coords.insert(k.clone(), x.as_f64().unwrap_or(f64::NAN));
                        }
                        serde_json::Value::Null => {}
                        other => {
                            tags.insert(k.clone(), other.to_string().trim_matches('"').to_string());
                        }
                    }
                }
            }
            // The protocol's target is a coordinate too (several runs of
            // one file at different pressures or distances from jamming).
            if let Some(protocol) = file.settings.get("protocol").and_then(|p| p.as_object()) {
                for (kind, fields) in protocol {
                    for (field, name) in PROTOCOL_TARGETS
                        .iter()
                        .filter(|t| t.0 == kind.as_str())
                        .map(|t| (t.1, t.2))
                    {
                        if let Some(x) = fields.get(field).and_then(|v| v.as_f64()) {
                            coords.insert(name.to_string(), x);
                        }
                    }
                }
            }
            let key = |p: &Point| p.family == file.family && p.coords == coords && p.tags == tags;
            match points.iter_mut().find(|p| key(p)) {
                Some(p) => p.files.push(file),
                None => points.push(Point {
                    family: file.family.clone(),
                    coords: coords.clone(),
                    tags: tags.clone(),
                    files: vec![file],
                }),
            }
        }
    }
    Ok(points)
}

/// The value of coordinate `name` at `p`, as text (for splitting).
fn split_value(p: &Point, name: &str) -> String {
    p.coords
        .get(name)
        .map(|v| short(*v))
        .or_else(|| p.tags.get(name).cloned())
        .unwrap_or_default()
}

/// The quantities that take more than one value over `points`.
fn scanned(points: &[Point]) -> Vec<String> {
    let mut names: std::collections::BTreeSet<String> = std::collections::BTreeSet::new();
    for p in points {
        names.extend(p.coords.keys().cloned());
        names.extend(p.tags.keys().cloned());
    }
    names
        .into_iter()
        .filter(|name| {
            let mut values: Vec<String> = points
                .iter()
                .map(|p| {
                    p.coords
                        .get(name)
                        .map(|v| v.to_string())
                        .or_else(|| p.tags.get(name).cloned())
                        .unwrap_or_default()
                })
                .collect();
            values.sort();
            values.dedup();
            values.len() > 1
        })
        .collect()
}

/// A series in the making: the order key (the other coordinates), its
/// label and its points `(x, mean, s.e.m.)`.
type Group = (Vec<f64>, String, Vec<(f64, f64, f64)>);

/// One observable of a packing (`None` where it was not measured).
type Measure = fn(&PackingFile) -> Option<f64>;

/// Protocol targets that become coordinates: protocol, its field, the
/// coordinate's name.
const PROTOCOL_TARGETS: [(&str, &str, &str); 3] = [
    ("Pressure", "pressure", "target_pressure"),
    ("Phi", "phi", "target_phi"),
    ("AboveJam", "delta_phi", "delta_phi"),
];

const OBSERVABLES: [(&str, &str, Measure); 10] = [
    ("phi_j", "φ_J", |f| Some(f.phi)),
    ("z_j", "z_J", |f| f.measures.z_j),
    ("z_corr", "z_corr", |f| f.z_corr()),
    ("rattlers", "rattler fraction", |f| {
        Some(f.measures.n_rattlers? as f64 / f.particles as f64)
    }),
    ("pressure", "pressure p", |f| f.measures.pressure),
    ("shear_modulus", "shear modulus G", |f| {
        Some(f.measures.moduli.as_ref()?.moduli.shear)
    }),
    ("bulk_modulus", "bulk modulus B", |f| {
        Some(f.measures.moduli.as_ref()?.moduli.bulk)
    }),
    // `protocol.shear_stabilised`: `G` above is the stabilised cell's, and
    // this the fixed box's, measured before the stabilisation.
    (
        "shear_modulus_fixed_box",
        "shear modulus G of the fixed box (before the shear stabilisation)",
        |f| {
            let m = f.measures.moduli.as_ref()?;
            Some(m.stabilisation.as_ref()?.fixed_box.shear)
        },
    ),
    (
        "z_above_jam",
        "z − z_J (from its own jamming point)",
        |f| Some(f.measures.z_j? - f.measures.jam_point.as_ref()?.z?),
    ),
    // `protocol.shear_stabilised`: the stabilised cell's contacts against
    // the fixed box's jamming point.
    (
        "z_stab_above_jam",
        "z − z_J of the shear-stabilised cell (from its own jamming point)",
        |f| {
            let m = f.measures.moduli.as_ref()?;
            let cell = m.stabilisation.as_ref()?.contacts.as_ref()?;
            Some(cell.z - f.measures.jam_point.as_ref()?.z?)
        },
    ),
];

/// Draw the figures of the runs in `dirs` into `out`.
pub fn plot(dirs: &[PathBuf], out: &Path) -> Result<Plots, ReportError> {
    let points = load(dirs)?;
    if points.is_empty() {
        let list: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        return Err(ReportError::NoPackings(list.join(", ")));
    }
    std::fs::create_dir_all(out).map_err(|e| ReportError::Io {
        path: out.to_path_buf(),
        error: e,
    })?;
    let mut scanned = scanned(&points);
    let mut points = points;
    if scanned.is_empty() {
        // One point: its packings one by one, against their seed.
        points = points
            .into_iter()
            .flat_map(|p| {
                p.files.into_iter().map(move |f| {
                    let mut coords = p.coords.clone();
                    coords.insert("seed".into(), f.seed as f64);
                    Point {
                        family: p.family.clone(),
                        coords,
                        tags: p.tags.clone(),
                        files: vec![f],
                    }
                })
            })
            .collect();
        scanned = vec!["seed".into()];
    }
    let families = {
        let mut f: Vec<&str> = points.iter().map(|p| p.family.as_str()).collect();
        f.sort_unstable();
        f.dedup();
        f.len() > 1
    };
    let mut figures = Vec::new();
    let mut index = String::from("# Figures of the runs\n\n");
    let _ = writeln!(
        index,
        "{} points, {} packings; scanned: {}.\n",
        points.len(),
        points.iter().map(|p| p.files.len()).sum::<usize>(),
        if scanned.is_empty() {
            "nothing (one point)".to_string()
        } else {
            scanned
                .iter()
                .map(|s| axis_name(s))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    let mut save = |name: String, figure: Figure, about: String| -> Result<(), ReportError> {
        let stem = out.join(&name);
        figure.write(&stem)?;
        let _ = writeln!(index, "* `{name}`: {about}\n\n  ![{name}]({name}.png)");
        figures.push(stem);
        Ok(())
    };
    let mut skipped: Vec<String> = Vec::new();
    // Observables against each numeric scanned quantity.
    for x_name in scanned
        .iter()
        .filter(|n| points.iter().any(|p| p.coords.contains_key(*n)))
    {
        let xs: Vec<f64> = points
            .iter()
            .filter_map(|p| p.coords.get(x_name))
            .copied()
            .collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let log_x = lo > 0.0 && hi >= 20.0 * lo;
        for (key, y_label, measure) in OBSERVABLES {
            // One series per value of the other coordinates, in their
            // numerical order.
            let mut groups: Vec<Group> = Vec::new();
            for p in points.iter() {
                let Some(&x) = p.coords.get(x_name) else {
                    continue;
                };
                let values: Vec<f64> = p.files.iter().filter_map(measure).collect();
                if values.is_empty() {
                    continue;
                }
                let (m, se) = mean_sem(&values);
                let label = p.label(&scanned, x_name, families);
                match groups.iter_mut().find(|g| g.1 == label) {
                    Some(g) => g.2.push((x, m, se)),
                    None => {
                        let order = p
                            .coords
                            .iter()
                            .filter(|(k, _)| *k != x_name)
                            .map(|(_, v)| *v)
                            .collect();
                        groups.push((order, label, vec![(x, m, se)]));
                    }
                }
            }
            if groups.is_empty() {
                skipped.push(format!(
                    "{y_label} against {} (not measured)",
                    axis_name(x_name)
                ));
                continue;
            }
            // z_corr only where it says something z_J does not.
            if key == "z_corr" {
                let same = points
                    .iter()
                    .all(|p| p.files.iter().all(|f| f.z_corr() == f.measures.z_j));
                if same {
                    continue;
                }
            }
            groups.sort_by(|a, b| {
                a.0.iter()
                    .zip(&b.0)
                    .map(|(x, y)| x.total_cmp(y))
                    .find(|o| o.is_ne())
                    .unwrap_or(a.1.cmp(&b.1))
            });
            // Pressure and moduli on a log axis when every mean is positive
            // and they span a factor of 20 (a negative mean G stays on a
            // linear axis, where it shows). `z − z_J` is exactly 0 where a
            // compression gained no contact: such points are left off a
            // log axis (the caption counts them), a negative one keeps the
            // axis linear.
            let zero_ok = matches!(key, "z_above_jam" | "z_stab_above_jam");
            let ys: Vec<f64> = groups
                .iter()
                .flat_map(|g| g.2.iter().map(|p| p.1))
                .collect();
            let zeros = ys.iter().filter(|&&y| y == 0.0).count();
            let positive = ys.iter().copied().filter(|&y| y > 0.0);
            let lo = positive.clone().fold(f64::INFINITY, f64::min);
            let hi = positive.fold(f64::NEG_INFINITY, f64::max);
            let log_y = matches!(
                key,
                "pressure"
                    | "shear_modulus"
                    | "shear_modulus_fixed_box"
                    | "bulk_modulus"
                    | "z_above_jam"
                    | "z_stab_above_jam"
            ) && ys.iter().all(|&y| y > 0.0 || (zero_ok && y == 0.0))
                && hi >= 20.0 * lo;
            let left_off = if log_y && zeros > 0 {
                for g in groups.iter_mut() {
                    g.2.retain(|p| p.1 > 0.0);
                }
                let points = if zeros == 1 { "point" } else { "points" };
                format!(" ({zeros} {points} with a mean of exactly 0 left off the log axis)")
            } else {
                String::new()
            };
            let series = groups
                .into_iter()
                .map(|(_, label, mut pts)| {
                    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                    Series {
                        label,
                        points: pts,
                        line: false,
                    }
                })
                .collect();
            save(
                format!("{key}_vs_{x_name}"),
                Figure {
                    title: format!("{y_label} against {}", axis_name(x_name)),
                    x_label: axis_name(x_name),
                    y_label: y_label.into(),
                    log_x,
                    log_y,
                    series,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::UpperLeft,
                },
                format!(
                    "{y_label} against {}, mean ± s.e.m. over each point's packings{left_off}",
                    axis_name(x_name)
                ),
            )?;
        }
    }
    // D(ω) and Z(h), one curve per point; more than eight points are split
    // into one figure per value of the scanned quantity with the fewest
    // values (e.g. one per n).
    let split: Option<&String> = (points.len() > 8)
        .then(|| {
            scanned.iter().min_by_key(|name| {
                let mut v: Vec<String> = points.iter().map(|p| split_value(p, name)).collect();
                v.sort();
                v.dedup();
                v.len()
            })
        })
        .flatten();
    let mut parts: Vec<(String, Vec<&Point>)> = Vec::new();
    for p in &points {
        let key = split.map_or(String::new(), |name| split_value(p, name));
        match parts.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(p),
            None => parts.push((key, vec![p])),
        }
    }
    let mut any_dos = false;
    let mut any_gaps = false;
    for (value, members) in &parts {
        let (suffix, title) = match split {
            Some(name) => (
                format!("_{name}{value}"),
                format!(", {} = {value}", axis_name(name)),
            ),
            None => (String::new(), String::new()),
        };
        let label = |p: &Point| p.label(&scanned, split.map_or("", |s| s.as_str()), families);
        let dos: Vec<Series> = members
            .iter()
            .filter_map(|p| {
                let refs: Vec<&PackingFile> = p.files.iter().collect();
                let h = pooled_histogram(&refs)?;
                Some(Series {
                    label: label(p),
                    points: h
                        .centres()
                        .iter()
                        .zip(h.density())
                        .map(|(&w, d)| (w, d, 0.0))
                        .collect(),
                    line: true,
                })
            })
            .collect();
        if !dos.is_empty() {
            any_dos = true;
            save(
                format!("dos{suffix}"),
                Figure {
                    title: format!("density of states (pooled){title}"),
                    x_label: "ω".into(),
                    y_label: "D(ω)".into(),
                    log_x: true,
                    log_y: true,
                    series: dos,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::LowerRight,
                },
                format!("D(ω) of each point{title}, zero modes left out"),
            )?;
        }
        let gaps: Vec<Series> = members
            .iter()
            .filter_map(|p| {
                let mut pooled: Option<GapCounts> = None;
                for g in p.files.iter().filter_map(|f| f.measures.gaps.as_ref()) {
                    match &mut pooled {
                        None => pooled = Some(g.clone()),
                        Some(acc) => acc.merge(g).ok()?,
                    }
                }
                let g = pooled?;
                Some(Series {
                    label: label(p),
                    points: g
                        .h
                        .iter()
                        .zip(g.cumulative())
                        .filter(|(_, z)| *z > 0.0)
                        .map(|(&h, z)| (h, z, 0.0))
                        .collect(),
                    line: true,
                })
            })
            .collect();
        if !gaps.is_empty() {
            any_gaps = true;
            save(
                format!("gaps{suffix}"),
                Figure {
                    title: format!("cumulative gap distribution (pooled){title}"),
                    x_label: "h".into(),
                    y_label: "Z(h)".into(),
                    log_x: true,
                    log_y: true,
                    series: gaps,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::UpperLeft,
                },
                format!("Z(h) of each point{title}: the fraction of gaps below h"),
            )?;
        }
    }
    if !any_dos {
        skipped.push("D(ω) (no Spectrum measured)".into());
    }
    if !any_gaps {
        skipped.push("Z(h) (no Gaps measured)".into());
    }
    if !skipped.is_empty() {
        index += "\n## Skipped\n\n";
        for s in &skipped {
            let _ = writeln!(index, "* {s}");
        }
    }
    let path = out.join("index.md");
    std::fs::write(&path, &index).map_err(|e| ReportError::Io { path, error: e })?;
    Ok(Plots {
        figures,
        scanned,
        index,
    })
}
