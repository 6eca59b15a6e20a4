//! `caustics adapters`: every adapter wgpu finds, the one `run` would pick, and each
//! one's features and limits, so a result's numbers can be read against what the
//! adapter offers (and a missing timestamp or statistics feature explained) before any
//! run.

use std::path::PathBuf;

use anyhow::{Context, Result};
use caustics_gpu::wgpu;
use caustics_gpu::{AdapterChoice, AdapterSummary, OPTIONAL_FEATURES, REQUIRED_FEATURES};
use serde::Serialize;

/// `caustics adapters` flags.
#[derive(clap::Args, Debug, Clone)]
pub struct AdaptersArgs {
    /// Substring of the adapter name, as `caustics run --adapter` takes it: marks the
    /// adapter it would pick (default: CAUSTICS_ADAPTER, else the first hardware
    /// adapter, else lavapipe).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Also write every adapter's features and limits as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
}

/// One adapter as the instance enumerates it.
#[derive(Debug, Clone, Serialize)]
pub struct AdapterReport {
    /// Position in the instance's enumeration.
    pub index: usize,
    /// Whether `run` with the same `--adapter` would use it.
    pub chosen: bool,
    /// Name, backend, device type, driver.
    pub name: String,
    /// e.g. "Vulkan".
    pub backend: String,
    /// e.g. "DiscreteGpu" or "Cpu".
    pub device_type: String,
    /// Driver name.
    pub driver: String,
    /// Driver version.
    pub driver_info: String,
    /// PCI vendor id.
    pub vendor_id: u32,
    /// PCI device id.
    pub device_id: u32,
    /// Features the harness needs and the adapter lacks: a run refuses it.
    pub missing_required: Vec<String>,
    /// Optional features (timestamps, pipeline statistics, ...) the adapter lacks:
    /// a run on it records the matching figures as absent.
    pub missing_optional: Vec<String>,
    /// Every feature the adapter offers (wgpu's names).
    pub features: Vec<String>,
    /// The adapter's limits (WebGPU's names); a run asks for wgpu's defaults except
    /// the texture side, storage binding and buffer sizes, which it takes from here.
    pub limits: wgpu::Limits,
}

fn feature_names(features: wgpu::Features) -> Vec<String> {
    features
        .iter_names()
        .map(|(name, _)| name.to_owned())
        .collect()
}

/// Every adapter, with the one `args.adapter` picks marked.
pub fn adapter_reports(args: &AdaptersArgs) -> Result<Vec<AdapterReport>> {
    let adapters = caustics_gpu::enumerate_adapters()?;
    let choice = AdapterChoice::from_flag_or_env(args.adapter.as_deref());
    let chosen = caustics_gpu::choose_adapter(&adapters, &choice)?;
    Ok(adapters
        .iter()
        .enumerate()
        .map(|(index, adapter)| {
            let info = adapter.get_info();
            let AdapterSummary {
                name,
                backend,
                device_type,
                driver,
                driver_info,
            } = caustics_gpu::adapter_summary(adapter);
            let features = adapter.features();
            AdapterReport {
                index,
                chosen: index == chosen,
                name,
                backend,
                device_type,
                driver,
                driver_info,
                vendor_id: info.vendor,
                device_id: info.device,
                missing_required: feature_names(REQUIRED_FEATURES - features),
                missing_optional: feature_names(OPTIONAL_FEATURES - features),
                features: feature_names(features),
                limits: adapter.limits(),
            }
        })
        .collect())
}

/// The reports as text: one block per adapter, features and limits one per line.
pub fn text(reports: &[AdapterReport]) -> Result<String> {
    use std::fmt::Write as _;
    let mut s = String::new();
    for r in reports {
        let mark = if r.chosen { " (chosen)" } else { "" };
        writeln!(
            s,
            "adapter {}{mark}: {} ({}, {}; driver {} {}; pci {:04x}:{:04x})",
            r.index,
            r.name,
            r.backend,
            r.device_type,
            r.driver,
            r.driver_info,
            r.vendor_id,
            r.device_id
        )?;
        if !r.missing_required.is_empty() {
            writeln!(
                s,
                "  unusable: lacks required {}",
                r.missing_required.join(", ")
            )?;
        }
        if !r.missing_optional.is_empty() {
            writeln!(
                s,
                "  lacks optional {} (their figures are recorded as absent)",
                r.missing_optional.join(", ")
            )?;
        }
        writeln!(s, "  features ({}):", r.features.len())?;
        for f in &r.features {
            writeln!(s, "    {f}")?;
        }
        // The limits through their serde form, so the names are WebGPU's and new wgpu
        // limits appear without a change here.
        let limits = serde_json::to_value(&r.limits).context("limits as JSON")?;
        if let serde_json::Value::Object(map) = limits {
            writeln!(s, "  limits:")?;
            for (k, v) in map {
                writeln!(s, "    {k} = {v}")?;
            }
        }
    }
    Ok(s)
}

/// `caustics adapters`: prints the reports, writes the JSON when asked.
pub fn adapters(args: &AdaptersArgs) -> Result<String> {
    let reports = adapter_reports(args)?;
    if let Some(path) = &args.json {
        let json = serde_json::to_vec_pretty(&reports).context("adapters as JSON")?;
        caustics_metrics::atomic_write(path, &json)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    text(&reports)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On lavapipe (CI) at least one adapter is found, exactly one is chosen, and it
    /// has the features every run needs; its limits serialize under WebGPU's names.
    #[test]
    fn lists_the_chosen_adapter_with_its_features_and_limits() {
        let reports = adapter_reports(&AdaptersArgs {
            adapter: None,
            json: None,
        })
        .expect(
            "no adapter: install a Vulkan driver (Debian: apt-get install -y mesa-vulkan-drivers)",
        );
        assert!(!reports.is_empty());
        let chosen: Vec<_> = reports.iter().filter(|r| r.chosen).collect();
        assert_eq!(chosen.len(), 1, "exactly one adapter is chosen");
        assert!(
            chosen[0].missing_required.is_empty(),
            "{} lacks {:?}",
            chosen[0].name,
            chosen[0].missing_required
        );
        assert!(
            chosen[0].features.iter().any(|f| f == "FLOAT32_BLENDABLE"),
            "{:?}",
            chosen[0].features
        );
        let text = text(&reports).expect("the reports format");
        assert!(text.contains("(chosen)"), "{text}");
        assert!(text.contains("maxStorageBufferBindingSize = "), "{text}");
    }

    #[test]
    fn an_adapter_filter_that_matches_nothing_names_the_adapters_present() {
        let err = adapter_reports(&AdaptersArgs {
            adapter: Some("no-such-adapter-xyz".into()),
            json: None,
        })
        .expect_err("an unknown adapter is an error");
        let text = format!("{err:#}");
        assert!(text.contains("no-such-adapter-xyz"), "{text}");
    }
}
