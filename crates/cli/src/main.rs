//! `jamkit`: the command line.
//!
//! * `jamkit run FILE… [--out DIR] [--jobs N] [--set KEY=VALUE …]`
//! * `jamkit validate FILE [--set KEY=VALUE …]`
//! * `jamkit shapes [--markdown]`
//! * `jamkit bench [packing|eval|spectrum|accuracy|pair]`
//! * `jamkit spectrum PACKING.json [--stiffness-only] [--remove-rattlers] [--modes] -o FILE.csv`
//! * `jamkit report DIR… -o OUT`
//! * `jamkit draw PACKING.json -o FILE.svg|FILE.png [--size PIXELS]`
//! * `jamkit draw-shape [FAMILY] [--dim 2|3] [--panel RON …] [--curve RON …] [--n 2,3] [--delta 0,0.1] [--modes RON …] -o FILE.svg|FILE.png`

/// `println!` that ignores a closed pipe (`jamkit validate … | head`)
/// instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod bench;
mod check;
mod spectrum;

use anyhow::{Context, Result, bail};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use jamkit_experiment::grid::Shard;
use jamkit_experiment::runner::{RunOptions, default_out, run};
use jamkit_experiment::{Experiment, Log, Plan, overrides};
use jamkit_registry as registry;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "jamkit",
    version,
    about = "Jamming of frictionless particles, spherical and not"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run an experiment file; results go to DIR (default out/<name>).
    Run {
        /// The RON experiment file(s), run one after the other (files with
        /// the same name share an output directory and add up their
        /// observables on the same packings).
        #[arg(required = true, num_args = 1..)]
        files: Vec<PathBuf>,
        /// Output directory; a rerun into the same directory resumes.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        jobs: Option<usize>,
        /// Override a field: --set particles=256 --set protocol.eps=1e-4.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Run only part I of K of the samples (e.g. one part per task of a
        /// cluster job array; docs/how-to/slurm.md). Parts may share one output
        /// directory; a part writes packings only, and a run without
        /// --shard into that directory reuses them and writes the tables.
        #[arg(long, value_name = "I/K")]
        shard: Option<String>,
        /// Write nothing on stderr while running.
        #[arg(long, conflicts_with = "verbose")]
        quiet: bool,
        /// Write log lines (one per finished packing, one every 10 s per
        /// running packing) even on a terminal. Without a terminal (a batch
        /// job) they are the default, every 30 s.
        #[arg(long)]
        verbose: bool,
    },
    /// Gather the parts of a run (`run --shard`) from separate directories
    /// into one, with the tables of one plain run; refuses parts of
    /// different experiments, conflicting duplicates and missing packings.
    Merge {
        /// The parts' output directories.
        #[arg(required = true, num_args = 1..)]
        dirs: Vec<PathBuf>,
        /// The merged run's directory (may be one of the parts).
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Copy a run's measures, tables and experiment.ron without the
    /// packings' configurations (a fortieth of the size at N = 1024): what
    /// `jamkit report` needs, small enough to commit
    /// (docs/reference/output-files.md, "Archives"). Packings the run has not made yet are absent.
    Archive {
        /// The run's directory.
        dir: PathBuf,
        /// The archive's directory.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Write packings as extended XYZ (for OVITO and ASE) or, for an output
    /// file ending in .gsd, as HOOMD-blue's GSD (for HOOMD-blue, OVITO and
    /// the Python package gsd): one packing file, or every packing of a run
    /// directory as the frames of one file
    /// (docs/reference/export-formats.md).
    Export {
        /// A packing file (DIR/packings/<id>.json) or a run directory.
        path: PathBuf,
        /// The file to write: FILE.gsd for GSD, any other name (FILE.xyz)
        /// for extended XYZ.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Check an experiment file and print its grid, without running it.
    Validate {
        /// The RON experiment file.
        file: PathBuf,
        /// Override a field, as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
    /// List the registered shape families and their parameters.
    Shapes {
        /// Print the reference page docs/reference/families.md (Markdown)
        /// instead of the plain list.
        #[arg(long)]
        markdown: bool,
    },
    /// Run the conformance kit on one family: forces and Hessian against
    /// finite differences, symmetry, invariances, smoothness, a small jam.
    Check {
        /// The family's registered name.
        family: String,
        /// Its parameters in RON, e.g. "(delta: 0.2, kappa: 2.0)"; default:
        /// the family's example.
        #[arg(long)]
        params: Option<String>,
        /// Only this dimension; default: every dimension the family claims.
        #[arg(long)]
        dim: Option<usize>,
    },
    /// Time the engine (see docs/reports/performance.md).
    Bench {
        #[command(subcommand)]
        what: bench::BenchCommand,
    },
    /// The paper's figures from runs of experiments/paper/ (near-disks, n)
    /// or experiments/paper3d/ (near-spheres, l): PNG and SVG plots, fitted
    /// exponents and a markdown summary (OUT/report.md).
    Report {
        /// Output directories of runs (each with packings/).
        #[arg(required = true, num_args = 1..)]
        dirs: Vec<PathBuf>,
        /// Directory for the figures and report.md.
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// γ of the gap distribution, for the guides and the collapse.
        #[arg(long, default_value_t = 0.41)]
        gamma: f64,
        /// Bootstrap resamples per fitted exponent.
        #[arg(long, default_value_t = 500)]
        resamples: usize,
        /// Instead of the paper's figures, the accuracy comparison of
        /// docs/reports/speed-vs-error.md: `gap-models` (each packing against the
        /// most accurate gap model's of the same Δ and seed) or `tolerances`
        /// (against the tightest force tolerance that converged on the same
        /// seed); writes its CSV, figure and OUT/accuracy.md.
        #[arg(long, value_name = "STUDY")]
        accuracy: Option<String>,
    },
    /// Measure a sphere packing made by another code (extended XYZ, or
    /// plain `x y (z) r` lines) as our own: contacts, rattlers, z, iso
    /// margin, pressure, spectrum, gaps; writes a jamkit packing file
    /// (docs/reference/output-files.md, "jamkit analyze output").
    Analyze {
        /// The packing: FILE.xyz / FILE.extxyz (extended XYZ, first frame)
        /// or plain text.
        file: PathBuf,
        /// The jamkit packing file to write.
        #[arg(short, long)]
        out: PathBuf,
        /// The dimension, where the file does not say it.
        #[arg(long)]
        dim: Option<usize>,
        /// Box edges `Lx,Ly(,Lz)`, for plain text without a `# box` line.
        #[arg(long, value_delimiter = ',')]
        r#box: Option<Vec<f64>>,
        /// The observables, as in an experiment file.
        #[arg(long, default_value = "[Contacts, Pressure, Spectrum(), Gaps()]")]
        observables: String,
    },
    /// Figures of any run, whatever its family: each scanned parameter (or
    /// N) against φ_J, z_J, z_corr, the rattler fraction and the pressure
    /// with error bars, and D(ω) and Z(h) where they were measured
    /// (docs/reference/output-files.md, "jamkit plot output").
    Plot {
        /// Output directories of runs (or archives), each with packings/.
        #[arg(required = true, num_args = 1..)]
        dirs: Vec<PathBuf>,
        /// Directory for the figures and index.md.
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
    },
    /// Eigenvalues of a saved packing's Hessian, one per line, ascending.
    Spectrum {
        /// A packing file written by `run` (DIR/packings/<id>.json).
        packing: PathBuf,
        /// Only the stiffness part K (default: the full Hessian K + T).
        #[arg(long)]
        stiffness_only: bool,
        /// Leave out the rattlers' rows (the file's rattler flags).
        #[arg(long)]
        remove_rattlers: bool,
        /// Also write each mode's participation ratio and rotational share
        /// (a CSV with a header: lambda,omega,participation,rotational_share).
        #[arg(long)]
        modes: bool,
        /// The file to write (`-` for standard output).
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Draw a 2D packing file (true outlines, periodic images, rattlers) or
    /// a 3D one (an orthographic ray-cast of the box seen along z).
    Draw {
        /// A packing file written by `run` (DIR/packings/<id>.json).
        packing: PathBuf,
        /// The picture to write: FILE.svg or FILE.png.
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
        /// Length in pixels of the picture's longer side.
        #[arg(long, value_name = "PIXELS", default_value_t = jamkit_draw::render::DEFAULT_SIZE)]
        size: u32,
        /// 3D only: draw the content of the periodic box, every body cut to
        /// 0 ≤ z ≤ L3 (cross-sections on the top face), instead of the
        /// whole bodies whose centres lie in the box.
        #[arg(long)]
        cut: bool,
    },
    /// Polar plots R(θ)/R0 of a family's shapes (SVG or PNG): one panel per
    /// parameter set (--panel, --n, --modes), one curve per parameter set
    /// (--curve, --delta); unset parameters come from the family's example.
    DrawShape {
        /// Any family whose 2D bodies have an outline, or any 3D family
        /// (`jamkit shapes`).
        #[arg(default_value = "fourier")]
        family: String,
        /// 2: polar plots of outlines; 3: shaded 3D bodies. Default: 2 when
        /// the family has 2D bodies, else 3.
        #[arg(long)]
        dim: Option<usize>,
        /// One panel's parameters, in RON, repeatable: --panel '(n: 3)'.
        #[arg(long, value_name = "RON")]
        panel: Vec<String>,
        /// One curve's parameters, in RON, repeatable: --curve '(aspect: 2.0)'.
        #[arg(long, value_name = "RON")]
        curve: Vec<String>,
        /// Shorthand for one --panel '(n: N)' per value, comma-separated.
        #[arg(long, value_delimiter = ',')]
        n: Vec<u32>,
        /// Shorthand for one --curve '(delta: Δ)' per value, comma-separated.
        #[arg(long, value_delimiter = ',')]
        delta: Vec<f64>,
        /// Shorthand for --panel '(modes: RON)', repeatable:
        /// --modes '[(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)]'.
        #[arg(long, value_name = "RON")]
        modes: Vec<String>,
        /// The picture to write: FILE.svg or FILE.png.
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
        /// Side in pixels of one panel.
        #[arg(long, value_name = "PIXELS", default_value_t = jamkit_draw::render::DEFAULT_PANEL_SIZE)]
        size: u32,
    },
}

fn load(file: &std::path::Path, sets: &[String]) -> Result<Experiment> {
    let experiment = Experiment::from_file(file)?;
    let experiment = overrides::apply(&experiment, sets)?;
    experiment.validate()?;
    Ok(experiment)
}

/// The files a run of `experiment` writes, for the closing line.
fn written(experiment: &Experiment) -> String {
    let mut files = vec!["results.csv", "summary.csv"];
    if let Some(s) = experiment.spectrum() {
        files.push("dos.csv");
        if s.eigenvalues || s.modes {
            files.push("eigenvalues/");
        }
    }
    if experiment.gaps().is_some() {
        files.push("gaps.csv");
    }
    files.push("packings/");
    files.join(", ")
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<()> {
    // `--version` names the commit too, as the files jamkit writes do.
    let version: &'static str = Box::leak(
        jamkit_format::provenance::describe()
            .trim_start_matches("jamkit ")
            .to_string()
            .into_boxed_str(),
    );
    let matches = Cli::command().version(version).get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    match cli.command {
        Command::Export { path, out } => {
            let files = packing_files(&path)?;
            let bytes = if out
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("gsd"))
            {
                let mut writer = jamkit_experiment::gsd::writer();
                for (k, f) in files.iter().enumerate() {
                    let file = jamkit_format::PackingFile::load_checked(f)?;
                    let frame = jamkit_experiment::gsd::frame(&file, k as u64)
                        .with_context(|| f.display().to_string())?;
                    writer.frame(frame)?;
                }
                writer.to_bytes()?
            } else {
                let mut text = String::new();
                for f in &files {
                    let file = jamkit_format::PackingFile::load_checked(f)?;
                    let frame = jamkit_experiment::extxyz::frame(&file)
                        .with_context(|| f.display().to_string())?;
                    text.push_str(&frame);
                }
                text.into_bytes()
            };
            jamkit_format::write_atomic(&out, &bytes)?;
            out!("{} frames in {}", files.len(), out.display());
            Ok(())
        }
        Command::Archive { dir, out } => {
            let report = jamkit_experiment::archive::archive(&dir, &out)?;
            out!(
                "{} packings archived in {} ({} in flight left out; {:.1} MB of packing files → {:.1} MB)",
                report.packings,
                out.display(),
                report.in_flight,
                report.bytes.0 as f64 / 1e6,
                report.bytes.1 as f64 / 1e6
            );
            Ok(())
        }
        Command::Merge { dirs, out } => {
            let report = jamkit_experiment::merge::merge(&dirs, &out)?;
            out!(
                "{} packings from {} parts ({} found in more than one, the same) in {}: results.csv, summary.csv, packings/",
                report.packings,
                dirs.len(),
                report.duplicates,
                out.display()
            );
            Ok(())
        }
        Command::Run {
            files,
            out,
            jobs,
            sets,
            shard,
            quiet,
            verbose,
        } => {
            if jobs == Some(0) {
                bail!("--jobs = 0: must be at least 1");
            }
            let shard = shard.as_deref().map(Shard::parse).transpose()?;
            // Check every file before running any.
            let experiments = files
                .iter()
                .map(|f| load(f, &sets))
                .collect::<Result<Vec<_>>>()?;
            let mut failed = 0;
            let mut reports = Vec::with_capacity(files.len());
            for (file, experiment) in files.iter().zip(&experiments) {
                if files.len() > 1 {
                    out!("\n== {} ==", file.display());
                }
                let out = out.clone().unwrap_or_else(|| default_out(experiment));
                let options = RunOptions {
                    out: out.clone(),
                    jobs,
                    log: Log::for_stderr(quiet, verbose),
                    shard,
                };
                let report = run(experiment, &options)
                    .with_context(|| format!("running {}", file.display()))?;
                print_table(&report);
                match shard {
                    Some(s) => out!(
                        "\nshard {}/{}: {} packings ({} reused from an earlier run) in {}/packings; run without --shard into {} to gather every part's packings into the tables",
                        s.index,
                        s.count,
                        report.packings.len(),
                        report.reused,
                        out.display(),
                        out.display()
                    ),
                    None if !report.elsewhere.is_empty() => out!(
                        "\n{} packings ({} reused from an earlier run) in {}; {} more are being made by other processes (their locks: {}/packings/*.lock), so no tables were written: rerun when they are done to gather them",
                        report.packings.len(),
                        report.reused,
                        out.display(),
                        report.elsewhere.len(),
                        out.display()
                    ),
                    None => out!(
                        "\n{} packings ({} reused from an earlier run) in {}: {}",
                        report.packings.len(),
                        report.reused,
                        out.display(),
                        written(experiment)
                    ),
                }
                for f in &report.failures {
                    eprintln!("error: {f}");
                }
                failed += report.failures.len();
                reports.push(report);
            }
            // Several files into one `--out`: each run's tables hold its own
            // packings, so the last would hide the others'. Gather them all.
            if let (Some(dir), true, None) = (&out, files.len() > 1, shard)
                && reports.iter().all(|r| r.elsewhere.is_empty())
            {
                let runs: Vec<_> = experiments.iter().zip(&reports).collect();
                let n = jamkit_experiment::runner::tables_of_runs(&runs, dir)?;
                out!(
                    "\n{n} packings of the {} files in {}: results.csv, summary.csv",
                    files.len(),
                    dir.display()
                );
            }
            if failed > 0 {
                bail!(
                    "{failed} samples failed (the others are saved; rerun to retry only the failed ones)"
                );
            }
            Ok(())
        }
        Command::Validate { file, sets } => {
            let experiment = load(&file, &sets)?;
            let plan = Plan::new(&experiment)?;
            out!(
                "{}: valid; {} point(s) × {} sample(s)",
                file.display(),
                plan.points.len(),
                experiment.samples
            );
            for p in &plan.points {
                out!("  {}", p.label(&experiment.family));
            }
            Ok(())
        }
        Command::Shapes { markdown: true } => {
            out!("{}", registry::reference_markdown().trim_end());
            Ok(())
        }
        Command::Shapes { markdown: false } => {
            for f in registry::FAMILIES {
                out!("{} ({}): {}", f.name, registry::describe_dims(f), f.about);
                if f.params.is_empty() {
                    out!("    (no parameters)");
                }
                for p in f.params {
                    let default = p
                        .default
                        .map(|d| format!(" [default {d}]"))
                        .unwrap_or_else(|| " [required]".into());
                    out!("    {}{}: {}", p.name, default, p.about);
                }
            }
            Ok(())
        }
        Command::Check {
            family,
            params,
            dim,
        } => check::run(&family, params.as_deref(), dim),
        Command::Bench { what } => bench::run(what),
        Command::Report {
            dirs,
            out,
            gamma,
            resamples,
            accuracy,
        } => {
            if let Some(study) = accuracy {
                let study = jamkit_report::accuracy::Study::parse(&study)?;
                let name = dirs
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect::<Vec<_>>()
                    .join("`, `");
                let md = jamkit_report::accuracy::report(study, &dirs, &out, &name)?;
                let path = out.join("accuracy.md");
                jamkit_format::write_atomic(&path, md.as_bytes())?;
                out!("{md}");
                out!("written: {}", path.display());
                return Ok(());
            }
            if !(gamma > 0.0 && gamma < 1.0) {
                bail!("--gamma = {gamma}: must lie in (0, 1)");
            }
            if resamples < 2 {
                bail!("--resamples = {resamples}: must be at least 2");
            }
            let options = jamkit_report::Options {
                gamma,
                resamples,
                ..Default::default()
            };
            let r = match jamkit_report::report(&dirs, &out, &options) {
                Err(jamkit_report::ReportError::NoData(_)) => {
                    // Not the paper's near-disks: the figures of any run.
                    let p = jamkit_report::runplot::plot(&dirs, &out)?;
                    out!(
                        "no near-disk (n, Δ) or near-sphere (l, Δ) packings (the paper's figures); drew the runs' own instead (jamkit plot): {} figures, {}",
                        p.figures.len(),
                        out.join("index.md").display()
                    );
                    return Ok(());
                }
                r => r?,
            };
            out!(
                "{} figures (PNG and SVG), {} fitted exponents: {}",
                r.figures.len(),
                r.fits.len(),
                out.join("report.md").display()
            );
            Ok(())
        }
        Command::Analyze {
            file,
            out,
            dim,
            r#box,
            observables,
        } => {
            let observables = jamkit_experiment::analyze::parse_observables(&observables)?;
            let options = jamkit_experiment::analyze::ReadOptions {
                dim,
                box_edges: r#box,
            };
            let packing = jamkit_experiment::analyze::read(&file, &options)?;
            let (packing, force, table) =
                jamkit_experiment::analyze::analyze(packing, &observables)?;
            packing.save(&out)?;
            if let Some(table) = table {
                jamkit_format::write_atomic(
                    &out.with_extension("eigenvalues.csv"),
                    table.as_bytes(),
                )?;
            }
            let m = &packing.measures;
            let opt = |x: Option<f64>| x.map_or("–".to_string(), |x| format!("{x:.6}"));
            out!(
                "{} spheres in {}D, φ = {:.6}, V/N = {:.3e}, largest force component {:.3e}",
                packing.particles,
                packing.dim,
                packing.phi,
                packing.energy_per_particle,
                force
            );
            out!(
                "contacts {}, rattlers {}, z = {}, iso margin {}, pressure {}",
                m.n_contacts.map_or("–".into(), |c| c.to_string()),
                m.n_rattlers.map_or("–".into(), |c| c.to_string()),
                opt(m.z_j),
                m.iso_margin.map_or("–".into(), |c| c.to_string()),
                m.pressure.map_or("–".to_string(), |p| format!("{p:.4e}"))
            );
            if let Some(s) = &m.spectrum {
                let params = &s.dos;
                out!(
                    "spectrum: {} coordinates, {} zero modes, ω₁ = {}, ω_* = {}",
                    s.coordinates,
                    s.zero_modes.total,
                    opt(s.histogram.omega_1()),
                    opt(s.histogram.omega_star(params))
                );
            }
            out!("written: {}", out.display());
            Ok(())
        }
        Command::Plot { dirs, out } => {
            let p = jamkit_report::runplot::plot(&dirs, &out)?;
            out!(
                "{} figures (PNG and SVG), scanned: {}: {}",
                p.figures.len(),
                if p.scanned.is_empty() {
                    "nothing".to_string()
                } else {
                    p.scanned.join(", ")
                },
                out.join("index.md").display()
            );
            Ok(())
        }
        Command::Spectrum {
            packing,
            stiffness_only,
            remove_rattlers,
            modes,
            out,
        } => {
            let options = jamkit_observe::hessian::HessianOptions {
                stiffness_only,
                remove_rattlers,
            };
            let (text, summary) = spectrum::of_file(&packing, options, modes)?;
            if out.as_os_str() == "-" {
                use std::io::Write;
                let _ = std::io::stdout().write_all(text.as_bytes());
            } else {
                jamkit_format::write_atomic(&out, text.as_bytes())?;
                out!(
                    "{}: {summary}; written to {}",
                    packing.display(),
                    out.display()
                );
            }
            Ok(())
        }
        Command::Draw {
            packing,
            out,
            size,
            cut,
        } => {
            let file = jamkit_draw::packing::read_file(&packing)?;
            if file.dim == 3 {
                let p = jamkit_draw::Packing3d::from_file(&file)?;
                let view = if cut {
                    jamkit_draw::scene3d::View::Cut
                } else {
                    jamkit_draw::scene3d::View::Whole
                };
                jamkit_draw::draw_packing_3d(&p, view, &out, size)?;
                let images = p
                    .primitives(view)
                    .iter()
                    .filter(|q| q.shift != [0, 0, 0])
                    .map(|q| q.image_id())
                    .collect::<std::collections::BTreeSet<_>>()
                    .len();
                out!(
                    "{}: {} {} bodies in 3D ({} periodic images, {} rattlers), seen along z, drawn to {}",
                    packing.display(),
                    p.bodies.len(),
                    p.family,
                    images,
                    p.bodies.iter().filter(|b| b.rattler).count(),
                    out.display()
                );
                return Ok(());
            }
            if cut {
                bail!(
                    "--cut: only for 3D packings (this one has dim = {})",
                    file.dim
                );
            }
            let p = jamkit_draw::Packing2d::from_file(&file)?;
            jamkit_draw::draw_packing(&p, &out, size)?;
            let images = p
                .pieces(jamkit_draw::render::POINTS_PER_BODY)
                .iter()
                .filter(|q| q.is_image())
                .count();
            out!(
                "{}: {} {} bodies ({} periodic image pieces, {} rattlers) drawn to {}",
                packing.display(),
                p.bodies.len(),
                p.family,
                images,
                p.bodies.iter().filter(|b| b.rattler).count(),
                out.display()
            );
            Ok(())
        }
        Command::DrawShape {
            family,
            dim,
            panel,
            curve,
            n,
            delta,
            modes,
            out,
            size,
        } => {
            let parse = |text: &str| jamkit_draw::shapes::parse_params(&family, text);
            let mut panels = panel
                .iter()
                .map(|p| parse(p))
                .collect::<Result<Vec<_>, _>>()?;
            for k in &n {
                panels.push(parse(&format!("(n: {k})"))?);
            }
            for m in &modes {
                panels.push(parse(&format!("(modes: {m})"))?);
            }
            let mut curves = curve
                .iter()
                .map(|c| parse(c))
                .collect::<Result<Vec<_>, _>>()?;
            for d in &delta {
                curves.push(parse(&format!("(delta: {d:?})"))?);
            }
            let info = registry::family_info(&family)?;
            let dim = dim.unwrap_or(if registry::supports_dim(&info, 2) {
                2
            } else {
                3
            });
            if !matches!(dim, 2 | 3) || !registry::supports_dim(&info, dim) {
                bail!(
                    "--dim = {dim}: family `{family}` is drawn in dim 2 or 3 where it exists ({:?})",
                    info.dims
                );
            }
            if dim == 3 {
                let panels = jamkit_draw::render3d::body_panels(&family, &panels, &curves)?;
                jamkit_draw::draw_bodies(&panels, &out, size)?;
                out!(
                    "{} row(s) of 3D bodies drawn to {}",
                    panels.len(),
                    out.display()
                );
                return Ok(());
            }
            let panels = jamkit_draw::shapes::panels(&family, &panels, &curves)?;
            jamkit_draw::draw_shapes(&panels, &out, size)?;
            out!("{} panel(s) drawn to {}", panels.len(), out.display());
            Ok(())
        }
    }
}

/// `x` to three decimals, or `-` when no packing had it (NaN: e.g. packing
/// files written before the measure existed).
fn three_places(x: f64) -> String {
    if x.is_nan() {
        "-".into()
    } else {
        format!("{x:.3}")
    }
}

fn print_table(report: &jamkit_experiment::runner::RunReport) {
    out!(
        "{:<40} {:>7} {:>22} {:>18} {:>7} {:>7} {:>10} {:>8} {:>8}",
        "point",
        "samples",
        "phi",
        "z",
        "z_iso",
        "z_corr",
        "rattlers",
        "iso_min",
        "flagged"
    );
    for s in &report.summaries {
        out!(
            "{:<40} {:>7} {:>13.6} ± {:<7.1e} {:>9.4} ± {:<6.1e} {:>7} {:>7} {:>9.2}% {:>8} {:>8}",
            s.label,
            s.samples,
            s.phi.0,
            s.phi.1,
            s.z_j.0,
            s.z_j.1,
            three_places(s.z_iso.0),
            three_places(s.z_corr.0),
            100.0 * s.rattler_fraction.0,
            s.iso_margin_min
                .map(|m| m.to_string())
                .unwrap_or_else(|| "-".into()),
            s.flagged
        );
    }
    out!(
        "phi, z: mean ± s.e.m. over the point's packings (z = z_J among non-rattlers); z_iso: the isostatic z of the non-rattlers' coordinates (2f); z_corr: z_J counting free rotations of rotational rattlers as missing contacts; iso_min: the smallest N_c − (f N_nr − d) (negative: hypostatic); flagged: packings with a warning (results.csv column flag). docs/reference/output-files.md, \"results.csv\"."
    );
}

/// The packing files `path` names: itself, or a run directory's packings
/// (in the grid order of its `experiment.ron` when it has one, else by
/// name).
fn packing_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let dir = path.join("packings");
    let ron = path.join("experiment.ron");
    if ron.exists() {
        let e = Experiment::from_file(&ron)?;
        let files: Vec<PathBuf> = Plan::new(&e)?
            .jobs
            .iter()
            .map(|j| dir.join(format!("{}.json", j.id)))
            .filter(|p| p.exists())
            .collect();
        if !files.is_empty() {
            return Ok(files);
        }
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| format!("{}: not a packing file nor a run directory", path.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|x| x == "json")
                && !p.to_string_lossy().ends_with(".failed.json")
        })
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("{}: no packings in {}", path.display(), dir.display());
    }
    Ok(files)
}
