// The triangles of the photon hit location image (caustic-triangles' passes share this).
// Neighbouring texels of one face form triangles (§4.2, Fig. 6): cell (x, y) is split
// along its diagonal into (00, 10, 11) and (00, 11, 01), two triangles per cell.

struct TriUniform {
    // Faces of the photon hit image.
    layers: u32,
    // Texels per side of a face.
    resolution: u32,
    // Discard rule: a triangle whose area on the receiver exceeds max_stretch × the
    // area its light had at the generator (half a texel footprint) spans a
    // discontinuity of the light's path (a silhouette, a grazing exit).
    max_stretch: f32,
    // ΔA of a vertex: AREA_FAN or AREA_THIRD (areas.wgsl).
    vertex_area: u32,
}

const AREA_FAN: u32 = 0u;
const AREA_THIRD: u32 = 1u;

const TRI_KEPT: u32 = 0u;
const TRI_INVALID_VERTEX: u32 = 1u;
const TRI_RECEIVER_MISMATCH: u32 = 2u;
const TRI_PATH_MISMATCH: u32 = 3u;
const TRI_STRETCHED: u32 = 4u;
const TRI_DEGENERATE: u32 = 5u;
// After the TRI_* reasons: valid hits none of whose triangles is kept (their light is
// lost unless `splat_orphans` splats them).
const ORPHAN_HITS: u32 = 6u;

fn cells_per_face() -> u32 {
    return (tri.resolution - 1u) * (tri.resolution - 1u);
}

fn triangle_count() -> u32 {
    return tri.layers * cells_per_face() * 2u;
}

// First triangle of cell (x, y) of face `layer`.
fn cell_triangle(layer: u32, x: u32, y: u32) -> u32 {
    return 2u * (layer * cells_per_face() + y * (tri.resolution - 1u) + x);
}

// Hit indices of triangle `t`.
fn triangle_vertices(t: u32) -> vec3<u32> {
    let cpf = cells_per_face();
    let layer = t / (2u * cpf);
    let r = t % (2u * cpf);
    let cell = r / 2u;
    let n = tri.resolution;
    let x = cell % (n - 1u);
    let y = cell / (n - 1u);
    let base = layer * n * n + y * n + x;
    if r % 2u == 0u {
        return vec3<u32>(base, base + 1u, base + n + 1u);
    }
    return vec3<u32>(base, base + n + 1u, base + n);
}
