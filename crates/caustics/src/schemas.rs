//! JSON Schemas (draft 2020-12) of the files a user writes or reads: scene, experiment,
//! result, ceilings and animation files, generated from the Rust types that read them (`schemars`, which
//! follows their serde attributes) and committed under `schemas/`; a test checks that
//! the committed ones are current and that every committed scene, experiment and result
//! file validates against them. `caustics schema KIND` prints one.

/// Which file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SchemaKind {
    /// A scene file (`scenes/*.json`, `--scene PATH`).
    Scene,
    /// An experiment file (`bench/experiments/*.json`).
    Experiment,
    /// A run's `result.json`.
    Result,
    /// An adapter's ceilings record (`results/ceilings/*.json`, `caustics ceilings`).
    Ceilings,
    /// A sequence's `animation.json` (`caustics run --animate`).
    Animation,
}

impl SchemaKind {
    /// Every kind, in the order the README lists them.
    pub const ALL: [SchemaKind; 5] = [
        SchemaKind::Scene,
        SchemaKind::Experiment,
        SchemaKind::Result,
        SchemaKind::Ceilings,
        SchemaKind::Animation,
    ];

    /// The committed file's name under `schemas/`.
    pub fn file_name(self) -> &'static str {
        match self {
            SchemaKind::Scene => "scene.schema.json",
            SchemaKind::Experiment => "experiment.schema.json",
            SchemaKind::Result => "result.schema.json",
            SchemaKind::Ceilings => "ceilings.schema.json",
            SchemaKind::Animation => "animation.schema.json",
        }
    }
}

/// The schema of `kind`, as JSON.
pub fn schema(kind: SchemaKind) -> serde_json::Value {
    let s = match kind {
        SchemaKind::Scene => return caustics_scene::json_schema(),
        SchemaKind::Experiment => schemars::schema_for!(crate::experiment::ExperimentFile),
        SchemaKind::Result => schemars::schema_for!(crate::result::RunResult),
        SchemaKind::Ceilings => schemars::schema_for!(crate::ceilings_cmd::CeilingsRecord),
        SchemaKind::Animation => schemars::schema_for!(crate::animate::AnimationResult),
    };
    serde_json::to_value(s).unwrap_or(serde_json::Value::Null)
}

/// The schema of `kind` as the committed file holds it: pretty JSON and a newline.
pub fn schema_text(kind: SchemaKind) -> String {
    let mut text = serde_json::to_string_pretty(&schema(kind)).unwrap_or_default();
    text.push('\n');
    text
}
