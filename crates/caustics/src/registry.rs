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

#[cfg(test)]
mod tests {
    use super::methods;

    /// fog_sphere (a medium) is rendered by the volume methods and declined by every
    /// other one with the sentence of its paper that leaves media out (issue 14: a
    /// decline names what in the paper rules it out).
    #[test]
    fn a_medium_is_declined_with_the_papers_sentence() {
        let path = caustics_scene::resolve("fog_sphere").expect("fog_sphere");
        let scene = caustics_scene::Scene::load(&path).expect("fog_sphere loads");
        assert!(scene.medium.is_some());
        for m in methods() {
            let params = (m.parse)(&serde_json::Value::Null).expect("defaults");
            let verdict = m.supports(&scene, &params);
            if m.capabilities.volume {
                assert_eq!(verdict, Ok(()), "{}", m.name);
                continue;
            }
            let why = verdict.expect_err(m.name).0;
            let cited = m.capabilities.no_medium_in_paper;
            assert!(
                why.contains("participating medium") && !cited.is_empty() && why.contains(cited),
                "{}: {why}",
                m.name
            );
            // A quotation, and the paper's authors as `caustics list` names its source.
            let author = m
                .source
                .split([' ', ','])
                .find(|w| w.chars().next().is_some_and(char::is_uppercase))
                .expect("source names an author");
            assert!(
                cited.contains('\u{201c}') && cited.contains(author),
                "{}: {cited} (source {})",
                m.name,
                m.source
            );
        }
    }
}
