// Camera pass (Umenhoffer et al. §4.3): the caustic cube map acts as a light source.
// For each camera G-buffer pixel on a diffuse surface, the map is looked up in the
// direction from its centre to the shaded point (bilinear over the four nearest
// texels of the face). A texel's light is accepted only where the distance stored
// with it matches the shaded point's distance from the centre, so light reconstructed
// on a nearer surface never leaks onto one hidden behind it (§4: "this cube map is
// also a shadow map"). The map holds irradiance on the receiver (W/m²) in rgb and
// luminance(E) × distance in alpha (so additive blending keeps a flux-weighted mean
// distance); the pixel's radiance is ρ/π · E (DESIGN units).

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var caustic_atlas: texture_2d<f32>;

// Texel `t` of face `face`, clamped to the face (taps past an edge repeat the edge).
fn atlas_texel(face: u32, t: vec2<i32>) -> vec4<f32> {
    let s = i32(cm.params.x);
    let c = clamp(t, vec2<i32>(0), vec2<i32>(s - 1));
    let origin = vec2<i32>(i32(face % 3u) * s, i32(face / 3u) * s);
    return textureLoad(caustic_atlas, origin + c, 0);
}

// A tap's irradiance if its stored distance matches `dist` (or the test is off).
fn accepted(v: vec4<f32>, dist: f32) -> vec3<f32> {
    if cm.params.y < 0.5 {
        return v.rgb;
    }
    let lum = luminance(v.rgb);
    if lum <= 0.0 || abs(v.a / lum - dist) > cm.params.z * dist {
        return vec3<f32>(0.0);
    }
    return v.rgb;
}

@fragment
fn fs_lookup(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    count_fragment(frag);
    let g = gbuffer_sample(vec2<u32>(frag.xy));
    if !g.hit || materials[g.material].kind != MAT_DIFFUSE {
        discard;
    }
    let l = g.position - cm.center.xyz;
    let dist = length(l);
    // The caustic light arrives on the side of a receiver that faces the generator:
    // the back of a thin receiver lies at the same distance in the same direction.
    if dist <= 0.0 || dot(g.facing_normal, l) >= 0.0 {
        discard;
    }
    let fuv = impostor_face_uv(l);
    let face = u32(fuv.z);
    let st = fuv.xy * cm.params.x - 0.5;
    let base = floor(st);
    let f = st - base;
    let b = vec2<i32>(base);
    let e = mix(
        mix(accepted(atlas_texel(face, b), dist), accepted(atlas_texel(face, b + vec2<i32>(1, 0)), dist), f.x),
        mix(accepted(atlas_texel(face, b + vec2<i32>(0, 1)), dist), accepted(atlas_texel(face, b + vec2<i32>(1, 1)), dist), f.x),
        f.y,
    );
    let albedo = materials[g.material].color.xyz;
    return vec4<f32>(albedo * INV_PI * e, 1.0);
}
