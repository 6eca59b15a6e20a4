//! Headless wgpu context: adapter choice, device features, adapter description.

use std::sync::{Arc, Mutex};

use crate::GpuError;

/// Environment variable that picks an adapter by a substring of its name.
pub const ADAPTER_ENV: &str = "CAUSTICS_ADAPTER";

/// Features the harness needs from every adapter: method targets are `Rgba32Float`
/// with additive blending (half floats lose caustic energy when many triangles
/// or beams overlap a pixel).
pub const REQUIRED_FEATURES: wgpu::Features = wgpu::Features::FLOAT32_BLENDABLE;

/// Features used when present. Without them the matching figures are recorded as
/// absent (never as 0): timestamps give per-pass GPU time, pipeline statistics give
/// fragment-shader invocations and primitive counts per pass. Timestamps inside passes
/// let a compute pass's beginning be taken before its first dispatch on lavapipe
/// ([`crate::profiling`]). Forced early depth tests let the beam methods reject hull
/// fragments behind nothing they light before shading them, in every frame alike.
pub const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
    .union(wgpu::Features::PIPELINE_STATISTICS_QUERY)
    .union(wgpu::Features::INDIRECT_FIRST_INSTANCE)
    .union(wgpu::Features::SHADER_EARLY_DEPTH_TEST);

/// Where the adapter filter came from, for messages.
#[derive(Debug, Clone)]
pub enum AdapterChoice {
    /// Default: the first hardware adapter, else the first software one (lavapipe).
    Default,
    /// A substring of the adapter name, from the `--adapter` flag.
    Flag(String),
    /// A substring of the adapter name, from `CAUSTICS_ADAPTER`.
    Env(String),
}

impl AdapterChoice {
    /// The flag wins over the environment variable, which wins over the default.
    pub fn from_flag_or_env(flag: Option<&str>) -> Self {
        if let Some(f) = flag.filter(|f| !f.is_empty()) {
            return Self::Flag(f.to_owned());
        }
        match std::env::var(ADAPTER_ENV) {
            Ok(v) if !v.is_empty() => Self::Env(v),
            _ => Self::Default,
        }
    }
}

/// The adapter, device and queue every pass runs on.
pub struct GpuContext {
    /// The adapter that was chosen.
    pub adapter: wgpu::Adapter,
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter is, for result files.
    pub summary: AdapterSummary,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// What a request is checked against before a large allocation: the device's
    /// limits and the memory budget.
    pub limits: crate::limits::DeviceLimits,
    /// The ledger of GPU memory every live resource holds, summed against the budget.
    pub memory: Arc<crate::limits::GpuMemory>,
    /// Device loss and errors raised outside any error scope, recorded by the device's
    /// callbacks instead of wgpu's default (a panic), reported by [`GpuContext::check_device`].
    faults: Arc<Mutex<DeviceFaults>>,
    /// Shader modules and pipelines compiled on this device, reused by identical builds.
    pipelines: crate::pipeline_cache::PipelineCache,
}

/// What the device's callbacks saw.
#[derive(Debug, Default)]
struct DeviceFaults {
    lost: Option<String>,
    uncaptured: Vec<String>,
}

/// Adapter facts, as strings so result files stay stable across wgpu versions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterSummary {
    /// Adapter name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub name: String,
    /// Backend, e.g. "Vulkan".
    pub backend: String,
    /// Device type, e.g. "Cpu" or "DiscreteGpu".
    pub device_type: String,
    /// Driver name.
    pub driver: String,
    /// Driver version string.
    pub driver_info: String,
}

fn summary(info: &wgpu::AdapterInfo) -> AdapterSummary {
    AdapterSummary {
        name: info.name.clone(),
        backend: format!("{:?}", info.backend),
        device_type: format!("{:?}", info.device_type),
        driver: info.driver.clone(),
        driver_info: info.driver_info.clone(),
    }
}

fn is_hardware(t: wgpu::DeviceType) -> bool {
    matches!(
        t,
        wgpu::DeviceType::DiscreteGpu
            | wgpu::DeviceType::IntegratedGpu
            | wgpu::DeviceType::VirtualGpu
    )
}

/// Backends the harness opens (where the platform has them).
const BACKENDS: wgpu::Backends = wgpu::Backends::VULKAN
    .union(wgpu::Backends::METAL)
    .union(wgpu::Backends::DX12);

/// Every adapter the instance finds, in the instance's order: what `caustics adapters`
/// lists and what [`choose_adapter`] picks from. Errors when there is none.
pub fn enumerate_adapters() -> Result<Vec<wgpu::Adapter>, GpuError> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = BACKENDS;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(BACKENDS));
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter {
            backends: format!("{BACKENDS:?}"),
        });
    }
    Ok(adapters)
}

/// Index into `adapters` of the one `choice` picks: by default the first hardware
/// adapter, else the first (lavapipe on a machine without a GPU); with a filter, the
/// first whose name contains it (case-insensitive), else an error listing them all.
pub fn choose_adapter(
    adapters: &[wgpu::Adapter],
    choice: &AdapterChoice,
) -> Result<usize, GpuError> {
    match choice {
        AdapterChoice::Default => Ok(adapters
            .iter()
            .position(|a| is_hardware(a.get_info().device_type))
            .unwrap_or(0)),
        AdapterChoice::Flag(s) | AdapterChoice::Env(s) => {
            let wanted = s.to_lowercase();
            adapters
                .iter()
                .position(|a| a.get_info().name.to_lowercase().contains(&wanted))
                .ok_or_else(|| GpuError::AdapterNotFound {
                    wanted: s.clone(),
                    source_of_filter: match choice {
                        AdapterChoice::Flag(_) => "--adapter".into(),
                        _ => ADAPTER_ENV.into(),
                    },
                    available: adapters
                        .iter()
                        .map(|a| {
                            let i = a.get_info();
                            format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
                        })
                        .collect::<Vec<_>>()
                        .join("; "),
                })
        }
    }
}

