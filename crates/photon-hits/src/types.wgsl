// Types shared by the photon-hit passes (photon-hits, caustic-triangles, splatting).

// One texel of the photon hit location image (Umenhoffer et al. §4.1).
struct PhotonHit {
    // xyz: where the photon lands on a diffuse receiver (world, m); w: its distance from
    // the caustic map's centre (m), 0 for an invalid texel.
    position: vec4<f32>,
    // xyz: the receiver's unit normal on the side the light arrives on; w: the texel's
    // footprint (m²) perpendicular to the light at the generator, for the stretch rule.
    normal: vec4<f32>,
    // rgb: flux (W) the texel's light carries to the receiver, Fresnel/reflectance
    // weighted; w unused.
    flux: vec4<f32>,
    // x: receiver object (NONE if invalid), y: specular path id, z: why invalid (0 valid).
    ids: vec4<u32>,
}

// The caustic ("light") cube map, stored as a 3×2 atlas of faces in the order
// +X, -X, +Y, -Y, +Z, -Z (face f at column f % 3, row f / 3), the same faces and
// texel convention as the distance impostors (`impostor_face_uv`).
struct CausticMapUniform {
    // World -> clip of each face around the centre.
    face_view_proj: array<mat4x4<f32>, 6>,
    // xyz: the centre (the distance maps' reference point, m); w unused.
    center: vec4<f32>,
    // x: face size (texels), y: 1 = distance test on, z: relative distance tolerance, w unused.
    params: vec4<f32>,
}

const HIT_VALID: u32 = 0u;
const HIT_NOT_GENERATOR: u32 = 1u;
const HIT_TIR: u32 = 2u;
const HIT_NO_EXIT: u32 = 3u;
const HIT_SECOND_BOUNCE: u32 = 4u;
const HIT_NO_RECEIVER: u32 = 5u;
const HIT_SPECULAR_RECEIVER: u32 = 6u;
// A silhouette hit (`silhouette_hits`): the landing of the light
// through the generator's edge beside a texel whose centre misses it, carrying the
// share of the texel's light on the generator's side. A valid hit otherwise.
const HIT_EDGE: u32 = 7u;
