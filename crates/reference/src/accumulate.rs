//! Deterministic accumulation: work units, batches, mean and standard-error images.
//!
//! Photons are traced in work units of a fixed size; unit k draws its random numbers
//! from a generator seeded by (seed, k) only, and belongs to batch k mod B. Units run
//! in parallel and return their splats; each batch image then adds its units' splats
//! in increasing unit order (batches in parallel, each by one thread), in `f64`. No sum
//! depends on scheduling or on the thread count, so images are bit-identical for any
//! thread count and any run, and tracing R rounds of B units (what [`Plan`] counts)
//! gives the same image whether they ran in one call or as the rounds of
//! `render_for`.
//!
//! With X_b the estimate of batch b (its sum over its photons, each photon's power
//! being a one-sample estimate, divided by the batch's photon count), the image is
//! the mean of the X_b and the per-pixel standard error of that mean is
//! sqrt(Σ_b (X_b − X̄)² / (B (B − 1))).

use rayon::prelude::*;

use crate::tracer::{Splat, UnitOutput};

/// The largest work unit, in photons.
pub(crate) const UNIT_PHOTONS: u32 = 1 << 14;
/// The smallest work unit, in photons (for small test renders).
pub(crate) const MIN_UNIT_PHOTONS: u32 = 1 << 8;

/// How many photons are traced: `rounds` rounds of one unit of `unit` photons per batch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Plan {
    pub(crate) unit: u32,
    pub(crate) rounds: u64,
    pub(crate) batches: u32,
}

impl Plan {
    /// The plan tracing at least `photons`: units of the next power of two of
    /// photons/B clamped to [`MIN_UNIT_PHOTONS`, `UNIT_PHOTONS`], whole rounds.
    /// Planning again for the returned photon count gives the same plan.
    pub(crate) fn for_photons(photons: u64, batches: u32) -> Plan {
        let per_batch = photons.div_ceil(batches as u64);
        let unit = per_batch
            .next_power_of_two()
            .clamp(MIN_UNIT_PHOTONS as u64, UNIT_PHOTONS as u64) as u32;
        Plan {
            unit,
            rounds: per_batch.div_ceil(unit as u64).max(1),
            batches,
        }
    }

    /// Photons traced.
    pub(crate) fn photons(&self) -> u64 {
        self.rounds * self.batches as u64 * self.unit as u64
    }
}

/// Per-batch sums of one image kind.
pub(crate) struct Batched {
    /// B images of `3 · pixels` sums.
    sums: Vec<Vec<f64>>,
}

impl Batched {
    pub(crate) fn new(batches: u32, pixels: usize) -> Batched {
        Batched {
            sums: (0..batches).map(|_| vec![0.0; 3 * pixels]).collect(),
        }
    }

    /// Adds the splats chosen by `pick` of `outs` (units `first`, `first` + 1, …).
    fn add(&mut self, first: u64, outs: &[UnitOutput], pick: fn(&UnitOutput) -> &[Splat]) {
        let b_count = self.sums.len() as u64;
        self.sums.par_iter_mut().enumerate().for_each(|(b, img)| {
            for (i, out) in outs.iter().enumerate() {
                if (first + i as u64) % b_count == b as u64 {
                    add_splats(img, pick(out));
                }
            }
        });
    }

    /// The mean image and its standard error, for `per_batch` photons per batch.
    pub(crate) fn finish(&self, per_batch: u64) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let b = self.sums.len();
        let pixels = self.sums.first().map_or(0, |s| s.len() / 3);
        let scale = 1.0 / per_batch as f64;
        (0..pixels)
            .into_par_iter()
            .map(|p| {
                let mut mean = [0f32; 3];
                let mut err = [0f32; 3];
                for c in 0..3 {
                    let x = |k: usize| self.sums[k][3 * p + c] * scale;
                    let m = (0..b).map(x).sum::<f64>() / b as f64;
                    let var = (0..b).map(|k| (x(k) - m).powi(2)).sum::<f64>();
                    mean[c] = m as f32;
                    err[c] = (var / (b as f64 * (b as f64 - 1.0))).sqrt() as f32;
                }
                (mean, err)
            })
            .unzip()
    }
}

fn add_splats(img: &mut [f64], splats: &[Splat]) {
    for s in splats {
        let i = 3 * s.pixel as usize;
        if let Some(px) = img.get_mut(i..i + 3) {
            for (acc, v) in px.iter_mut().zip(s.rgb) {
                *acc += v as f64;
            }
        }
    }
}

/// All the sums of one render.
pub(crate) struct Accumulator {
    pub(crate) surface: Batched,
    pub(crate) volume: Option<Batched>,
    pub(crate) direct: Option<Vec<f64>>,
    pub(crate) power: [f64; 3],
}

impl Accumulator {
    pub(crate) fn new(batches: u32, pixels: usize, volume: bool, direct: bool) -> Accumulator {
        Accumulator {
            surface: Batched::new(batches, pixels),
            volume: volume.then(|| Batched::new(batches, pixels)),
            direct: direct.then(|| vec![0.0; 3 * pixels]),
            power: [0.0; 3],
        }
    }

    /// Adds the outputs of units `first`, `first` + 1, … in unit order.
    pub(crate) fn add(&mut self, first: u64, outs: &[UnitOutput]) {
        let Accumulator {
            surface,
            volume,
            direct,
            power,
        } = self;
        rayon::join(
            || surface.add(first, outs, |o| &o.surface),
            || {
                if let Some(v) = volume {
                    v.add(first, outs, |o| &o.volume);
                }
                if let Some(d) = direct {
                    for o in outs {
                        add_splats(d, &o.direct);
                    }
                }
            },
        );
        for o in outs {
            for (acc, v) in power.iter_mut().zip(o.power) {
                *acc += v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_are_stable_under_replanning() {
        for (p, b) in [
            (1u64, 2u32),
            (1000, 16),
            (300_000, 16),
            (10_000_000, 16),
            (5, 3),
        ] {
            let plan = Plan::for_photons(p, b);
            assert!(plan.photons() >= p);
            assert_eq!(Plan::for_photons(plan.photons(), b), plan, "{p} {b}");
        }
        let full = Plan {
            unit: UNIT_PHOTONS,
            rounds: 7,
            batches: 16,
        };
        assert_eq!(Plan::for_photons(full.photons(), 16), full);
    }
}
