// Pass 1 of pinhole: per sample of a one-event generator (a mirror, an open surface
// that refracts), the radiance of the light seen from the sample (with the light's
// visibility from it) and which side of the surface is lit.
// Both depend on the sample only, so the gather reads them instead of tracing a
// shadow ray per pixel and sample. (Dielectric spheres: the point the light enters
// depends on the pixel, so the gather traces that shadow ray itself.)

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> samples: array<Sample>;
// rgb: light radiance seen from the sample (0 if shadowed); w: +1/-1, the side of the
// normal the light is on.
@group(1) @binding(2) var<storage, read_write> sample_light: array<vec4<f32>>;

@compute @workgroup_size(64)
fn prepare_samples(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.sample_count {
        return;
    }
    let s = samples[i];
    // An environment lights every side, and its visibility depends on the direction a
    // receiver looks up (the gather traces it).
    if PINHOLE_ENVIRONMENT {
        sample_light[i] = vec4<f32>(1.0, 1.0, 1.0, 1.0);
        return;
    }
    let light = lights[params.light_index];
    let o = s.pos.xyz;
    var to_light = -light.direction.xyz;
    if light.kind != LIGHT_DIRECTIONAL {
        to_light = light.position.xyz - o;
    }
    let side = select(-1.0, 1.0, dot(to_light, s.normal.xyz) >= 0.0);
    // Start the shadow ray just off the lit side so the generator does not shadow itself.
    let start = o + side * s.normal.xyz * 1e-4;
    sample_light[i] = vec4<f32>(light_radiance(light, params, start, s.extra.y), side);
}
