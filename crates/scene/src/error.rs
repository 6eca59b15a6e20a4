//! The error type of scene loading and validation.

use std::path::PathBuf;

/// Everything that can go wrong while resolving, reading, parsing or validating a scene.
///
/// Every variant names the scene file; the ones about a value also name its JSON path
/// (`objects[2].shape.radius`), so that a message points at the exact spot to fix.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A value in the scene file is of the wrong type, out of range or inconsistent.
    ///
    /// Displayed exactly as `{file}: {json_path}: {message}`, e.g.
    /// `scenes/x.json: objects[2].shape.radius: expected a positive number, got -1`.
    #[error("{}: {json_path}: {message}", file.display())]
    Invalid {
        /// The scene file (or the label given to [`crate::Scene::from_json_str`]).
        file: PathBuf,
        /// Where in the document: `camera.fov_y_deg`, `objects[0].shape.radius`, `(root)`.
        json_path: String,
        /// What was expected and what was found.
        message: String,
    },
    /// The scene file could not be read.
    #[error("{}: cannot read the scene file: {source}", file.display())]
    Io {
        /// The file that could not be read.
        file: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The file is not well-formed JSON (or a number in it does not fit a float).
    #[error("{}:{line}:{column}: invalid JSON at {json_path}: {message}", file.display())]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// The JSON path reached when parsing stopped (`(root)` at the top level).
        json_path: String,
        /// The parser's description of the problem.
        message: String,
    },
    /// A mesh referenced by the scene could not be loaded or is unusable.
    #[error("{}: {json_path}: cannot load mesh {}: {source}", file.display(), mesh_file.display())]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// The JSON path of the mesh reference (`objects[3].shape.path`).
        json_path: String,
        /// The mesh file, resolved against the scene file's folder.
        mesh_file: PathBuf,
        /// Why it could not be used: the element of the mesh file and what was expected.
        source: Box<crate::MeshError>,
    },
    /// [`crate::resolve`] got a name that is neither a built-in scene nor a scene file.
    #[error(
        "unknown scene `{name}`; {}",
        if available.is_empty() {
            format!(
                "no built-in scenes in {} (a binary run away from its checkout: run it from a checkout, or set {}=<checkout>)",
                dir.display(),
                crate::ROOT_ENV
            )
        } else {
            format!("built-in scenes ({}): {}", dir.display(), available.join(", "))
        }
    )]
    UnknownScene {
        /// The name that was asked for.
        name: String,
        /// The built-in scene names ([`crate::builtin_names`]).
        available: Vec<String>,
        /// Where they were looked for ([`crate::builtin_dir`]).
        dir: PathBuf,
    },
}
