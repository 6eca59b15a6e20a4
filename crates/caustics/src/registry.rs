//! The table of methods (STYLE: one table lists them, with parameters and support).

use caustics_method::MethodInfo;

/// Every method the harness can run, in the order `caustics list` prints them.
pub fn methods() -> Vec<MethodInfo> {
    vec![
        wavefront::info(),
        pinhole::info(),
        static_grid::info(),
        adaptive_beams::info(),
        caustic_triangles::info(),
        splatting::info(),
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

/// The method's `validate_params` (its errors name the parameter at fault), as an
/// `anyhow` error.
pub fn validate_params(info: &MethodInfo, params: &serde_json::Value) -> anyhow::Result<()> {
    Ok((info.validate_params)(params)?)
}
