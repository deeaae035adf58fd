//! `jamkit spectrum`: the eigenvalues of a saved packing's Hessian.

use anyhow::{Context, Result};
use jamkit_core::Shape;
use jamkit_engine::Scene;
use jamkit_experiment::reload::{PackingVisitor, reload};
use jamkit_format::PackingFile;
use jamkit_observe::hessian::HessianOptions;
use jamkit_observe::spectrum::{self, DosParams};
use std::path::Path;

/// The table to write (eigenvalues one per line, or with `modes` a CSV of
/// `lambda,omega,participation,rotational_share`) and a one-line summary.
pub fn of_file(path: &Path, options: HessianOptions, modes: bool) -> Result<(String, String)> {
    let file = PackingFile::load_checked(path)?;
    let rattler = file.rattler.clone();
    let visitor = Visit {
        rattler,
        options,
        modes,
    };
    let s = reload(&file, visitor)
        .with_context(|| path.display().to_string())?
        .with_context(|| format!("spectrum of {}", path.display()))?;
    let text = if modes {
        jamkit_experiment::sample::eigenvalue_table(&s)
    } else {
        s.eigenvalues.iter().map(|l| format!("{l:e}\n")).collect()
    };
    let summary = format!(
        "{} eigenvalues, {} zero modes (ω ≤ {:e}: {} translations, {} of rattlers, {} extra)",
        s.eigenvalues.len(),
        s.zero.total,
        DosParams::default().omega_zero,
        s.zero.translations,
        s.zero.rattlers,
        s.zero.extra
    );
    Ok((text, summary))
}

struct Visit {
    rattler: Vec<bool>,
    options: HessianOptions,
    modes: bool,
}

impl PackingVisitor for Visit {
    type Output = jamkit_core::Result<spectrum::Spectrum>;
    fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
        spectrum::measure(
            &mut scene,
            &self.rattler,
            self.options,
            self.modes,
            &DosParams::default(),
        )
    }
}
