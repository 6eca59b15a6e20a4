//! The table of methods (STYLE: one table lists them, with parameters and support).

use caustics_method::{MethodInfo, registry_entry};

/// Every method the harness can run, in the order `caustics list` prints them.
pub fn methods() -> Vec<MethodInfo> {
    vec![
        registry_entry::<wavefront::Wavefront>(),
        registry_entry::<pinhole::Pinhole>(),
        registry_entry::<static_grid::StaticGrid>(),
        registry_entry::<adaptive_beams::AdaptiveBeams>(),
        registry_entry::<caustic_triangles::CausticTriangles>(),
        registry_entry::<splatting::Splatting>(),
    ]
}

/// The method called `name`, or an error listing the known ones.
pub fn find(name: &str) -> anyhow::Result<MethodInfo> {
    let all = methods();
    let known: Vec<&str> = all.iter().map(|m| m.name).collect();
    let known = known.join(", ");
    all.into_iter()
        .find(|m| m.name == name)
        .ok_or_else(|| anyhow::anyhow!("unknown method {name:?}; known methods: {known}"))
}

/// The method's parameters parsed and checked (its errors name the parameter at fault),
/// as an `anyhow` error.
pub fn parse_params(
    info: &MethodInfo,
    params: &serde_json::Value,
) -> anyhow::Result<caustics_method::ParsedParams> {
    Ok((info.parse)(params)?)
}
