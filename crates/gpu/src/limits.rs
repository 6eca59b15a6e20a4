//! What one device can hold, checked before a large allocation. Every pass that sizes
//! a texture or buffer from what a user asked for (the camera's resolution, a method's
//! parameters, a heightfield's vertex grid) asks here first, so a request past the
//! adapter's limits or the memory budget is refused with the limit and the way to
//! raise or avoid it, instead of by a wgpu validation or out-of-memory error after the
//! fact.
//!
//! The limits are the device's own (`wgpu::Device::limits`, which [`crate::GpuContext`]
//! requests at the adapter's values for texture sides and buffer sizes). wgpu reports
//! no memory size, so the memory budget is a stated number: [`DEFAULT_MEMORY_BUDGET_BYTES`],
//! or [`MEMORY_BUDGET_ENV`] in MiB.

use crate::GpuError;

/// Environment variable that sets the GPU memory budget, in MiB.
pub const MEMORY_BUDGET_ENV: &str = "CAUSTICS_GPU_MEMORY_MIB";

/// Memory budget without [`MEMORY_BUDGET_ENV`]: 8 GiB, a stated default (wgpu reports
/// no memory size); raise it on a larger device.
pub const DEFAULT_MEMORY_BUDGET_BYTES: u64 = 8 << 30;

/// The limits a request is checked against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceLimits {
    /// Largest side of a 2D texture (`max_texture_dimension_2d`).
    pub max_texture_side: u32,
    /// Largest storage-buffer binding (`max_storage_buffer_binding_size`), bytes.
    pub max_storage_binding_bytes: u64,
    /// Largest buffer (`max_buffer_size`), bytes.
    pub max_buffer_bytes: u64,
    /// What one resource (or the buffers one pass sizes together) may take, bytes;
    /// checked per resource, not summed over a method's resources.
    pub memory_budget_bytes: u64,
}

impl DeviceLimits {
    /// The limits of a device with `limits` under a memory budget.
    pub fn new(limits: &wgpu::Limits, memory_budget_bytes: u64) -> Self {
        Self {
            max_texture_side: limits.max_texture_dimension_2d,
            max_storage_binding_bytes: limits.max_storage_buffer_binding_size,
            max_buffer_bytes: limits.max_buffer_size,
            memory_budget_bytes,
        }
    }

    /// The memory budget [`MEMORY_BUDGET_ENV`] sets (MiB), else the default. A value
    /// that is not a positive whole number of MiB is refused by name.
    pub fn memory_budget_from_env() -> Result<u64, GpuError> {
        match std::env::var(MEMORY_BUDGET_ENV) {
            Err(_) => Ok(DEFAULT_MEMORY_BUDGET_BYTES),
            Ok(text) => parse_mib(&text).ok_or_else(|| {
                GpuError::Invalid(format!(
                    "{MEMORY_BUDGET_ENV}={text:?}: expected a whole number of MiB from 1 to {}",
                    u64::MAX >> 20
                ))
            }),
        }
    }

    /// A `width` × `height` texture (`what` names it and where its size comes from).
    pub fn texture(
        &self,
        what: &str,
        width: u32,
        height: u32,
        raise: &str,
    ) -> Result<(), GpuError> {
        let side = width.max(height);
        if side > self.max_texture_side {
            return Err(GpuError::OverLimit {
                what: what.to_owned(),
                needed: format!("{width}x{height} texels"),
                limit: format!(
                    "this device's largest texture side, {} (max_texture_dimension_2d)",
                    self.max_texture_side
                ),
                raise: raise.to_owned(),
            });
        }
        Ok(())
    }

    /// A storage buffer of `bytes`, bound whole.
    pub fn storage(&self, what: &str, bytes: u64, raise: &str) -> Result<(), GpuError> {
        let limit = self.max_storage_binding_bytes.min(self.max_buffer_bytes);
        if bytes > limit {
            return Err(GpuError::OverLimit {
                what: what.to_owned(),
                needed: format_bytes(bytes),
                limit: format!(
                    "this device's largest storage binding, {} (max_storage_buffer_binding_size)",
                    format_bytes(limit)
                ),
                raise: raise.to_owned(),
            });
        }
        Ok(())
    }

