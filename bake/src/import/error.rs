//! The one error type of the importers.
//!
//! Every message starts with the file (as the caller named it) and, where there is one, the
//! element at fault, so that a user can find the problem without a debugger:
//! `lucy.ply: face 1234: vertex index 99999 out of range (50000 vertices)`.

use std::io;

/// Why an import failed.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The file (or a file it refers to, such as a glTF buffer) could not be read.
    #[error("{file}: {what}: {source}")]
    Io {
        /// The file being imported.
        file: String,
        /// What was being read (`cannot read`, `buffer 0 ('scene.bin')`, ...).
        what: String,
        /// The operating-system error.
        #[source]
        source: io::Error,
    },

    /// The extension names no format this crate reads.
    #[error("{file}: unknown format {extension} (expected .gltf, .glb, .obj, .ply, .dem or .npy)")]
    UnknownFormat {
        /// The file being imported.
        file: String,
        /// The extension with its dot (`.stl`), or `(no extension)`.
        extension: String,
    },

    /// A structural error at a named place in the file.
    #[error("{file}: {at}: {message}")]
    Malformed {
        /// The file being imported.
        file: String,
        /// The element at fault: `line 17`, `face 12`, `accessor 3 (POSITION of mesh 'Helmet'
        /// primitive 0)`, `header`, ...
        at: String,
        /// What is wrong there.
        message: String,
    },

    /// An index that points past the end of what it indexes.
    #[error("{file}: {at}: {what} {index} out of range ({count} {of})")]
    IndexOutOfRange {
        /// The file being imported.
        file: String,
        /// The element holding the index (`face 1234`, `line 17`, ...).
        at: String,
        /// What the index is (`vertex index`, `texture coordinate index`, ...).
        what: &'static str,
        /// The offending index, as written in the file (OBJ indices are 1-based and may be
        /// negative).
        index: i64,
        /// How many there are.
        count: usize,
        /// What there are `count` of (`vertices`, `positions`, ...).
        of: &'static str,
    },

    /// A NaN or infinite number where a coordinate or attribute must be finite.
    #[error("{file}: {at}: {what} is {value}")]
    NonFinite {
        /// The file being imported.
        file: String,
        /// The element (`vertex 12`, `line 40`, ...).
        at: String,
        /// Which number (`coordinate`, `normal`, `x`, ...).
        what: String,
        /// `NaN`, `inf` or `-inf`.
        value: f64,
    },

    /// The file ends before the data its header promises.
    #[error("{file}: truncated: {detail}")]
    Truncated {
        /// The file being imported.
        file: String,
        /// What was missing.
        detail: String,
    },

    /// Valid input that uses a feature this importer does not support.
    #[error("{file}: {at}: unsupported: {message}")]
    Unsupported {
        /// The file being imported.
        file: String,
        /// The element using the feature.
        at: String,
        /// The feature.
        message: String,
    },

    /// An option the format needs was not given.
    #[error("{file}: {message}")]
    MissingOption {
        /// The file being imported.
        file: String,
        /// Which option and why.
        message: String,
    },

    /// The format's importer is not compiled in (its cargo feature is off).
    #[error("{file}: {format} files need caveclod-bake's `{feature}` feature, which this build leaves out")]
    FormatDisabled {
        /// The file being imported.
        file: String,
        /// The format, as its extension.
        format: String,
        /// The cargo feature that enables it.
        feature: &'static str,
    },

    /// The file was read but contains no triangle.
    #[error("{file}: no triangles{detail}")]
    Empty {
        /// The file being imported.
        file: String,
        /// Extra context, starting with `: ` when present.
        detail: String,
    },

    /// A bug in an importer (it produced an inconsistent mesh or panicked). Never expected.
    #[error("{file}: internal importer error (please report): {message}")]
    Internal {
        /// The file being imported.
        file: String,
        /// What went wrong.
        message: String,
    },
}

impl ImportError {
    /// The file the error is about, as the caller named it.
    pub fn file(&self) -> &str {
        match self {
            ImportError::Io { file, .. }
            | ImportError::UnknownFormat { file, .. }
            | ImportError::Malformed { file, .. }
            | ImportError::IndexOutOfRange { file, .. }
            | ImportError::NonFinite { file, .. }
            | ImportError::Truncated { file, .. }
            | ImportError::Unsupported { file, .. }
            | ImportError::MissingOption { file, .. }
            | ImportError::FormatDisabled { file, .. }
            | ImportError::Empty { file, .. }
            | ImportError::Internal { file, .. } => file,
        }
    }
}

/// The file an importer is reading: builds errors that name it.
#[derive(Clone, Debug)]
pub(crate) struct Source {
    /// The path as the caller wrote it.
    pub name: String,
}

impl Source {
    pub fn new(path: &std::path::Path) -> Self {
        Source {
            name: path.display().to_string(),
        }
    }

    pub fn io(&self, what: impl Into<String>, source: io::Error) -> ImportError {
        ImportError::Io {
            file: self.name.clone(),
            what: what.into(),
            source,
        }
    }

    pub fn malformed(&self, at: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::Malformed {
            file: self.name.clone(),
            at: at.into(),
            message: message.into(),
        }
    }

    pub fn out_of_range(
        &self,
        at: impl Into<String>,
        what: &'static str,
        index: i64,
        count: usize,
        of: &'static str,
    ) -> ImportError {
        ImportError::IndexOutOfRange {
            file: self.name.clone(),
            at: at.into(),
            what,
            index,
            count,
            of,
        }
    }

    pub fn non_finite(
        &self,
        at: impl Into<String>,
        what: impl Into<String>,
        value: f64,
    ) -> ImportError {
        ImportError::NonFinite {
            file: self.name.clone(),
            at: at.into(),
            what: what.into(),
            value,
        }
    }

    pub fn truncated(&self, detail: impl Into<String>) -> ImportError {
        ImportError::Truncated {
            file: self.name.clone(),
            detail: detail.into(),
        }
    }

    pub fn unsupported(&self, at: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::Unsupported {
            file: self.name.clone(),
            at: at.into(),
            message: message.into(),
        }
    }

    /// `Err` naming the first non-finite component of `values`, labelled by `names`.
    pub fn check_finite<const N: usize>(
        &self,
        values: &[f32; N],
        names: &[&str; N],
        at: impl FnOnce() -> String,
    ) -> Result<(), ImportError> {
        match values.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(i) => Err(self.non_finite(at(), names[i], f64::from(values[i]))),
        }
    }
}
