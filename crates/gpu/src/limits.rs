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
//!
//! The budget is summed, not per resource: [`GpuMemory`] is one ledger per device of
//! what every live resource holds (the scene's buffers, the camera-sized targets, each
//! method's textures and buffers). A resource reserves its bytes before it is made and
//! gives them back when dropped ([`Reservation`]), so a method that would fit alone but
//! not beside the camera targets and the scene is refused, naming what already holds
//! the budget.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use crate::GpuError;

pub use caustics_scene::{format_bytes, parse_mib};

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
    /// What all live resources together may hold, bytes (the ledger, [`GpuMemory`],
    /// sums them against it).
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

    /// How many elements of `element_bytes` one storage binding holds.
    pub fn storage_elements(&self, element_bytes: u64) -> u64 {
        self.max_storage_binding_bytes.min(self.max_buffer_bytes) / element_bytes.max(1)
    }
}

/// The GPU memory ledger of one device: what every live resource holds, summed against
/// the memory budget. Shared ([`Arc`]) by the context and every [`Reservation`].
#[derive(Debug)]
pub struct GpuMemory {
    budget_bytes: u64,
    next_id: AtomicU64,
    /// Live reservations by id: what holds them and how many bytes.
    held: Mutex<BTreeMap<u64, (String, u64)>>,
}

/// Bytes held in the ledger by one resource (or the buffers one pass sizes together),
/// given back when dropped: keep it beside the resource it stands for.
#[derive(Debug)]
pub struct Reservation {
    ledger: Arc<GpuMemory>,
    id: u64,
    bytes: u64,
}

impl Reservation {
    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

impl Drop for Reservation {
    fn drop(&mut self) {
        if let Ok(mut held) = self.ledger.held.lock() {
            held.remove(&self.id);
        }
    }
}

/// How many holders a refusal names (the largest first).
const HOLDERS_NAMED: usize = 4;

impl GpuMemory {
    /// An empty ledger under `budget_bytes`.
    pub fn new(budget_bytes: u64) -> Arc<Self> {
        Arc::new(Self {
            budget_bytes,
            next_id: AtomicU64::new(0),
            held: Mutex::new(BTreeMap::new()),
        })
    }

    /// The budget, bytes.
    pub fn budget_bytes(&self) -> u64 {
        self.budget_bytes
    }

    /// Bytes held by live reservations.
    pub fn held_bytes(&self) -> u64 {
        self.held
            .lock()
            .map(|h| h.values().map(|(_, b)| b).sum())
            .unwrap_or(0)
    }

    /// Checks that `bytes` more fit beside what is held, without holding them: for a
    /// request whose resources reserve their own bytes as they are made (the whole
    /// request is refused before the first of them).
    pub fn check(&self, what: &str, bytes: u64, raise: &str) -> Result<(), GpuError> {
        let held = self
            .held
            .lock()
            .map_err(|_| GpuError::Invalid("GPU memory ledger poisoned".into()))?;
        self.fits(&held, what, bytes, raise)
    }

    /// Holds `bytes` for `what` until the returned reservation is dropped, if they fit
    /// beside what is held; else refuses, naming the budget, the largest holders and
    /// `raise`.
    pub fn reserve(
        self: &Arc<Self>,
        what: &str,
        bytes: u64,
        raise: &str,
    ) -> Result<Reservation, GpuError> {
        let mut held = self
            .held
            .lock()
            .map_err(|_| GpuError::Invalid("GPU memory ledger poisoned".into()))?;
        self.fits(&held, what, bytes, raise)?;
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        held.insert(id, (what.to_owned(), bytes));
        Ok(Reservation {
            ledger: Arc::clone(self),
            id,
            bytes,
        })
    }

    fn fits(
        &self,
        held: &BTreeMap<u64, (String, u64)>,
        what: &str,
        bytes: u64,
        raise: &str,
    ) -> Result<(), GpuError> {
        let in_use: u64 = held.values().map(|(_, b)| b).sum();
        if in_use.saturating_add(bytes) <= self.budget_bytes {
            return Ok(());
        }
        let held_by = if in_use == 0 {
            String::new()
        } else {
            let mut holders: Vec<&(String, u64)> = held.values().collect();
            holders.sort_by_key(|h| std::cmp::Reverse(h.1));
            let mut named: Vec<String> = holders
                .iter()
                .take(HOLDERS_NAMED)
                .map(|(w, b)| format!("{w}: {}", format_bytes(*b)))
                .collect();
            if holders.len() > HOLDERS_NAMED {
                named.push(format!("{} more", holders.len() - HOLDERS_NAMED));
            }
            format!(
                ", with {} of it already held ({})",
                format_bytes(in_use),
                named.join("; ")
            )
        };
        Err(GpuError::OverLimit {
            what: what.to_owned(),
            needed: format_bytes(bytes),
            limit: format!(
                "the GPU memory budget, {}, summed over every live resource{held_by} (set {MEMORY_BUDGET_ENV} in MiB to change it)",
                format_bytes(self.budget_bytes)
            ),
            raise: raise.to_owned(),
        })
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
        assert_eq!(l.storage_elements(288), (128 << 20) / 288);
    }

    #[test]
    fn the_budget_is_summed_over_live_reservations() {
        let ledger = GpuMemory::new(1 << 30);
        let e = ledger
            .reserve("beam buffers", 3 << 30, "lower max_beams")
            .expect_err("past the budget alone")
            .to_string();
        assert!(
            e.contains(MEMORY_BUDGET_ENV) && e.contains("3.00 GiB") && !e.contains("already held"),
            "{e}"
        );
        let camera = ledger
            .reserve("camera targets", 600 << 20, "lower camera.width")
            .expect("fits alone");
        let scene = ledger
            .reserve("scene buffers", 100 << 20, "fewer triangles")
            .expect("fits beside the camera");
        assert_eq!(ledger.held_bytes(), 700 << 20);
        // 400 MiB fits alone, not beside the 700 held: refused, naming the holders.
        ledger
            .check("hit images", 300 << 20, "lower resolution")
            .expect("324 MiB are left");
        let e = ledger
            .reserve("hit images", 400 << 20, "lower resolution")
            .expect_err("past the budget summed")
            .to_string();
        assert!(
            e.starts_with("hit images: 400.00 MiB (419,430,400 bytes) needed, past the GPU memory budget, 1.00 GiB")
                && e.contains("with 700.00 MiB (734,003,200 bytes) of it already held (camera targets: 600.00 MiB (629,145,600 bytes); scene buffers: 100.00 MiB (104,857,600 bytes))")
                && e.ends_with("lower resolution"),
            "{e}"
        );
        assert_eq!(ledger.held_bytes(), 700 << 20, "a refusal holds nothing");
        drop(camera);
        let hits = ledger
            .reserve("hit images", 400 << 20, "lower resolution")
            .expect("fits once the camera targets are given back");
        assert_eq!(hits.bytes(), 400 << 20);
        drop((scene, hits));
        assert_eq!(ledger.held_bytes(), 0);
    }
}