/// The adapter's facts as the result files record them.
pub fn adapter_summary(adapter: &wgpu::Adapter) -> AdapterSummary {
    summary(&adapter.get_info())
}

impl GpuContext {
    /// Opens a device on the adapter picked by `choice`.
    pub fn new(choice: &AdapterChoice) -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async(choice))
    }

    async fn new_async(choice: &AdapterChoice) -> Result<Self, GpuError> {
        let mut adapters = enumerate_adapters()?;
        let index = choose_adapter(&adapters, choice)?;
        let adapter = adapters.swap_remove(index);

        let info = adapter.get_info();
        let available = adapter.features();
        if !available.contains(REQUIRED_FEATURES) {
            return Err(GpuError::MissingFeatures {
                adapter: info.name.clone(),
                missing: REQUIRED_FEATURES - available,
            });
        }
        let features = REQUIRED_FEATURES | (OPTIONAL_FEATURES & available);
        let adapter_limits = adapter.limits();
        let memory_budget = crate::limits::DeviceLimits::memory_budget_from_env()?;
        let limits = wgpu::Limits {
            // The adapter's own texture side (wgpu's default is 8,192), so a large
            // camera image is refused only where the device cannot hold it.
            max_texture_dimension_2d: adapter_limits.max_texture_dimension_2d,
            max_storage_buffers_per_shader_stage: adapter_limits
                .max_storage_buffers_per_shader_stage
                .min(16),
            max_storage_buffer_binding_size: adapter_limits.max_storage_buffer_binding_size,
            max_buffer_size: adapter_limits.max_buffer_size,
            max_texture_array_layers: adapter_limits.max_texture_array_layers,
            max_color_attachment_bytes_per_sample: adapter_limits
                .max_color_attachment_bytes_per_sample,
            ..wgpu::Limits::default()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("caustics-bench"),
                required_features: features,
                required_limits: limits,
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::RequestDevice {
                adapter: info.name.clone(),
                source,
            })?;
        let faults = Arc::new(Mutex::new(DeviceFaults::default()));
        let on_lost = faults.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut f) = on_lost.lock() {
                f.lost = Some(format!("{reason:?}: {message}"));
            }
        });
        let on_error = faults.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut f) = on_error.lock() {
                f.uncaptured.push(e.to_string());
            }
        }));
        let limits = crate::limits::DeviceLimits::new(&device.limits(), memory_budget);
        Ok(Self {
            summary: summary(&info),
            adapter,
            device,
            queue,
            features,
            limits,
            memory: crate::limits::GpuMemory::new(memory_budget),
            faults,
            pipelines: Default::default(),
        })
    }

    /// Checks a storage buffer of `bytes`, bound whole, against the device's largest
    /// binding and holds its bytes in the memory ledger (summed with every live
    /// resource): call before creating it, and keep the reservation beside it.
    pub fn reserve_storage(
        &self,
        what: &str,
        bytes: u64,
        raise: &str,
    ) -> Result<crate::limits::Reservation, GpuError> {
        self.limits.storage(what, bytes, raise)?;
        self.memory.reserve(what, bytes, raise)
    }

    /// Fails if the device was lost (driver reset, out of memory on the device, or
    /// destroyed) or reported an error outside every error scope since the last check
    /// (the errors are then cleared): `what` names the work that was going on.
    pub fn check_device(&self, what: &str) -> Result<(), GpuError> {
        let Ok(mut f) = self.faults.lock() else {
            return Err(GpuError::DeviceLost {
                what: what.to_owned(),
                reason: "device fault record poisoned".into(),
            });
        };
        if let Some(reason) = &f.lost {
            return Err(GpuError::DeviceLost {
                what: what.to_owned(),
                reason: reason.clone(),
            });
        }
        if !f.uncaptured.is_empty() {
            let message = f.uncaptured.join("; ");
            f.uncaptured.clear();
            return Err(GpuError::Validation {
                kind: "uncaptured",
                what: what.to_owned(),
                message,
            });
        }
        Ok(())
    }

    /// How many pipelines this device compiled and how many pass builds reused one
    /// ([`crate::pipeline_cache`]).
    pub fn pipeline_stats(&self) -> crate::pipeline_cache::PipelineStats {
        self.pipelines.stats()
    }

    pub(crate) fn pipelines(&self) -> &crate::pipeline_cache::PipelineCache {
        &self.pipelines
    }

    /// Whether per-pass timestamps can be taken.
    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Whether a pass can write timestamps between its commands.
    pub fn has_timestamps_inside_passes(&self) -> bool {
        self.features.contains(
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES,
        )
    }

    /// Whether pipeline statistics (fragment invocations, primitives) can be taken.
    pub fn has_pipeline_statistics(&self) -> bool {
        self.features
            .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
    }

    /// Runs `f` inside validation and out-of-memory error scopes and turns what wgpu
    /// reports into a typed error, so a bad pipeline is an error naming `what`, not a panic.
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let val = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let validation = pollster::block_on(val.pop());
        let memory = pollster::block_on(oom.pop());
        for (kind, err) in [("validation", validation), ("out of memory", memory)] {
            if let Some(e) = err {
                return Err(GpuError::Validation {
                    kind,
                    what: what.to_owned(),
                    message: e.to_string(),
                });
            }
        }
        self.check_device(what)?;
        Ok(out)
    }

    /// Blocks until all submitted work is done.
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback {
                what: "device poll".into(),
                message: e.to_string(),
            })
    }
}
