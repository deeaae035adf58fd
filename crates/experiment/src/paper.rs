//! `paper_path: true`: the paper's path, one named setting.
//!
//! The paper runs FIRE (Bitzek et al.) all the way with the bodies' own
//! masses and no L-BFGS, stops a minimisation on `Σ (∂V/∂q)² < force_tol`
//! ([`FireParams::paper`]), and finds the jamming point by the plain
//! bisection (`search: Bisection`), and takes the end state of the
//! bisection as it is. jamkit's defaults differ in the Newton finish, the
//! family's masses and L-BFGS, the check of `Δt_max` against the stiffest
//! mode, the extrapolated search and the saddle escape
//! (docs/how-to/paper-protocol.md); `paper_path: true` sets those
//! fields to the paper's, so that the packings are the paper path's bit
//! for bit, the same as with each field set by hand.
//!
//! A field it sets that the file gives a value that is neither jamkit's
//! default nor the paper's, or that a `scan` varies, is refused, naming
//! it: the file would ask for two things at once.

use crate::error::ExperimentError;
use crate::schema::{Experiment, Protocol};
use jamkit_engine::{FireParams, JamSearch};

/// The minimiser fields the paper's path sets, by their `--set` path.
const MINIMIZER_FIELDS: [&str; 7] = [
    "minimizer.variant",
    "minimizer.force_tol_per_body",
    "minimizer.force_criterion",
    "minimizer.newton",
    "minimizer.masses",
    "minimizer.lbfgs",
    "minimizer.stable_dt",
];

/// Refuse a file whose `paper_path: true` contradicts one of its own
/// values or scans.
pub(crate) fn check(e: &Experiment) -> Result<(), ExperimentError> {
    if !e.paper_path {
        return Ok(());
    }
    let (m, default, paper) = (&e.minimizer, FireParams::default(), FireParams::paper());
    let either = [
        (
            m.variant == default.variant || m.variant == paper.variant,
            format!("{:?}", m.variant),
        ),
        (
            m.force_tol_per_body == default.force_tol_per_body
                || m.force_tol_per_body == paper.force_tol_per_body,
            m.force_tol_per_body.to_string(),
        ),
        (
            m.force_criterion == default.force_criterion
                || m.force_criterion == paper.force_criterion,
            format!("{:?}", m.force_criterion),
        ),
        (
            m.newton == default.newton || m.newton == paper.newton,
            format!("{:?}", m.newton),
        ),
        (
            m.masses == default.masses || m.masses == paper.masses,
            format!("{:?}", m.masses),
        ),
        (
            m.lbfgs == default.lbfgs || m.lbfgs == paper.lbfgs,
            format!("{:?}", m.lbfgs),
        ),
    ];
    // `stable_dt` is a bool: either value is the default's or the paper's,
    // so only a scan of it is refused (below).
    for (field, (allowed, value)) in MINIMIZER_FIELDS.iter().zip(either) {
        if !allowed {
            return Err(ExperimentError::invalid(
                *field,
                value,
                "paper_path: true runs the paper's minimiser (FIRE all the way, plain masses, no L-BFGS, Σ (∂V/∂q)²): leave this field out, or drop paper_path",
            ));
        }
    }
    if let Protocol::Jam { search, .. } | Protocol::AboveJam { search, .. } = &e.protocol
        && !matches!(search, JamSearch::Bisection)
        && *search != JamSearch::default()
    {
        return Err(ExperimentError::invalid(
            "protocol.search",
            format!("{search:?}"),
            "paper_path: true runs the paper's bisection: leave this field out, or drop paper_path",
        ));
    }
    for axis in &e.scan {
        for key in axis.keys() {
            if MINIMIZER_FIELDS.contains(&key.as_str())
                || key == "protocol.search"
                || key == "protocol.escape_saddles"
            {
                return Err(ExperimentError::invalid(
                    format!("scan.{key}"),
                    "(given)",
                    "paper_path: true sets this field to the paper's value: scan it without paper_path",
                ));
            }
        }
    }
    Ok(())
}

/// `e` on the paper's path when it asks for it (its minimiser's fields
/// above and its jamming search set to the paper's), else as it is.
pub(crate) fn apply(mut e: Experiment) -> Experiment {
    if !e.paper_path {
        return e;
    }
    let paper = FireParams::paper();
    let m = &mut e.minimizer;
    m.variant = paper.variant;
    m.force_tol_per_body = paper.force_tol_per_body;
    m.force_criterion = paper.force_criterion;
    m.newton = paper.newton;
    m.masses = paper.masses;
    m.lbfgs = paper.lbfgs;
    m.stable_dt = paper.stable_dt;
    if let Protocol::Jam { search, .. } | Protocol::AboveJam { search, .. } = &mut e.protocol {
        *search = JamSearch::Bisection;
    }
    if let Protocol::Jam { escape_saddles, .. } = &mut e.protocol {
        *escape_saddles = false;
    }
    e
}
