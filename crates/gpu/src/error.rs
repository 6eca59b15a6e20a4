//! Typed errors of the GPU layer.

use std::path::PathBuf;

/// Everything that can go wrong while setting up or driving the GPU.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan/Metal/DX12 adapter exists on this machine.
    #[error(
        "no GPU adapter found (checked backends: {backends}). On Debian/Ubuntu install a \
         software Vulkan device with `apt-get install -y mesa-vulkan-drivers` (lavapipe), \
         or install your GPU's Vulkan driver"
    )]
    NoAdapter {
        /// The backends that were enumerated.
        backends: String,
    },
    /// `--adapter` / `CAUSTICS_ADAPTER` matched none of the adapters present.
    #[error(
        "no adapter name contains {wanted:?} (from {source_of_filter}); available: {available}"
    )]
    AdapterNotFound {
        /// The substring asked for.
        wanted: String,
        /// Where the filter came from (flag or environment variable).
        source_of_filter: String,
        /// Names of the adapters that do exist.
        available: String,
    },
    /// The adapter lacks a feature this harness cannot work without.
    #[error("adapter {adapter:?} lacks required features {missing:?}")]
    MissingFeatures {
        /// Adapter name.
        adapter: String,
        /// The missing features, as wgpu names them.
        missing: wgpu::Features,
    },
    /// `request_device` failed.
    #[error("could not open a device on adapter {adapter:?}: {source}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's error.
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// Mapping a readback buffer failed or the device was lost while waiting.
    #[error("GPU readback of {what} failed: {message}")]
    Readback {
        /// What was being read back.
        what: String,
        /// The underlying error.
        message: String,
    },
    /// A scene cannot be uploaded (for example it is larger than the adapter's limits).
    #[error("cannot upload scene {scene}: {message}")]
    Upload {
        /// Scene file.
        scene: PathBuf,
        /// Why.
        message: String,
    },
    /// wgpu reported a validation or out-of-memory error inside an error scope.
    #[error("wgpu {kind} error in {what}: {message}")]
    Validation {
        /// "validation", "out of memory" or "internal".
        kind: &'static str,
        /// The operation that was checked.
        what: String,
        /// wgpu's message.
        message: String,
    },
    /// The device was lost (driver reset, device out of memory, destroyed): nothing
    /// more can run on it.
    #[error("GPU device lost during {what}: {reason}")]
    DeviceLost {
        /// The work that was going on.
        what: String,
        /// wgpu's reason and message.
        reason: String,
    },
    /// A shader failed to parse or validate (naga's report, with the source lines).
    #[error("{0}")]
    Shader(String),
    /// A resource sized from a user's request is past the device's limits or the memory
    /// budget ([`crate::limits`]); refused before it is allocated.
    #[error("{what}: {needed} needed, past {limit}; {raise}")]
    OverLimit {
        /// The resource and what sizes it.
        what: String,
        /// What it needs.
        needed: String,
        /// The limit, named.
        limit: String,
        /// How to stay within it.
        raise: String,
    },
    /// A resource was asked for with arguments it cannot be built from.
    #[error("invalid GPU resource request: {0}")]
    Invalid(String),
    /// The profiler was asked for more passes or frames than it was sized for.
    #[error("profiler capacity exceeded: {0}")]
    ProfilerCapacity(String),
}
