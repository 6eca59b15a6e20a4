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

/// Pixels per tile of a batch image (row-major runs of the image).
const TILE: usize = 16;
/// Tiles per task of the final reduction.
const TILES_PER_TASK: usize = 32;
/// No tile stored.
const NO_TILE: u32 = u32::MAX;

/// One batch's sums, stored sparsely: only tiles of [`TILE`] pixels that received a
/// splat hold memory (caustics cover a small part of most images, and a dense
/// `f64` image per batch made allocating, zeroing and reducing them a large fixed
/// cost of every render). A missing tile reads as zeros, so the sums are exactly
/// those of a dense image.
struct Sparse {
    /// Per tile: its index in `data`, or [`NO_TILE`].
    tiles: Vec<u32>,
    /// Stored tiles, `3 · TILE` sums each.
    data: Vec<f64>,
}

impl Sparse {
    fn new(pixels: usize) -> Sparse {
        let tiles = pixels.div_ceil(TILE);
        Sparse {
            tiles: vec![NO_TILE; tiles],
            // Reserved, not touched: pages are mapped only as tiles are stored, and
            // the buffer never moves.
            data: Vec::with_capacity(tiles * 3 * TILE),
        }
    }

    /// Bytes of the stored tiles.
    fn stored_bytes(&self) -> u64 {
        (self.data.len() * std::mem::size_of::<f64>()) as u64
    }

    /// The sums of tile `t`, if stored.
    #[inline]
    fn tile(&self, t: usize) -> Option<&[f64]> {
        let k = self.tiles[t];
        (k != NO_TILE).then(|| &self.data[k as usize * 3 * TILE..(k as usize + 1) * 3 * TILE])
    }

    fn add_splats(&mut self, splats: &[Splat]) {
        for s in splats {
            let p = s.pixel as usize;
            let Some(slot) = self.tiles.get_mut(p / TILE) else {
                continue;
            };
            if *slot == NO_TILE {
                *slot = (self.data.len() / (3 * TILE)) as u32;
                self.data.resize(self.data.len() + 3 * TILE, 0.0);
            }
            let i = *slot as usize * 3 * TILE + 3 * (p % TILE);
            let px = &mut self.data[i..i + 3];
            for (acc, v) in px.iter_mut().zip(s.rgb) {
                *acc += v as f64;
            }
        }
    }
}

/// Per-batch sums of one image kind.
pub(crate) struct Batched {
    sums: Vec<Sparse>,
    pixels: usize,
}

impl Batched {
    pub(crate) fn new(batches: u32, pixels: usize) -> Batched {
        Batched {
            sums: (0..batches).map(|_| Sparse::new(pixels)).collect(),
            pixels,
        }
    }

    /// Bytes of the tiles stored over all batches (what grows as the caustic spreads).
    fn stored_bytes(&self) -> u64 {
        self.sums.iter().map(Sparse::stored_bytes).sum()
    }

    /// Adds the splats chosen by `pick` of `outs` (units `first`, `first` + 1, …).
    fn add(&mut self, first: u64, outs: &[UnitOutput], pick: fn(&UnitOutput) -> &[Splat]) {
        let b_count = self.sums.len() as u64;
        self.sums.par_iter_mut().enumerate().for_each(|(b, img)| {
            for (i, out) in outs.iter().enumerate() {
                if (first + i as u64) % b_count == b as u64 {
                    img.add_splats(pick(out));
                }
            }
        });
    }

    /// The mean image and its standard error, for `per_batch` photons per batch.
    pub(crate) fn finish(&self, per_batch: u64) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let scale = 1.0 / per_batch as f64;
        let mut mean = vec![[0f32; 3]; self.pixels];
        let mut err = vec![[0f32; 3]; self.pixels];
        let task = TILE * TILES_PER_TASK;
        mean.par_chunks_mut(task)
            .zip(err.par_chunks_mut(task))
            .enumerate()
            .for_each(|(k, (mean, err))| {
                let tiles = mean.chunks_mut(TILE).zip(err.chunks_mut(TILE));
                for (t, (mean, err)) in tiles.enumerate() {
                    self.finish_tile(k * TILES_PER_TASK + t, scale, mean, err);
                }
            });
        (mean, err)
    }

    /// [`Batched::finish`] for tile `t`.
    fn finish_tile(&self, t: usize, scale: f64, mean: &mut [[f32; 3]], err: &mut [[f32; 3]]) {
        let b = self.sums.len();
        if self.sums.iter().all(|s| s.tile(t).is_none()) {
            return;
        }
        // Missing tiles are zeros: the same sums, in the same batch order, as a
        // dense image (x + 0 = x for the non-negative sums).
        let n = 3 * mean.len();
        let mut m = [0f64; 3 * TILE];
        for s in self.sums.iter().filter_map(|s| s.tile(t)) {
            for (m, v) in m[..n].iter_mut().zip(&s[..n]) {
                *m += v * scale;
            }
        }
        for m in &mut m[..n] {
            *m /= b as f64;
        }
        let mut var = [0f64; 3 * TILE];
        for s in &self.sums {
            match s.tile(t) {
                Some(s) => {
                    for ((acc, v), m) in var[..n].iter_mut().zip(&s[..n]).zip(&m[..n]) {
                        *acc += (v * scale - m) * (v * scale - m);
                    }
                }
                None => {
                    for (acc, m) in var[..n].iter_mut().zip(&m[..n]) {
                        *acc += m * m;
                    }
                }
            }
        }
        let norm = b as f64 * (b as f64 - 1.0);
        for (p, (mean, err)) in mean.iter_mut().zip(err.iter_mut()).enumerate() {
            for c in 0..3 {
                mean[c] = m[3 * p + c] as f32;
                err[c] = (var[3 * p + c] / norm).sqrt() as f32;
            }
        }
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
    /// Bytes held whatever the photons do, for `pixels` pixels: the per-batch tile
    /// indices, the dense direct sums, and the finished mean and standard-error images
    /// (`f32` RGB each) of every kind.
    pub(crate) fn fixed_bytes(batches: u32, pixels: usize, volume: bool, direct: bool) -> u64 {
        let pixels = pixels as u64;
        let kinds = 1 + u64::from(volume);
        let tile_index = u64::from(batches) * pixels.div_ceil(TILE as u64) * 4;
        let finished = 2 * 12 * pixels;
        kinds * (tile_index + finished) + u64::from(direct) * (24 + 12) * pixels
    }

    /// Bytes of the batch tiles stored so far (they grow with the caustic's area, up to
    /// 24 bytes a pixel per batch and kind).
    pub(crate) fn stored_bytes(&self) -> u64 {
        self.surface.stored_bytes() + self.volume.as_ref().map_or(0, Batched::stored_bytes)
    }

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
