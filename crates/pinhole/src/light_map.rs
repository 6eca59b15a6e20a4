//! The light as an environment map (Wand & Straßer §3.1: "the incoming light as an
//! environment map").
//!
//! The map is the cube map of the light in a frame whose +Z axis points at the light's
//! centre (the disc's axis): the light then lies in the middle of the +Z face, never on a
//! seam, and the other five faces are empty, so only the +Z face is stored, as a 2D
//! texture addressed in the shader (s, t) = (x/z, y/z) of the lookup in that frame. It
//! holds the light's *coverage*: for each texel, the fraction of its solid angle inside a
//! cone of half angle `alpha` around +Z (4×4 supersamples per texel), 1 inside the
//! light's disc and 0 outside; the gather multiplies a lookup by the light's radiance.
//! The mip chain is built by 2×2 box averaging, so a level holds the mean coverage over
//! its footprint and the footprint filter averages the light without changing its
//! energy. R16Float: filterable on every adapter (32-bit float filtering is optional).
//! The addressing is done in the shader, not by a hardware cube lookup, because
//! lavapipe's cube sampling was measured to misplace light for long lookup vectors
//! (ghost images of the light far from it) and to ignore explicit gradients.
//! The bench's lights do not move, so the map is built once per scene; the paper
//! re-renders it per frame, which costs little next to the gather.

use caustics_gpu::limits::Reservation;
use caustics_gpu::wgpu;
use caustics_gpu::{GpuContext, GpuError};

/// The map on the GPU: a `size`² R16Float texture with its mip chain, and the
/// trilinear sampler the gather's footprint filter reads it with.
pub struct LightMap {
    /// View of every level.
    pub view: wgpu::TextureView,
    /// Linear min/mag/mip filtering.
    pub sampler: wgpu::Sampler,
    /// Bytes of the texture.
    pub bytes: u64,
    /// Those bytes in the device's memory ledger.
    _memory: Reservation,
}

impl LightMap {
    /// Builds the coverage of a cone of half angle `alpha` ([`coverage_mips`]) and
    /// uploads it, after checking its side against the device and reserving its bytes.
    pub fn new(ctx: &GpuContext, size: u32, alpha: f32) -> Result<Self, GpuError> {
        let what = format!("cube_size: the pinhole light map ({size}x{size}, R16Float with mips)");
        ctx.limits.texture(&what, size, size, "lower cube_size")?;
        // A full mip chain adds a third to level 0's 2 bytes a texel.
        let memory = ctx.memory.reserve(
            &what,
            (u64::from(size) * u64::from(size) * 2 * 4).div_ceil(3),
            "lower cube_size",
        )?;
        let levels = coverage_mips(size, alpha);
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("pinhole light map"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let bytes = upload_levels(
            ctx,
            &texture,
            2,
            levels.iter().enumerate().map(|(level, data)| {
                let w = (size >> level).max(1);
                let texels = data.iter().flat_map(|&v| f16_bits(v).to_le_bytes());
                (w, w, texels.collect())
            }),
        );
        Ok(Self {
            view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
            sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("pinhole light map"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            }),
            bytes,
            _memory: memory,
        })
    }
}

impl LightMap {
    /// An environment light's lat-long map (Mitsuba 3's convention, `EnvironmentMap`)
    /// as an Rgba16Float texture with its mip chain (2×2 box means; an odd side keeps
    /// its last column or row), divided by its peak so that any HDR map fits half
    /// floats: the gather multiplies by [`LightMap::environment`]'s returned peak. The
    /// sampler repeats in u (the seam at φ = ±π) and clamps in v (the poles).
    pub fn environment(
        ctx: &GpuContext,
        map: &caustics_scene::EnvironmentMap,
    ) -> Result<(Self, f32), GpuError> {
        let (w, h) = (map.width, map.height);
        let what = format!("the pinhole environment map ({w}x{h}, Rgba16Float with mips)");
        ctx.limits
            .texture(&what, w, h, "use a smaller environment map")?;
        let memory = ctx.memory.reserve(
            &what,
            (u64::from(w) * u64::from(h) * 8 * 4).div_ceil(3),
            "use a smaller environment map",
        )?;
        let peak = map
            .pixels
            .iter()
            .map(|p| p.max_element())
            .fold(0.0f32, f32::max)
            .max(1e-30);
        let mut levels = vec![(
            w,
            h,
            map.pixels.iter().map(|p| *p / peak).collect::<Vec<_>>(),
        )];
        while let Some((lw, lh, prev)) = levels.last().filter(|(lw, lh, _)| *lw > 1 || *lh > 1) {
            let (nw, nh) = ((lw / 2).max(1), (lh / 2).max(1));
            let at = |x: u32, y: u32| prev[(y.min(lh - 1) * lw + x.min(lw - 1)) as usize];
            let mut next = Vec::with_capacity((nw * nh) as usize);
            for y in 0..nh {
                for x in 0..nw {
                    next.push(
                        (at(2 * x, 2 * y)
                            + at(2 * x + 1, 2 * y)
                            + at(2 * x, 2 * y + 1)
                            + at(2 * x + 1, 2 * y + 1))
                            * 0.25,
                    );
                }
            }
            levels.push((nw, nh, next));
        }
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("pinhole environment map"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let bytes = upload_levels(
            ctx,
            &texture,
            8,
            levels.iter().map(|(lw, lh, data)| {
                let texels = data
                    .iter()
                    .flat_map(|p| [p.x, p.y, p.z, 1.0])
                    .flat_map(|v| f16_bits(v).to_le_bytes());
                (*lw, *lh, texels.collect())
            }),
        );
        Ok((
            Self {
                view: texture.create_view(&wgpu::TextureViewDescriptor::default()),
                sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("pinhole environment map"),
                    address_mode_u: wgpu::AddressMode::Repeat,
                    address_mode_v: wgpu::AddressMode::ClampToEdge,
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                }),
                bytes,
                _memory: memory,
            },
            peak,
        ))
    }
}

