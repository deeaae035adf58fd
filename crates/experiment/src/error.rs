//! Errors of the experiment layer: each names what the user can fix.

use thiserror::Error;

/// What can go wrong between an experiment file and the packings on disk.
#[derive(Debug, Error)]
pub enum ExperimentError {
    /// The file is not valid RON for the schema (unknown field, wrong type, …).
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A field has a value outside what is allowed.
    #[error("{field} = {value}: {allowed}")]
    Invalid {
        field: String,
        value: String,
        allowed: String,
    },
    /// A `--set` override could not be applied.
    #[error("--set {key}: {message}")]
    Override { key: String, message: String },
    /// Reading or writing a file failed. The cause is part of the message
    /// and not a separate `source`, so that a chain of errors printed whole
    /// (`{:#}`) names it once.
    #[error("{path}: {error}")]
    Io { path: String, error: std::io::Error },
    /// The output directory holds a packing of this run made with other
    /// settings (`lock` module): refused, so that one directory never
    /// mixes two experiments.
    #[error(
        "{file} was made with {key} = {there}, this run has {key} = {here}: refusing to mix \
         packings of different settings in one directory; use another --out, or remove that \
         directory's packings to make them again"
    )]
    SettingsDiffer {
        file: String,
        key: String,
        here: String,
        there: String,
    },
    /// `jamkit merge` cannot gather these parts.
    #[error("merge refused: {message}")]
    Merge { message: String },
    /// The engine failed on one sample, making it or measuring it.
    #[error(
        "sample {sample}: {}{source}{}",
        measuring_note(observable),
        saved_note(saved, kept)
    )]
    Sample {
        sample: String,
        #[source]
        source: Box<jamkit_core::Error>,
        /// The configuration the engine stopped at, when there is one to
        /// look at (a minimisation that did not converge); the runner
        /// saves it as `packings/<id>.failed.json` and sets `saved`.
        state: Option<Box<jamkit_format::PackingFile>>,
        /// Where `state` was saved.
        saved: Option<String>,
        /// The observable whose measurement failed (`Spectrum`, `Moduli`),
        /// when the packing was made and its measuring failed.
        observable: Option<String>,
        /// Where the packing stays without the observables that failed
        /// (`packings/<id>.json`): a rerun measures them on it without
        /// making it again.
        kept: Option<String>,
    },
}

fn measuring_note(observable: &Option<String>) -> String {
    observable
        .as_ref()
        .map(|o| format!("measuring {o}: "))
        .unwrap_or_default()
}

fn saved_note(saved: &Option<String>, kept: &Option<String>) -> String {
    let notes: Vec<String> = [
        saved
            .as_ref()
            .map(|p| format!("the configuration it stopped at is in {p}")),
        kept.as_ref().map(|p| {
            format!(
                "the packing is kept in {p} without the observables that failed; a rerun measures them on it without making it again"
            )
        }),
    ]
    .into_iter()
    .flatten()
    .collect();
    if notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", notes.join("; "))
    }
}

impl ExperimentError {
    /// Shorthand for [`ExperimentError::Invalid`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        allowed: impl Into<String>,
    ) -> Self {
        Self::Invalid {
            field: field.into(),
            value: jamkit_core::error::show_value(&value),
            allowed: allowed.into(),
        }
    }

    /// A sample's engine error, without a configuration to keep.
    pub fn sample(sample: impl Into<String>, source: jamkit_core::Error) -> Self {
        Self::Sample {
            sample: sample.into(),
            source: Box::new(source),
            state: None,
            saved: None,
            observable: None,
            kept: None,
        }
    }

    /// A sample's error while measuring `observable` on its packing.
    pub fn measuring(
        sample: impl Into<String>,
        observable: impl Into<String>,
        source: jamkit_core::Error,
    ) -> Self {
        Self::Sample {
            sample: sample.into(),
            source: Box::new(source),
            state: None,
            saved: None,
            observable: Some(observable.into()),
            kept: None,
        }
    }

    /// Wrap an I/O error with its path.
    pub fn io(path: impl AsRef<std::path::Path>, error: std::io::Error) -> Self {
        Self::Io {
            path: path.as_ref().display().to_string(),
            error,
        }
    }
}

impl From<jamkit_format::FormatError> for ExperimentError {
    fn from(e: jamkit_format::FormatError) -> Self {
        use jamkit_format::FormatError as F;
        match e {
            F::Parse { file, message } => Self::Parse { file, message },
            F::Invalid {
                field,
                value,
                allowed,
            } => Self::Invalid {
                field,
                value,
                allowed,
            },
            F::Io { path, error } => Self::Io { path, error },
        }
    }
}

impl From<jamkit_core::Error> for ExperimentError {
    fn from(e: jamkit_core::Error) -> Self {
        match e {
            jamkit_core::Error::InvalidParameter {
                field,
                value,
                allowed,
            } => Self::Invalid {
                field,
                value,
                allowed,
            },
            other => Self::Invalid {
                field: "experiment".into(),
                value: String::new(),
                allowed: other.to_string(),
            },
        }
    }
}
