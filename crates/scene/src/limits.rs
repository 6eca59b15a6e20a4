//! What a scene may hold: the bounds every mesh is checked against before use.

/// Largest |coordinate| (metres) of any vertex after the object's transform.
///
/// Why 10⁶ m: the reference's BVH (SAH costs on box areas ~ x², PLOC over the scene
/// box) and its ray-triangle tests (triple products ~ x³), the area-weighted normals
/// (squared cross-product lengths ~ x⁴ = 10²⁴) and the GPU's f32 vertex math all stay
/// far below f32's 3.4·10³⁸ there; at 10²⁰ the box areas overflow to ∞, the BVH costs
/// become NaN and the BVH build panics. At 10⁶ m an f32 ulp is 6 cm, so geometry
/// beyond it is not resolvable anyway. Scenes are metres across (see the reference's
/// epsilon policy). This bound is not adjustable.
pub const MAX_COORDINATE: f32 = 1.0e6;

/// Resource limits of scene loading, checked before any large allocation.
///
/// [`crate::Scene::load`] uses [`Limits::default`]; raise a limit with
/// [`crate::Scene::load_with_limits`] (e.g. `Limits { max_scene_triangles: 1 << 26,
/// ..Limits::default() }`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Triangles in one mesh file (all its models or primitives together). Default
    /// 8 Mi (8,388,608).
    pub max_mesh_triangles: u64,
    /// Vertices in one mesh file. Default 8 Mi.
    pub max_mesh_vertices: u64,
    /// Triangles of all mesh files of a scene. Default 16 Mi: about 4 GB in the
    /// reference's BVH (~250 B per triangle with its normals and build memory) and
    /// 400 MB of GPU vertex and index buffers.
    pub max_scene_triangles: u64,
    /// Vertices of all mesh files of a scene. Default 16 Mi.
    pub max_scene_vertices: u64,
    /// Bytes of one mesh file, and separately of all the buffers a glTF file uses
    /// (external files and decoded `data:` URIs). Default 1 GiB.
    pub max_file_bytes: u64,
    /// Mesh objects (glTF primitives placed by nodes, one per OBJ file) of a scene.
    /// Default 16,384.
    pub max_mesh_objects: u64,
    /// Depth of a glTF node hierarchy (a scene's root nodes are at depth 1). Default 256.
    pub max_node_depth: u32,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_mesh_triangles: 1 << 23,
            max_mesh_vertices: 1 << 23,
            max_scene_triangles: 1 << 24,
            max_scene_vertices: 1 << 24,
            max_file_bytes: 1 << 30,
            max_mesh_objects: 16_384,
            max_node_depth: 256,
        }
    }
}

/// A memory budget given in an environment variable as a whole number of MiB (the
/// GPU's and the CPU reference's budgets are read this way): `None` where the text is
/// not a positive whole number or overflows bytes.
pub fn parse_mib(text: &str) -> Option<u64> {
    let mib: u64 = text.trim().parse().ok()?;
    (mib > 0).then(|| mib.checked_mul(1 << 20)).flatten()
}

/// `bytes` as a reader wants it: "1.06 GiB (1,140,850,688 bytes)".
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    let mut grouped = String::new();
    for (i, c) in bytes.to_string().chars().rev().enumerate() {
        if i > 0 && i % 3 == 0 {
            grouped.push(',');
        }
        grouped.push(c);
    }
    let grouped: String = grouped.chars().rev().collect();
    let mut value = bytes as f64;
    let mut unit = None;
    for u in UNITS {
        if value < 1024.0 {
            break;
        }
        value /= 1024.0;
        unit = Some(u);
    }
    match unit {
        None => format!("{grouped} bytes"),
        Some(u) => format!("{value:.2} {u} ({grouped} bytes)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_are_whole_mib_and_bytes_read_as_people_write_them() {
        assert_eq!(parse_mib("512"), Some(512 << 20));
        assert_eq!(parse_mib(" 1 "), Some(1 << 20));
        for bad in ["0", "-1", "1.5", "", "lots", "18446744073709551615"] {
            assert_eq!(parse_mib(bad), None, "{bad:?}");
        }
        assert_eq!(format_bytes(999), "999 bytes");
        assert_eq!(format_bytes(1536), "1.50 KiB (1,536 bytes)");
        assert_eq!(format_bytes(3 << 30), "3.00 GiB (3,221,225,472 bytes)");
    }
}
