//! Errors of documents (JSON, validation, conversion into solver types).

use thiserror::Error;

/// What is wrong with a document or one of its parts. Every variant names the offending field
/// with a path such as `tasks[2].joint` or `posture.l_knee.rx`.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DocumentError {
    /// The text is not JSON at all.
    #[error("not valid JSON: {0}")]
    Json(String),
    /// A field is missing, has the wrong type, is not finite or makes no sense for the skeleton.
    #[error("{path}: {message}")]
    Field {
        /// Where, e.g. `tasks[2].target[0]`.
        path: String,
        /// What is wrong, e.g. `expected a number`.
        message: String,
    },
    /// A valid task that this build of the solver cannot run (e.g. the analytic limb task).
    #[error("{path}: {what} is not supported by this version of the solver")]
    Unsupported {
        /// Where, e.g. `tasks[3].kind`.
        path: String,
        /// What, e.g. `the limb task`.
        what: String,
    },
}

impl DocumentError {
    /// A field error at `path`.
    pub fn field(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Field {
            path: path.into(),
            message: message.into(),
        }
    }

    /// The path of the offending field.
    pub fn path(&self) -> &str {
        match self {
            Self::Json(_) => "",
            Self::Field { path, .. } | Self::Unsupported { path, .. } => path,
        }
    }

    /// Prefixes the path with `prefix` (`joint` inside `tasks[2]` becomes `tasks[2].joint`).
    pub fn within(self, prefix: &str) -> Self {
        let join = |path: String| {
            if path.is_empty() {
                prefix.to_owned()
            } else if prefix.is_empty() || path.starts_with('[') {
                format!("{prefix}{path}")
            } else {
                format!("{prefix}.{path}")
            }
        };
        match self {
            Self::Json(m) => Self::Json(m),
            Self::Field { path, message } => Self::Field {
                path: join(path),
                message,
            },
            Self::Unsupported { path, what } => Self::Unsupported {
                path: join(path),
                what,
            },
        }
    }
}
