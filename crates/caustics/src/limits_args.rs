//! The scene-loading limits (`caustics_scene::Limits`) as command-line flags, so a user
//! whose mesh is refused for its size can raise the limit the error names.

use caustics_scene::Limits;

/// `--max-*` flags of `run`, `reference` and `reproduce`; each defaults to
/// [`Limits::default`].
#[derive(Clone, Debug, Default, clap::Args)]
pub struct LimitArgs {
    /// Triangles in one mesh file (default 8,388,608).
    #[arg(long, value_name = "N")]
    pub max_mesh_triangles: Option<u64>,
    /// Vertices in one mesh file (default 8,388,608).
    #[arg(long, value_name = "N")]
    pub max_mesh_vertices: Option<u64>,
    /// Triangles of all mesh files of a scene (default 16,777,216).
    #[arg(long, value_name = "N")]
    pub max_scene_triangles: Option<u64>,
    /// Vertices of all mesh files of a scene (default 16,777,216).
    #[arg(long, value_name = "N")]
    pub max_scene_vertices: Option<u64>,
    /// Bytes of one mesh file, and of all buffers one glTF file uses (default 1 GiB).
    #[arg(long, value_name = "BYTES")]
    pub max_file_bytes: Option<u64>,
    /// Mesh objects of a scene (default 16,384).
    #[arg(long, value_name = "N")]
    pub max_mesh_objects: Option<u64>,
    /// Depth of a glTF node hierarchy (default 256).
    #[arg(long, value_name = "N")]
    pub max_node_depth: Option<u32>,
}

impl LimitArgs {
    /// The limits in force: the defaults, with each given flag in place.
    pub fn limits(&self) -> Limits {
        let d = Limits::default();
        Limits {
            max_mesh_triangles: self.max_mesh_triangles.unwrap_or(d.max_mesh_triangles),
            max_mesh_vertices: self.max_mesh_vertices.unwrap_or(d.max_mesh_vertices),
            max_scene_triangles: self.max_scene_triangles.unwrap_or(d.max_scene_triangles),
            max_scene_vertices: self.max_scene_vertices.unwrap_or(d.max_scene_vertices),
            max_file_bytes: self.max_file_bytes.unwrap_or(d.max_file_bytes),
            max_mesh_objects: self.max_mesh_objects.unwrap_or(d.max_mesh_objects),
            max_node_depth: self.max_node_depth.unwrap_or(d.max_node_depth),
        }
    }
}
