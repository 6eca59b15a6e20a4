// Direct lighting (DESIGN "Direct image": L D E with shadows), one light per draw,
// added into the direct target. Visibility from the light G-buffer's depth (shadow
// map), 3x3 percentage-closer filtering.

struct DirectLight {
    light: GpuLight,
    // Per face (1 for directional/spot, 6 for a point light's cube) world -> clip.
    face_view_proj: array<mat4x4<f32>, 6>,
    // x: face count, y: shadow-map resolution (texels), z: world size of a texel at
    // unit distance (perspective) or in total (orthographic), w: 1 orthographic.
    params: vec4<f32>,
}

@group(0) @binding(0) var gbuf_position: texture_2d<f32>;
@group(0) @binding(1) var gbuf_normal: texture_2d<f32>;
@group(0) @binding(2) var gbuf_ids: texture_2d<u32>;
@group(0) @binding(3) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(4) var<uniform> dl: DirectLight;
@group(0) @binding(5) var shadow_map: texture_depth_2d_array;
@group(0) @binding(6) var shadow_sampler: sampler_comparison;

// Cube face order +X, -X, +Y, -Y, +Z, -Z (as `LightView::faces`).
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

fn visibility(p: vec3<f32>, n: vec3<f32>, dist: f32) -> f32 {
    // Normal offset of ~2 texels at this distance keeps flat receivers from self-shadowing.
    let texel = select(dl.params.z * dist, dl.params.z, dl.params.w > 0.5);
    let q = p + n * (2.0 * texel);
    let cube = u32(dl.params.x) == 6u;
    var face = 0u;
    if cube {
        // The face is chosen for the point actually looked up, so it is inside that face.
        face = cube_face(q - dl.light.position.xyz);
    }
    let clip = dl.face_view_proj[face] * vec4<f32>(q, 1.0);
    let ndc = clip.xyz / clip.w;
    if !cube && (any(abs(ndc.xy) > vec2<f32>(1.0)) || ndc.z < 0.0 || ndc.z > 1.0) {
        // Outside the light's frustum: lit for directional (fitted to the scene), unlit
        // outside a spot's cone (the cone factor is 0 there anyway).
        return 1.0;
    }
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let res = dl.params.y;
    var sum = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            // Taps past a face's edge clamp to it (the sampler clamps to edge).
            let o = vec2<f32>(f32(x), f32(y)) / res;
            sum += textureSampleCompareLevel(shadow_map, shadow_sampler, uv + o, face, ndc.z - 1e-5);
        }
    }
    return sum / 9.0;
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(frag.xy);
    let pos = textureLoad(gbuf_position, pixel, 0);
    if pos.w < 0.5 {
        return vec4<f32>(0.0);
    }
    let ids = textureLoad(gbuf_ids, pixel, 0);
    let mat = materials[ids.y];
    if mat.kind != MAT_DIFFUSE {
        return vec4<f32>(0.0);
    }
    let nraw = textureLoad(gbuf_normal, pixel, 0);
    let n = normalize(nraw.xyz) * select(-1.0, 1.0, nraw.w >= 0.0);
    let p = pos.xyz;
    var to_light: vec3<f32>;
    var irradiance_facing: vec3<f32>;
    var dist = 1.0;
    if dl.light.kind == LIGHT_DIRECTIONAL {
        to_light = -dl.light.direction.xyz;
        irradiance_facing = dl.light.power.xyz;
    } else {
        let d = dl.light.position.xyz - p;
        dist = length(d);
        to_light = d / dist;
        irradiance_facing = light_intensity(dl.light, -to_light) / (dist * dist);
    }
    let cos_theta = dot(n, to_light);
    if cos_theta <= 0.0 {
        return vec4<f32>(0.0);
    }
    let vis = visibility(p, n, dist);
    let radiance = mat.color.xyz * INV_PI * irradiance_facing * cos_theta * vis;
    return vec4<f32>(radiance, 1.0);
}
