//! Error type of the whole crate.
//!
//! Every variant carries the context a user needs to find the problem in their own input:
//! the file, line and section of a mesh, the group or element id, the material key. The
//! binary maps each variant to a documented exit code (see [`Error::exit_code`]).

use std::path::PathBuf;

/// Result alias used across the crate.
pub type Result<T> = std::result::Result<T, Error>;

/// The words that make a memory refusal's message, shared by the constructors of those
/// errors and [`Error::is_memory_refusal`] (they stay `InvalidInput`, exit 1).
pub(crate) const MEMORY_REFUSALS: [&str; 3] = [
    "the model needs at least",
    "the factorisation needs about",
    "cannot allocate",
];

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
    #[error(
        "{}element {element} ({kind}) has a non-positive Jacobian determinant {det:.3e}: {}",
        file.as_ref().map(|f| format!("{f}: ")).unwrap_or_default(),
        if det.is_finite() { "inverted or degenerate" } else { "its coordinates are beyond double precision (check their units)" }
    )]
    InvertedElement {
        /// gmsh element tag.
        element: u64,
        /// Cell kind name.
        kind: &'static str,
        /// The offending determinant.
        det: f64,
        /// The mesh (file or generator) it is in, once known ([`Error::in_source`]).
        file: Option<String>,
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
    /// Invalid user input at a place named as data ([`At`]): a command-line option, a
    /// parameter of a library call, a group, an element, a node or a DOF. The message is shown
    /// as written (it names the place in words too); `at` lets a program (the JSON error
    /// record, the Python package) tell where without parsing the text.
    #[error("{msg}")]
    Invalid {
        /// Where the bad value is.
        at: At,
        /// What is wrong.
        msg: String,
    },
    /// Any other invalid user input (a combination of options with no single place).
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
    /// The verification of a result failed (a mode missed, or accuracy lost).
    #[error("verification failed: {0}")]
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

/// Where an [`Error::Invalid`] input is: the place a user looks to fix it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum At {
    /// A command-line option (`--freq`) or a keyword argument of the Python package.
    Option {
        /// The option as the user spelled it.
        name: String,
    },
    /// A parameter of a library call or a field of an options struct (`ModalParams::n_modes`).
    Param {
        /// The parameter's name.
        name: String,
    },
    /// A key of an input file (scene, design, machine case) or a column of a CSV file.
    Key {
        /// The file, as given.
        file: String,
        /// 1-based line, where known.
        line: Option<usize>,
        /// The key (dotted path) or column name.
        key: String,
    },
    /// A mesh group (physical name).
    Group {
        /// The group's name.
        name: String,
    },
    /// A mesh element by its gmsh tag.
    Element {
        /// gmsh element tag.
        tag: u64,
    },
    /// A mesh node by its gmsh tag.
    Node {
        /// gmsh node tag.
        tag: u64,
    },
    /// A degree of freedom: a node's component.
    Dof {
        /// gmsh node tag.
        node: u64,
        /// Component name (`ux`, `ry`, ...).
        component: String,
    },
}

impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            At::Option { name } => write!(f, "option {name}"),
            At::Param { name } => write!(f, "parameter {name}"),
            At::Key { file, line, key } => write!(f, "{}key '{key}'", input_prefix(file, *line, None)),
            At::Group { name } => write!(f, "group '{name}'"),
            At::Element { tag } => write!(f, "element {tag}"),
            At::Node { tag } => write!(f, "node {tag}"),
            At::Dof { node, component } => write!(f, "node {node} {component}"),
        }
    }
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
            | Error::Invalid { .. }
            | Error::InvalidInput(_) => 1,
            Error::EigenNotConverged(_) | Error::Verification(_) | Error::Factorization(_) | Error::Singular { .. } => {
                2
            }
            Error::Output { .. } => 4,
            Error::Engine { .. } => 5,
        }
    }

    /// This error with `prefix: ` before its message (which case of a study it is), keeping its
    /// class: a numerical failure stays one (exit 2), a write or an engine failure stays as it
    /// is; any other becomes an input error naming the case.
    pub fn with_prefix(self, prefix: &str) -> Self {
        match self {
            Error::EigenNotConverged(m) => Error::EigenNotConverged(format!("{prefix}: {m}")),
            Error::Verification(m) => Error::Verification(format!("{prefix}: {m}")),
            Error::Factorization(m) => Error::Factorization(format!("{prefix}: {m}")),
            e @ Error::Singular { .. } => {
                let s = e.to_string();
                Error::Factorization(format!(
                    "{prefix}: {}",
                    s.strip_prefix("factorization failed: ").unwrap_or(&s)
                ))
            }
            e @ (Error::Output { .. } | Error::Engine { .. }) => e,
            e => Error::InvalidInput(format!("{prefix}: {e}")),
        }
    }

    /// An allocation of `bytes` for `what` failed: a model too large for the memory this
    /// process may use (an input error, exit 1, like a refusal by the memory estimate).
    pub fn out_of_memory(what: &str, bytes: u64) -> Self {
        Error::InvalidInput(format!(
            "{} {} for {what}: not enough memory for this model (a coarser mesh, or \
             more memory: --max-memory, ulimit -v and cgroup limits are honoured)",
            MEMORY_REFUSALS[2],
            crate::util::fmt::fmt_bytes(bytes)
        ))
    }

    /// Whether this is a refusal for memory: the model's estimate before assembly, the
    /// factorisation's after the ordering ([`crate::system`]) or an allocation that failed
    /// ([`Error::out_of_memory`]). `modes --solver auto` answers these with the low-memory path.
    pub fn is_memory_refusal(&self) -> bool {
        matches!(self, Error::InvalidInput(m) if MEMORY_REFUSALS.iter().any(|k| m.contains(k)))
    }

    /// An inverted element's error naming the mesh `source` it is in (the element sets know
    /// only the element's tag).
    pub fn in_source(self, source: &str) -> Self {
        match self {
            Error::InvertedElement {
                element,
                kind,
                det,
                file: None,
            } => Error::InvertedElement {
                element,
                kind,
                det,
                file: Some(source.to_string()),
            },
            e => e,
        }
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

    /// A bad value of the command-line option (or Python keyword) `name`.
    pub fn option(name: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Option { name: name.into() },
            msg: msg.into(),
        }
    }

    /// A bad value of the library parameter (or options-struct field) `name`.
    pub fn param(name: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Param { name: name.into() },
            msg: msg.into(),
        }
    }

    /// A bad value at `key` of the input file `file` (line where known). Shown with the
    /// `file, line L, key 'k': ` prefix, like [`Error::Input`].
    pub fn key(file: impl Into<String>, line: Option<usize>, key: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Input {
            file: file.into(),
            line,
            key: Some(key.into()),
            msg: msg.into(),
        }
    }

    /// A problem with the mesh group `name`.
    pub fn group(name: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Group { name: name.into() },
            msg: msg.into(),
        }
    }

    /// A problem with the element of gmsh tag `tag`.
    pub fn element(tag: u64, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Element { tag },
            msg: msg.into(),
        }
    }

    /// A problem with the node of gmsh tag `tag`.
    pub fn node(tag: u64, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Node { tag },
            msg: msg.into(),
        }
    }

    /// A problem with one DOF (node `node`, component `component`).
    pub fn dof(node: u64, component: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Invalid {
            at: At::Dof {
                node,
                component: component.into(),
            },
            msg: msg.into(),
        }
    }

    /// Where the bad input is, when the error names a place as data.
    pub fn at(&self) -> Option<At> {
        match self {
            Error::Invalid { at, .. } => Some(at.clone()),
            Error::Input { file, line, key, .. } => Some(At::Key {
                file: file.clone(),
                line: *line,
                key: key.clone().unwrap_or_default(),
            }),
            Error::UnknownGroup { name, .. } => Some(At::Group { name: name.clone() }),
            Error::InvertedElement { element, .. } => Some(At::Element { tag: *element }),
            _ => None,
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
