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

/// The method's `validate_params`, with an error that names the parameter at fault:
/// serde's type errors ("invalid type: string \"NaN\", expected u32") do not, so each
/// given parameter is checked alone to find the one refused.
pub fn validate_params(info: &MethodInfo, params: &serde_json::Value) -> anyhow::Result<()> {
    let Err(e) = (info.validate_params)(params) else {
        return Ok(());
    };
    let message = e.to_string();
    let Some(obj) = params.as_object() else {
        return Err(e.into());
    };
    if obj.keys().any(|k| message.contains(k.as_str())) {
        return Err(e.into());
    }
    for (k, v) in obj {
        let alone = serde_json::Value::Object([(k.clone(), v.clone())].into_iter().collect());
        if let Err(e) = (info.validate_params)(&alone) {
            anyhow::bail!("parameter {k} = {v}: {e}");
        }
    }
    Err(e.into())
}