/// Writes each mip level (width, height, texel bytes) of `texture`, level 0 first;
/// returns the bytes written.
fn upload_levels(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
    levels: impl Iterator<Item = (u32, u32, Vec<u8>)>,
) -> u64 {
    let mut bytes = 0u64;
    for (level, (w, h, texels)) in levels.enumerate() {
        bytes += texels.len() as u64;
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_texel * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    }
    bytes
}

/// Coverage of each texel of a `size`² map of the +Z face by the cone of half angle
/// `alpha` (< 45°) around +Z, rows top first (t = −1 first); then each smaller mip
/// level down to 1×1.
pub fn coverage_mips(size: u32, alpha: f32) -> Vec<Vec<f32>> {
    const SUB: u32 = 4;
    let n = size as usize;
    let cos_alpha = alpha.cos();
    let inside = |s: f32, t: f32| 1.0 / (1.0 + s * s + t * t).sqrt() >= cos_alpha;
    // Texels whose centre is beyond tan(alpha) + a texel diagonal from the centre are empty.
    let reach = alpha.tan() + 3.0 / size as f32;
    let mut level0 = vec![0.0f32; n * n];
    for j in 0..n {
        for i in 0..n {
            let s = 2.0 * (i as f32 + 0.5) / size as f32 - 1.0;
            let t = 2.0 * (j as f32 + 0.5) / size as f32 - 1.0;
            if s * s + t * t > reach * reach {
                continue;
            }
            let mut count = 0;
            for sj in 0..SUB {
                for si in 0..SUB {
                    let s = 2.0 * (i as f32 + (si as f32 + 0.5) / SUB as f32) / size as f32 - 1.0;
                    let t = 2.0 * (j as f32 + (sj as f32 + 0.5) / SUB as f32) / size as f32 - 1.0;
                    if inside(s, t) {
                        count += 1;
                    }
                }
            }
            level0[j * n + i] = count as f32 / (SUB * SUB) as f32;
        }
    }
    let mut levels = vec![level0];
    let mut n = n;
    while n > 1 {
        let m = n / 2;
        let prev = levels.last().map(Vec::as_slice).unwrap_or(&[]);
        let mut next = vec![0.0f32; m * m];
        for j in 0..m {
            for i in 0..m {
                let at = |x: usize, y: usize| prev[y * n + x];
                next[j * m + i] = 0.25
                    * (at(2 * i, 2 * j)
                        + at(2 * i + 1, 2 * j)
                        + at(2 * i, 2 * j + 1)
                        + at(2 * i + 1, 2 * j + 1));
            }
        }
        levels.push(next);
        n = m;
    }
    levels
}

/// IEEE binary16 bits of `v` (round to nearest even; values here are in [0, 1]).
pub fn f16_bits(v: f32) -> u16 {
    let x = v.to_bits();
    let sign = ((x >> 16) & 0x8000) as u16;
    let exp = ((x >> 23) & 0xff) as i32;
    let mant = x & 0x7f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if mant != 0 { 0x200 } else { 0 };
    }
    let e = exp - 127 + 15;
    if e >= 0x1f {
        return sign | 0x7c00;
    }
    if e <= 0 {
        if e < -10 {
            return sign;
        }
        // Subnormal: shift the mantissa (with its implicit 1) into place, rounding.
        let m = mant | 0x80_0000;
        let shift = (14 - e) as u32;
        let half = 1u32 << (shift - 1);
        let rest = m & ((1u32 << shift) - 1);
        let mut h = m >> shift;
        if rest > half || (rest == half && h & 1 == 1) {
            h += 1;
        }
        return sign | h as u16;
    }
    let mut h = ((e as u32) << 10) | (mant >> 13);
    let rest = mant & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && h & 1 == 1) {
        h += 1;
    }
    sign | h as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_integrates_to_the_cone_solid_angle_on_every_level() {
        let (size, alpha) = (64u32, 0.3f32);
        let levels = coverage_mips(size, alpha);
        assert_eq!(levels.len(), 7);
        let want = std::f32::consts::TAU * (1.0 - alpha.cos());
        // Solid angle of a texel at face coords (s, t) of width w: w² / (1+s²+t²)^1.5.
        let n = size as usize;
        let w = 2.0 / size as f32;
        let mut got = 0.0;
        for j in 0..n {
            for i in 0..n {
                let s = (i as f32 + 0.5) * w - 1.0;
                let t = (j as f32 + 0.5) * w - 1.0;
                got += levels[0][j * n + i] * w * w / (1.0 + s * s + t * t).powf(1.5);
            }
        }
        assert!((got - want).abs() < 0.01 * want, "{got} vs {want}");
        // Box mips keep the mean.
        let mean = |l: &Vec<f32>| l.iter().sum::<f32>() / l.len() as f32;
        for l in &levels[1..] {
            assert!((mean(l) - mean(&levels[0])).abs() < 1e-6);
        }
    }

    #[test]
    fn half_floats_round_trip_known_values() {
        assert_eq!(f16_bits(1.0), 0x3c00);
        assert_eq!(f16_bits(0.5), 0x3800);
        assert_eq!(f16_bits(0.0), 0);
        assert_eq!(f16_bits(0.25 + 1.0 / 4096.0), 0x3401); // one step above 0.25
        assert_eq!(f16_bits(0.25 + 1.0 / 8192.0), 0x3400); // halfway: rounds to even
        assert_eq!(f16_bits(6.0e-8), 0x0001); // smallest subnormal
        assert_eq!(f16_bits(65536.0), 0x7c00);
    }
}