    /// Resources of `bytes` in all.
    pub fn memory(&self, what: &str, bytes: u64, raise: &str) -> Result<(), GpuError> {
        if bytes > self.memory_budget_bytes {
            return Err(GpuError::OverLimit {
                what: what.to_owned(),
                needed: format_bytes(bytes),
                limit: format!(
                    "the GPU memory budget, {} (set {MEMORY_BUDGET_ENV} in MiB to change it)",
                    format_bytes(self.memory_budget_bytes)
                ),
                raise: raise.to_owned(),
            });
        }
        Ok(())
    }

    /// How many elements of `element_bytes` one storage binding holds.
    pub fn storage_elements(&self, element_bytes: u64) -> u64 {
        self.max_storage_binding_bytes.min(self.max_buffer_bytes) / element_bytes.max(1)
    }
}

fn parse_mib(text: &str) -> Option<u64> {
    let mib: u64 = text.trim().parse().ok()?;
    (mib > 0).then(|| mib.checked_mul(1 << 20)).flatten()
}

/// `bytes` as a reader wants it: "1.06 GiB (1,140,850,688 bytes)".
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    let mut grouped = String::new();
    for (i, c) in bytes.to_string().chars().rev().enumerate() {
        if i > 0 && i % 3 == 0 {
            grouped.push(',');
        }
        grouped.push(c);
    }
    let grouped: String = grouped.chars().rev().collect();
    let mut value = bytes as f64;
    let mut unit = None;
    for u in UNITS {
        if value < 1024.0 {
            break;
        }
        value /= 1024.0;
        unit = Some(u);
    }
    match unit {
        None => format!("{grouped} bytes"),
        Some(u) => format!("{value:.2} {u} ({grouped} bytes)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lavapipe_like() -> DeviceLimits {
        DeviceLimits {
            max_texture_side: 8192,
            max_storage_binding_bytes: 128 << 20,
            max_buffer_bytes: 1 << 30,
            memory_budget_bytes: 1 << 30,
        }
    }

    #[test]
    fn requests_past_a_limit_name_it_and_the_way_round_it() {
        let l = lavapipe_like();
        l.texture("camera image", 8192, 4096, "lower it")
            .expect("at the limit");
        let e = l
            .texture(
                "camera image (camera.width x camera.height)",
                16384,
                768,
                "lower camera.width",
            )
            .expect_err("past the limit")
            .to_string();
        assert!(
            e.contains("16384x768") && e.contains("8192") && e.contains("lower camera.width"),
            "{e}"
        );
        l.storage("beams", 128 << 20, "lower max_beams")
            .expect("at the limit");
        let e = l
            .storage(
                "beams (max_beams x 288 bytes)",
                (128 << 20) + 1,
                "lower max_beams",
            )
            .expect_err("past the limit")
            .to_string();
        assert!(
            e.contains("max_storage_buffer_binding_size")
                && e.contains("128.00 MiB (134,217,728 bytes)")
                && e.contains("lower max_beams"),
            "{e}"
        );
        let e = l
            .memory("beam buffers", 3 << 30, "lower max_beams")
            .expect_err("past the budget")
            .to_string();
        assert!(
            e.contains(MEMORY_BUDGET_ENV) && e.contains("3.00 GiB"),
            "{e}"
        );
        assert_eq!(l.storage_elements(288), (128 << 20) / 288);
    }

    #[test]
    fn the_memory_budget_is_whole_mib() {
        assert_eq!(parse_mib("512"), Some(512 << 20));
        assert_eq!(parse_mib(" 1 "), Some(1 << 20));
        for bad in ["0", "-1", "1.5", "", "lots", "18446744073709551615"] {
            assert_eq!(parse_mib(bad), None, "{bad:?}");
        }
        assert_eq!(format_bytes(999), "999 bytes");
        assert_eq!(format_bytes(1536), "1.50 KiB (1,536 bytes)");
    }
}
