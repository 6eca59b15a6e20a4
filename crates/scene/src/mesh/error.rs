//! Why a mesh file was refused.

use std::path::PathBuf;

/// A mesh file (or a buffer it names) that cannot be used.
///
/// Every variant names the element at fault (an OBJ line, a vertex, a glTF accessor,
/// buffer, node or primitive) and what was expected; the mesh file itself is named by
/// the [`crate::SceneError::Mesh`] that wraps it, beside the JSON path that named it.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file does not exist or is not a regular file.
    #[error("the file does not exist")]
    Missing,
    /// A file (the mesh, or a buffer a glTF file names) could not be read.
    #[error("cannot read {}: {source}", file.display())]
    Io {
        /// The file that could not be read.
        file: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A count (triangles, vertices, bytes, objects, node depth) is over its limit.
    #[error("{what}: {count}, more than the limit of {limit} ({})", raise_hint(.field))]
    Limit {
        /// What was counted, with the element it belongs to.
        what: String,
        /// The count found (or reached when loading stopped).
        count: u64,
        /// The limit in force.
        limit: u64,
        /// The [`crate::Limits`] field that sets it.
        field: &'static str,
    },
    /// An element of the file is malformed, out of range or inconsistent.
    ///
    /// Displayed as `{element}: {problem}`, e.g.
    /// `line 4: vertex index 9 out of range: expected 1..=3 or -3..=-1`.
    #[error("{element}: {problem}")]
    Invalid {
        /// Where: `line 12`, `vertex 3 of model "ring"`, `accessor 2 (POSITION of mesh 0
        /// primitive 1)`, `buffer 0`, `node 5`.
        element: String,
        /// What was expected and what was found.
        problem: String,
    },
    /// The file could not be parsed by the OBJ or glTF reader.
    #[error("not a valid {format} file: {message}")]
    Parse {
        /// `OBJ`, `glTF` or `GLB`.
        format: &'static str,
        /// The reader's description.
        message: String,
    },
    /// A glTF node is listed among its own descendants.
    #[error("node {node} is listed among its own descendants (children {}); expected a tree", fmt_cycle(.cycle))]
    NodeCycle {
        /// The node reached twice.
        node: usize,
        /// The chain of nodes from `node` back to itself.
        cycle: Vec<usize>,
    },
    /// Nothing is left to render.
    #[error("{element} has no triangles{}", if *.degenerate > 0 { format!(" ({} degenerate or zero-area faces dropped)", .degenerate) } else { String::new() })]
    Empty {
        /// The mesh, model or primitive.
        element: String,
        /// Faces dropped as degenerate before it was found empty.
        degenerate: usize,
    },
    /// The extension is not one of the supported formats.
    #[error("unsupported mesh format `.{0}`; expected .obj, .gltf or .glb")]
    Format(String),
}

fn fmt_cycle(cycle: &[usize]) -> String {
    let parts: Vec<String> = cycle.iter().map(ToString::to_string).collect();
    parts.join(" -> ")
}

/// Shorthand for [`MeshError::Invalid`].
pub(crate) fn invalid(element: impl Into<String>, problem: impl Into<String>) -> MeshError {
    MeshError::Invalid {
        element: element.into(),
        problem: problem.into(),
    }
}

/// How a user raises the limit `field` (a [`crate::Limits`] field name, possibly
/// followed by why it cannot be raised).
fn raise_hint(field: &str) -> String {
    if field.contains(' ') {
        return format!("Limits::{field}");
    }
    format!(
        "raise it with --{} on caustics run or caustics reference, or Limits::{field} through Scene::load_with_limits",
        field.replace('_', "-")
    )
}
