//! Error type of the whole crate.
//!
//! Every variant carries the context a user needs to find the problem in their own input:
//! the file, line and section of a mesh, the group or element id, the material key. The
//! binary maps each variant to a documented exit code (see [`Error::exit_code`]).

use std::path::PathBuf;

/// Result alias used across the crate.
pub type Result<T> = std::result::Result<T, Error>;

/// All errors vibrofem reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A mesh file is malformed or truncated.
    #[error("{path}: {section}{}: {msg}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    MeshParse {
        /// The mesh file.
        path: PathBuf,
        /// The section being read (`$Nodes`, `$Elements`, ...).
        section: String,
        /// 1-based line number where known (ASCII files).
        line: Option<usize>,
        /// What is wrong.
        msg: String,
    },
    /// A gmsh element type that vibrofem does not support.
    #[error("{path}: unsupported gmsh element type {gmsh_type} ({name}) in {group}")]
    UnsupportedElement {
        /// The mesh file.
        path: PathBuf,
        /// gmsh element type id.
        gmsh_type: i32,
        /// gmsh's name for it, when known.
        name: String,
        /// Physical group (or entity) the element belongs to.
        group: String,
    },
    /// A group named on the command line or in a scene does not exist in the mesh.
    #[error("unknown group '{name}' (the mesh has: {available})")]
    UnknownGroup {
        /// The requested name.
        name: String,
        /// Comma-separated list of the groups that exist.
        available: String,
    },
    /// An element whose Jacobian determinant is zero or negative at an integration point.
    #[error("element {element} ({kind}) has a non-positive Jacobian determinant {det:.3e}: inverted or degenerate")]
    InvertedElement {
        /// gmsh element tag.
        element: u64,
        /// Cell kind name.
        kind: &'static str,
        /// The offending determinant.
        det: f64,
    },
    /// A material with invalid constants.
    #[error("invalid material {name}: {msg}")]
    InvalidMaterial {
        /// Material name or the group it is assigned to.
        name: String,
        /// What is wrong.
        msg: String,
    },
    /// The model has no element the analysis can use.
    #[error("{what}")]
    EmptyModel {
        /// Description, naming the file.
        what: String,
    },
    /// An error in an input file at a known place (a scene, design or study file): the file,
    /// the line and the key where known.
    #[error("{}{msg}", input_prefix(file, *line, key.as_deref()))]
    Input {
        /// The file.
        file: String,
        /// 1-based line number.
        line: Option<usize>,
        /// The key (dotted path), when the error concerns one.
        key: Option<String>,
        /// What is wrong.
        msg: String,
    },
    /// Any other invalid user input (option, value, combination).
    #[error("{0}")]
    InvalidInput(String),
    /// A result could not be written or serialised (not the user's input: a full disk, a
    /// closed output).
    #[error("cannot write {what}: {msg}")]
    Output {
        /// The file or stream.
        what: String,
        /// Why.
        msg: String,
    },
    /// An external engine (SLEPc under MPI) is not installed, or it failed.
    #[error("{engine}: {msg}")]
    Engine {
        /// The engine (e.g. `SLEPc engine`).
        engine: String,
        /// What is missing or what went wrong, with the remedy.
        msg: String,
    },
    /// The eigen solver did not converge.
    #[error("eigen solve did not converge: {0}")]
    EigenNotConverged(String),
    /// The verification of an eigen solution failed (a mode missed, or accuracy lost).
    #[error("eigen solution failed verification: {0}")]
    Verification(String),
    /// A sparse factorisation failed (singular or indefinite where it must not be).
    #[error("factorization failed: {0}")]
    Factorization(String),
    /// A factorisation met a zero or non-finite pivot: the matrix is singular at that equation.
    /// `at` names it in the user's terms (node and component) once the model layer has located
    /// it ([`Error::locate`]).
    #[error("factorization failed: {msg}{}", at.as_ref().map(|a| format!(" (at {a})")).unwrap_or_default())]
    Singular {
        /// The equation (free-DOF index, unpermuted) of the pivot, when known.
        equation: Option<usize>,
        /// Node and component, filled by [`Error::locate`].
        at: Option<String>,
        /// What happened.
        msg: String,
    },
}

/// `file, line L, key 'k': ` with the parts that are known (nothing when none is).
fn input_prefix(file: &str, line: Option<usize>, key: Option<&str>) -> String {
    let mut parts = Vec::new();
    if !file.is_empty() {
        parts.push(file.to_string());
    }
    if let Some(l) = line {
        parts.push(format!("line {l}"));
    }
    if let Some(k) = key {
        parts.push(format!("key '{k}'"));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!("{}: ", parts.join(", "))
    }
}

impl Error {
    /// Process exit code for this error: 1 for bad input, 2 for a numerical failure.
    ///
    /// | code | meaning |
    /// |---|---|
    /// | 0 | success |
    /// | 1 | input error (file, mesh, option, material, group) |
    /// | 2 | numerical failure (no convergence, failed verification, singular model) |
    /// | 3 | batch run in which some cases failed |
    /// | 4 | a result could not be written (disk full, serialisation) |
    /// | 5 | an external engine (SLEPc, MPI) is missing or failed |
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Io { .. }
            | Error::MeshParse { .. }
            | Error::UnsupportedElement { .. }
            | Error::UnknownGroup { .. }
            | Error::InvertedElement { .. }
            | Error::InvalidMaterial { .. }
            | Error::EmptyModel { .. }
            | Error::Input { .. }
            | Error::InvalidInput(_) => 1,
            Error::EigenNotConverged(_) | Error::Verification(_) | Error::Factorization(_) | Error::Singular { .. } => {
                2
            }
            Error::Output { .. } => 4,
            Error::Engine { .. } => 5,
        }
    }

    /// An allocation of `bytes` for `what` failed: a model too large for the memory this
    /// process may use (an input error, exit 1, like a refusal by the memory estimate).
    pub fn out_of_memory(what: &str, bytes: u64) -> Self {
        Error::InvalidInput(format!(
            "cannot allocate {} for {what}: not enough memory for this model (a coarser mesh, or \
             more memory: --max-memory, ulimit -v and cgroup limits are honoured)",
            crate::io::fmt_bytes(bytes)
        ))
    }

    /// Name the equation of a [`Error::Singular`] in the user's terms with `describe` (an
    /// equation → "node 1234 uz" map, e.g. [`crate::system::System::describe_equation`]);
    /// other errors pass through.
    pub fn locate(self, describe: impl Fn(usize) -> String) -> Self {
        match self {
            Error::Singular {
                equation: Some(eq),
                at: None,
                msg,
            } => Error::Singular {
                equation: Some(eq),
                at: Some(describe(eq)),
                msg,
            },
            e => e,
        }
    }

    /// A serialisation or write failure of `what` (a file, or stdout).
    pub fn output(what: impl std::fmt::Display, e: impl std::fmt::Display) -> Self {
        Error::Output {
            what: what.to_string(),
            msg: e.to_string(),
        }
    }

    /// Shorthand for an [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
