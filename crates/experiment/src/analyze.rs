//! `jamkit analyze FILE -o OUT.json`: a sphere packing made by another
//! code, measured as our own.
//!
//! Two formats are read:
//!
//! * **extended XYZ** (`.xyz`, `.extxyz`; what OVITO, ASE and LAMMPS' dump
//!   converters write): the first frame, with an orthorhombic `Lattice`, a
//!   `pos` column and a `radius` column in `Properties`; 2D when `pbc`
//!   says `"T T F"` (or `--dim 2`), the `z` column then ignored;
//! * **plain text** (any other name): one body per line, `x y r` in 2D or
//!   `x y z r` in 3D, `#` starting a comment; the box from `--box` or from
//!   a comment line `# box Lx Ly (Lz)`.
//!
//! The bodies become a packing of the `sphere` family in a periodic box
//! with the harmonic potential (`v = h²/2` on overlaps, the paper's), and
//! the requested observables (default: contacts, rattlers, `z`, the iso
//! margin, the pressure, the spectrum and the gaps) are measured on it as
//! on a packing jamkit made, without minimising it: a packing that is not
//! in mechanical equilibrium gets the numbers of the state it is in, and
//! `V/N` and the largest force are printed so that this can be seen. The
//! result is a jamkit packing file, which `jamkit draw`, `export`,
//! `spectrum` and `plot` read.
//!
//! Errors name the file, the line and what was expected there.

use crate::error::ExperimentError;
use crate::reload::{PackingVisitor, reload};
use crate::sample;
use crate::schema::{Experiment, Observable};
use jamkit_core::Shape;
use jamkit_engine::{Objective, Scene};
use jamkit_format::{Measures, PackingFile};
use std::path::Path;

/// How to read a file that does not say everything itself.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// The dimension (else from the file: `pbc` of extended XYZ, the
    /// column count of plain text).
    pub dim: Option<usize>,
    /// The box edges (plain text without a `# box` line).
    pub box_edges: Option<Vec<f64>>,
}

fn parse_err(path: &Path, line: usize, message: String) -> ExperimentError {
    ExperimentError::Parse {
        file: format!("{} line {line}", path.display()),
        message,
    }
}

fn number(path: &Path, line: usize, what: &str, text: &str) -> Result<f64, ExperimentError> {
    text.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| {
            parse_err(
                path,
                line,
                format!("{what} = `{text}`: expected a finite number"),
            )
        })
}

/// The bodies of `path`: dimension, box edges, centres and radii.
type Bodies = (usize, Vec<f64>, Vec<Vec<f64>>, Vec<f64>);

/// Read a foreign packing file as a jamkit packing file (family `sphere`,
/// nothing measured yet).
pub fn read(path: &Path, options: &ReadOptions) -> Result<PackingFile, ExperimentError> {
    let text = std::fs::read_to_string(path).map_err(|e| ExperimentError::io(path, e))?;
    let is_xyz = path
        .extension()
        .is_some_and(|e| e == "xyz" || e == "extxyz");
    let (dim, box_edges, positions, radii) = if is_xyz {
        read_xyz(path, &text, options)?
    } else {
        read_plain(path, &text, options)?
    };
    let n = positions.len();
    let volume: f64 = radii
        .iter()
        .map(|r| jamkit_core::math::unit_ball_volume(dim) * r.powi(dim as i32))
        .sum();
    let phi = volume / box_edges.iter().product::<f64>();
    let id = path
        .file_stem()
        .map_or("analyzed".into(), |s| s.to_string_lossy().into_owned());
    let (jamkit_version, git_commit) = jamkit_format::provenance::stamp();
    let file = PackingFile {
        id,
        experiment: "analyze".into(),
        family: "sphere".into(),
        params: serde_json::json!({}),
        dim,
        particles: n,
        seed: 0,
        protocol: "none".into(),
        settings: serde_json::json!({ "source": path.display().to_string() }),
        observables: serde_json::json!([]),
        phi,
        energy_per_particle: f64::NAN,
        measures: Measures::bare(phi, f64::NAN),
        box_edges,
        positions,
        radii,
        orientations: Vec::new(),
        rattler: Vec::new(),
        spheres: Vec::new(),
        jamkit_version,
        git_commit,
    };
    file.check_as(path.display())?;
    Ok(file)
}

