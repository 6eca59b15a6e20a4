//! Shared WGSL and shader-module creation. Passes compose `common.wgsl` (and
//! `frame.wgsl` for method passes that read the camera G-buffer) with their own file.

use std::borrow::Cow;

/// Constants, scene tables and radiometry/intersection helpers.
pub const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");
/// Group 0 of every method pass: frame uniforms, camera G-buffer, scene tables, fill counter.
pub const FRAME_WGSL: &str = include_str!("shaders/frame.wgsl");
/// The G-buffer pass.
pub const GBUFFER_WGSL: &str = include_str!("shaders/gbuffer.wgsl");
/// The direct-lighting pass.
pub const DIRECT_WGSL: &str = include_str!("shaders/direct.wgsl");
/// 64-bit fixed-point accumulation with integer atomics (`add_fixed`, `take_fixed`) of the
/// compute-raster paths; the including shader declares `accum: array<atomic<u32>>`.
pub const FIXED_POINT_WGSL: &str = include_str!("shaders/fixed_point.wgsl");
/// 64-bit work counts of the compute-raster paths, summed per workgroup (`add_count`,
/// `group_count_begin`, `group_count_end`); the including shader declares
/// `raster_counts: array<atomic<u32>, N>`.
pub const RASTER_COUNTS_WGSL: &str = include_str!("shaders/raster_counts.wgsl");
/// Triangle scan conversion of the compute-raster paths (`triangle_footprint`,
/// `footprint_barycentrics`): the pixels a triangle covers and the rasterizer's
/// perspective-correct barycentrics there, from clip coordinates; no bindings.
pub const TRIANGLE_RASTER_WGSL: &str = include_str!("shaders/triangle_raster.wgsl");
/// Fractional bits of [`FIXED_POINT_WGSL`]'s numbers: contributions are rounded to the
/// nearest multiple of 2^-24.
pub const FIXED_POINT_FRAC_BITS: u32 = 24;
/// u32 words per channel of a [`FIXED_POINT_WGSL`] accumulator (low, high).
pub const FIXED_POINT_WORDS: u64 = 2;
/// `common.wgsl` followed by `own`, for passes with their own bindings.
pub fn compose(own: &str) -> String {
    format!("{COMMON_WGSL}\n{own}")
}

/// `common.wgsl`, `frame.wgsl`, then `own`: for method passes bound to group 0.
pub fn compose_method(own: &str) -> String {
    format!("{COMMON_WGSL}\n{FRAME_WGSL}\n{own}")
}

/// Creates a shader module from composed WGSL.
pub fn module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(source)),
    })
}

/// Parses and validates composed WGSL with naga (the compiler wgpu uses), so a broken
/// shader fails `cargo test` before any GPU run. Every crate's shader test calls this.
pub fn validate_wgsl(label: &str, source: &str) -> Result<(), String> {
    parse_and_validate(label, source).map(|_| ())
}

/// The naga module and its validation info (what [`crate::pass::Reflection`] reads).
pub(crate) fn parse_and_validate(
    label: &str,
    source: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{label}: WGSL parse error:\n{}", e.emit_to_string(source)))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| {
        format!(
            "{label}: WGSL validation error:\n{}",
            e.emit_to_string(source)
        )
    })?;
    Ok((module, info))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_shaders_validate() -> Result<(), String> {
        validate_wgsl("common.wgsl", COMMON_WGSL)?;
        validate_wgsl("common+frame.wgsl", &compose_method(""))?;
        validate_wgsl("gbuffer.wgsl", &compose(GBUFFER_WGSL))?;
        validate_wgsl("direct.wgsl", &compose(DIRECT_WGSL))?;
        validate_wgsl(
            "fixed_point.wgsl",
            &format!(
                "@group(0) @binding(0) var<storage, read_write> accum: array<atomic<u32>>;\n{FIXED_POINT_WGSL}\n\
                 @compute @workgroup_size(1) fn k() {{ add_fixed(0u, take_fixed(2u)); }}"
            ),
        )?;
        validate_wgsl(
            "raster_counts.wgsl",
            &format!(
                "@group(0) @binding(0) var<storage, read_write> raster_counts: array<atomic<u32>, 2>;\n\
                 {RASTER_COUNTS_WGSL}\n@compute @workgroup_size(64) fn k(\
                 @builtin(local_invocation_index) lane: u32) {{ group_count_begin(lane); \
                 group_count_end(lane, 1u, 0u); }}"
            ),
        )?;
        validate_wgsl(
            "triangle_raster.wgsl",
            &format!(
                "{TRIANGLE_RASTER_WGSL}\n@compute @workgroup_size(1) fn k() {{\n\
                 let f = triangle_footprint(vec4<f32>(0.0), vec4<f32>(1.0), vec4<f32>(2.0), vec2<f32>(8.0));\n\
                 _ = footprint_barycentrics(f, vec2<u32>(footprint_pixels(f)), vec2<f32>(8.0)); }}"
            ),
        )
    }

    #[test]
    fn the_fixed_point_constants_agree_with_the_shader() {
        assert!(
            FIXED_POINT_WGSL.contains(&format!(
                "const FIXED_FRAC_BITS: f32 = {FIXED_POINT_FRAC_BITS}.0;"
            )),
            "FIXED_POINT_FRAC_BITS and the shader's FIXED_FRAC_BITS agree"
        );
    }

    #[test]
    fn validator_rejects_a_broken_shader() {
        assert!(validate_wgsl("broken", "fn f() -> f32 { return vec2<f32>(1.0); }").is_err());
        assert!(
            validate_wgsl(
                "undeclared",
                &compose("fn f() -> f32 { return undeclared_thing; }")
            )
            .is_err()
        );
    }
}
