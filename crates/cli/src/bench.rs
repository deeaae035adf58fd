//! `jamkit bench`: timings of the engine, for docs/reports/performance.md,
//! and the speed-against-error study of docs/reports/speed-vs-error.md.
//! Each subcommand's flags and work are in `jamkit_bench`.

use jamkit_bench::{accuracy, eval, packing, pair, spectrum};

#[derive(clap::Subcommand)]
pub enum BenchCommand {
    /// Time whole jammed packings (paper's protocol, one thread).
    Packing(packing::Options),
    /// Time one energy+gradient evaluation of binary disks at phi = 0.84.
    Eval(eval::Options),
    /// Speed against error of the near-disk gap models and of FIRE's
    /// tolerances: CSV, figures and tables.md (docs/reports/speed-vs-error.md).
    Accuracy(accuracy::Options),
    /// Time and error of one pair evaluation (gap and gradient) of the
    /// near-disk gap models: pairs.csv, slopes.csv, figures and pairs.md
    /// (the pair benchmark of `bench accuracy`, on its own).
    Pair(pair::Options),
    /// Time Hessian assembly and eigenvalues of near-disks (n = 2, Δ = 0.1).
    Spectrum(spectrum::Options),
}

pub fn run(what: BenchCommand) -> anyhow::Result<()> {
    let print = &mut |line: &str| out!("{line}");
    match what {
        BenchCommand::Packing(o) => packing::run(&o, print),
        BenchCommand::Eval(o) => eval::run(&o, print),
        BenchCommand::Accuracy(o) => accuracy::run(&o, print),
        BenchCommand::Pair(o) => pair::run(&o, print),
        BenchCommand::Spectrum(o) => spectrum::run(&o, print),
    }
}