fn read_xyz(path: &Path, text: &str, options: &ReadOptions) -> Result<Bodies, ExperimentError> {
    let mut lines = text.lines();
    let count = lines.next().unwrap_or("").trim();
    let n: usize = count
        .parse()
        .map_err(|_| parse_err(path, 1, format!("`{count}`: expected the number of atoms")))?;
    let comment = lines.next().unwrap_or("");
    let fields = key_values(comment);
    let get = |key: &str| {
        fields
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    };
    let lattice = get("Lattice").ok_or_else(|| {
        parse_err(
            path,
            2,
            "no Lattice=\"…\": the box is needed (periodic packings only)".into(),
        )
    })?;
    let l: Vec<f64> = lattice
        .split_whitespace()
        .map(|x| number(path, 2, "Lattice", x))
        .collect::<Result<_, _>>()?;
    if l.len() != 9 || [1, 2, 3, 5, 6, 7].iter().any(|&k| l[k] != 0.0) {
        return Err(parse_err(
            path,
            2,
            format!(
                "Lattice = \"{lattice}\": expected an orthorhombic box (nine numbers, off-diagonal zero)"
            ),
        ));
    }
    let dim = match (options.dim, get("pbc")) {
        (Some(d), _) => d,
        (None, Some(p))
            if p.split_whitespace()
                .nth(2)
                .is_some_and(|z| z.eq_ignore_ascii_case("F")) =>
        {
            2
        }
        _ => 3,
    };
    let properties = get("Properties").ok_or_else(|| {
        parse_err(
            path,
            2,
            "no Properties=…: the columns (pos, radius) are needed".into(),
        )
    })?;
    // Properties=name:type:count:… → the first column of each name.
    let parts: Vec<&str> = properties.split(':').collect();
    let (mut column, mut pos, mut radius) = (0, None, None);
    for spec in parts.chunks(3) {
        let [name, _, count] = spec else {
            return Err(parse_err(
                path,
                2,
                format!("Properties = {properties}: expected name:type:count triples"),
            ));
        };
        let count: usize = count.parse().map_err(|_| {
            parse_err(
                path,
                2,
                format!("Properties: `{count}` is not a column count"),
            )
        })?;
        match name.to_ascii_lowercase().as_str() {
            "pos" => pos = Some(column),
            "radius" | "radii" => radius = Some(column),
            "aspherical_shape" | "body" => {
                return Err(parse_err(
                    path,
                    2,
                    format!(
                        "Properties has `{name}`: not a packing of spheres (jamkit analyze reads spheres; for jamkit's own packings use their .json files)"
                    ),
                ));
            }
            _ => {}
        }
        column += count;
    }
    let pos = pos.ok_or_else(|| parse_err(path, 2, "Properties has no `pos` column".into()))?;
    let radius = radius.ok_or_else(|| {
        parse_err(
            path,
            2,
            "Properties has no `radius` column: jamkit needs each sphere's radius".into(),
        )
    })?;
    let mut positions = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    for k in 0..n {
        let line = k + 3;
        let row: Vec<&str> = lines
            .next()
            .ok_or_else(|| parse_err(path, line, format!("the file ends after {k} of {n} atoms")))?
            .split_whitespace()
            .collect();
        if row.len() < column {
            return Err(parse_err(
                path,
                line,
                format!("{} columns, Properties names {column}", row.len()),
            ));
        }
        let x: Vec<f64> = (0..dim)
            .map(|a| number(path, line, "pos", row[pos + a]))
            .collect::<Result<_, _>>()?;
        positions.push(x);
        radii.push(number(path, line, "radius", row[radius])?);
    }
    let box_edges = (0..dim).map(|a| l[4 * a]).collect();
    Ok((dim, box_edges, positions, radii))
}

/// `key=value` and `key="value with spaces"` pairs of an extended XYZ
/// comment line.
fn key_values(line: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = line.trim();
    while let Some(eq) = rest.find('=') {
        let key = rest[..eq].trim().to_string();
        let after = &rest[eq + 1..];
        let (value, next) = if let Some(stripped) = after.strip_prefix('"') {
            let end = stripped.find('"').unwrap_or(stripped.len());
            (&stripped[..end], stripped.get(end + 1..).unwrap_or(""))
        } else {
            let end = after.find(char::is_whitespace).unwrap_or(after.len());
            (&after[..end], &after[end..])
        };
        out.push((key, value.to_string()));
        rest = next.trim_start();
    }
    out
}

