// The caustic cube map's fixed-point accumulator, shared by the compute-raster paths
// of the photon-hit methods (`raster=compute`: splatting's kernels, caustic-triangles'
// triangles and orphan splats). A reconstruction kernel adds each covered texel's
// value with `add_atlas`; `resolve` then writes the sums into the atlas and zeroes the
// accumulator for the next frame. Integer sums do not depend on the order in which
// invocations add (caustics-gpu's fixed_point.wgsl: 64-bit channels of 2^-24 units,
// W/m² in rgb and luminance × m in alpha), so the map is the same on every run.
// The including shader declares, besides `cm: CausticMapUniform`,
//     var<storage, read_write> accum: array<atomic<u32>>;
//     var atlas_out: texture_storage_2d<rgba32float, write>;

// Words per atlas texel: (low, high) for r, g, b and alpha.
const ATLAS_WORDS: u32 = 8u;

// Adds `value` (irradiance rgb, luminance × distance alpha) to texel `texel` (face
// texels from its top-left corner) of face `face`.
fn add_atlas(face: u32, texel: vec2<u32>, value: vec4<f32>) {
    let s = u32(cm.params.x);
    // Face f sits at column f % 3, row f / 3 of the 3 × 2 atlas.
    let x = (face % 3u) * s + texel.x;
    let y = (face / 3u) * s + texel.y;
    let w = (y * 3u * s + x) * ATLAS_WORDS;
    add_fixed(w, value.r);
    add_fixed(w + 2u, value.g);
    add_fixed(w + 4u, value.b);
    add_fixed(w + 6u, value.a);
}

// One invocation per atlas texel: the accumulated sums into the atlas (every texel
// written, so no clear is needed), and the accumulator zeroed for the next frame.
@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas_out);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let w = (gid.y * size.x + gid.x) * ATLAS_WORDS;
    let value = vec4<f32>(take_fixed(w), take_fixed(w + 2u), take_fixed(w + 4u), take_fixed(w + 6u));
    textureStore(atlas_out, vec2<i32>(gid.xy), value);
}