fn read_plain(path: &Path, text: &str, options: &ReadOptions) -> Result<Bodies, ExperimentError> {
    let mut box_edges = options.box_edges.clone();
    let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let (body, comment) = raw.split_once('#').unwrap_or((raw, ""));
        if let Some(b) = comment.trim().strip_prefix("box")
            && box_edges.is_none()
        {
            box_edges = Some(
                b.split_whitespace()
                    .map(|x| number(path, line, "box", x))
                    .collect::<Result<_, _>>()?,
            );
        }
        let values: Vec<f64> = body
            .split_whitespace()
            .map(|x| number(path, line, "column", x))
            .collect::<Result<_, _>>()?;
        if !values.is_empty() {
            rows.push((line, values));
        }
    }
    let Some((_, first)) = rows.first() else {
        return Err(parse_err(
            path,
            1,
            "no bodies: expected lines `x y r` (2D) or `x y z r` (3D)".into(),
        ));
    };
    let dim = options.dim.unwrap_or(first.len().saturating_sub(1));
    let box_edges = box_edges.ok_or_else(|| {
        ExperimentError::invalid(
            "--box",
            "none",
            format!(
                "{} has no `# box Lx Ly …` line: give the box edges with --box",
                path.display()
            ),
        )
    })?;
    if box_edges.len() != dim {
        return Err(ExperimentError::invalid(
            "box",
            format!("{box_edges:?}"),
            format!("must have one edge per dimension ({dim})"),
        ));
    }
    let mut positions = Vec::with_capacity(rows.len());
    let mut radii = Vec::with_capacity(rows.len());
    for (line, values) in rows {
        if values.len() != dim + 1 {
            return Err(parse_err(
                path,
                line,
                format!(
                    "{} numbers: expected {} (the centre's {dim} coordinates, then the radius)",
                    values.len(),
                    dim + 1
                ),
            ));
        }
        radii.push(values[dim]);
        positions.push(values[..dim].to_vec());
    }
    Ok((dim, box_edges, positions, radii))
}

/// The observables of `--observables`, a list as in an experiment file.
pub fn parse_observables(text: &str) -> Result<Vec<Observable>, ExperimentError> {
    ron::from_str(text).map_err(|e| {
        ExperimentError::invalid(
            "--observables",
            text,
            format!("{e}; expected a list as in an experiment file, e.g. [Contacts, Spectrum()]"),
        )
    })
}

/// `V/N` and the largest force component of the configuration.
fn energy_and_force(file: &PackingFile) -> Result<(f64, f64), ExperimentError> {
    struct Energy;
    impl PackingVisitor for Energy {
        type Output = (f64, f64);
        fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> (f64, f64) {
            let mut g = vec![0.0; scene.dof()];
            let v = scene.energy_gradient(&mut g);
            let n = scene.packing().positions.len() as f64;
            (v / n, g.iter().fold(0.0, |m: f64, x| m.max(x.abs())))
        }
    }
    reload(file, Energy)
}

/// Measure `observables` on `file` (read by [`read`]). Returns the file
/// with its measures, the largest force component, and the eigenvalue
/// table if the spectrum asked for one.
pub fn analyze(
    mut file: PackingFile,
    observables: &[Observable],
) -> Result<(PackingFile, f64, Option<String>), ExperimentError> {
    let (energy, force) = energy_and_force(&file)?;
    file.energy_per_particle = energy;
    file.measures.energy_per_particle = energy;
    let list: Vec<String> = observables
        .iter()
        .map(|o| ron::to_string(o).expect("observables serialise"))
        .collect();
    let text = format!(
        "(name: \"analyze\", family: \"sphere\", dim: {}, particles: {}, observables: [{}])",
        file.dim,
        file.particles.max(2),
        list.join(", ")
    );
    let experiment = Experiment::from_ron(&text, "analyze")?;
    let (file, table) = sample::measure_file(&experiment, file)?;
    Ok((file, force, table))
}
