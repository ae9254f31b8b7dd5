//! Deterministic 2-D gradient noise, fractional Brownian motion and Musgrave's ridged
//! multifractal, all evaluated in metres.
//!
//! # Algorithm
//!
//! * [`gradient`] is Perlin's improved gradient noise (Perlin 2002, "Improving noise"): a unit
//!   gradient from a 16-direction table at every integer lattice point, dotted with the offset to
//!   the sample and blended with the quintic fade `6t^5 - 15t^4 + 10t^3`. The lattice gradient is
//!   chosen by a 64-bit integer hash of `(seed, ix, iy)` (a SplitMix64 finaliser) instead of a
//!   permutation table, so every layer and octave is independent and the lattice never repeats.
//! * [`Layer::fbm`] is fractional Brownian motion (Mandelbrot & Van Ness 1968; Musgrave in
//!   Ebert et al., *Texturing & Modeling*, 3rd ed., 2003, ch. 16): octaves at wavelengths
//!   `wavelength_m / lacunarity^i`, amplitudes `gain^i`, each octave rotated by a fixed angle to
//!   hide lattice alignment.
//! * [`Layer::ridged`] is Musgrave's ridged multifractal (same chapter): `(offset - |n|)^2`
//!   signals whose weight is the previous octave's signal times `gain`, which keeps valleys
//!   smooth and makes crests rough.
//!
//! # Scale correctness and determinism
//!
//! Coordinates are metres and every layer has a wavelength in metres, so a feature's size does not
//! depend on the post spacing. Octaves finer than twice the post spacing are faded out
//! ([`octave_weight`]), which band-limits the signal (no aliasing) while a 30 m and a 90 m grid
//! share every octave both can represent. Only IEEE-exact operations (`+ - * /`, `floor`, `abs`)
//! are used, so results are bit-identical on every conforming platform.
//!
//! # Limits
//!
//! Gradient noise is isotropic only approximately (16 directions); its output range is about
//! `[-1, 1]` but not strictly bounded. Coordinates must stay below about 1e15 lattice units.

use std::f64::consts::FRAC_1_SQRT_2;

/// 16 unit gradients, `(cos, sin)` of `k * 22.5 deg`, written out so no transcendental runs.
const GRADIENTS: [(f64, f64); 16] = [
    (1.0, 0.0),
    (0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
    (FRAC_1_SQRT_2, FRAC_1_SQRT_2),
    (0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
    (0.0, 1.0),
    (-0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
    (-FRAC_1_SQRT_2, FRAC_1_SQRT_2),
    (-0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
    (-1.0, 0.0),
    (-0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
    (-FRAC_1_SQRT_2, -FRAC_1_SQRT_2),
    (-0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
    (0.0, -1.0),
    (0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
    (FRAC_1_SQRT_2, -FRAC_1_SQRT_2),
    (0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
];

/// Rotation between octaves: `(cos, sin)` of about 36.87 deg (a 3-4-5 triangle, exact ratios).
const ROT_COS: f64 = 0.8;
const ROT_SIN: f64 = 0.6;

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z ^= z >> 30;
    z = z.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z ^= z >> 27;
    z = z.wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hash of a lattice point under a seed.
#[inline]
pub(crate) fn hash2(seed: u64, ix: i64, iy: i64) -> u64 {
    let a = (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let b = (iy as u64)
        .wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        .rotate_left(31);
    mix64(seed ^ a ^ b)
}

/// A hash mapped to `[0, 1)`.
#[inline]
pub(crate) fn unit_from_hash(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
}

#[inline]
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// `floor` for |x| < 2^62, inlined (std's `floor` is a library call on x86-64 without SSE4.1).
#[inline]
pub(crate) fn fast_floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// Gradient noise at `(x, y)` in lattice units, roughly in `[-1, 1]`, zero at lattice points.
#[inline]
pub(crate) fn gradient(seed: u64, x: f64, y: f64) -> f64 {
    let x0 = fast_floor(x);
    let y0 = fast_floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let ix = x0 as i64;
    let iy = y0 as i64;
    let corner = |dx: i64, dy: i64, ox: f64, oy: f64| {
        let (gx, gy) = GRADIENTS[(hash2(seed, ix + dx, iy + dy) >> 60) as usize];
        gx * ox + gy * oy
    };
    let n00 = corner(0, 0, fx, fy);
    let n10 = corner(1, 0, fx - 1.0, fy);
    let n01 = corner(0, 1, fx, fy - 1.0);
    let n11 = corner(1, 1, fx - 1.0, fy - 1.0);
    let u = fade(fx);
    let v = fade(fy);
    // The extreme of 2-D Perlin noise with unit gradients is sqrt(1/2); scale to about [-1, 1].
    lerp(lerp(n00, n10, u), lerp(n01, n11, u), v) * std::f64::consts::SQRT_2
}

/// Weight in `[0, 1]` of an octave of wavelength `wavelength_m` on posts `spacing_m` apart:
/// 1 from four post spacings up, fading linearly to 0 at two (the Nyquist limit).
#[inline]
pub(crate) fn octave_weight(wavelength_m: f64, spacing_m: f64) -> f64 {
    ((wavelength_m / (2.0 * spacing_m)) - 1.0).clamp(0.0, 1.0)
}

/// One noise layer: a seed, a wavelength in metres and a random offset of the domain.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layer {
    seed: u64,
    offset_x: f64,
    offset_y: f64,
    /// Wavelength of the first octave, metres.
    pub wavelength_m: f64,
}

impl Layer {
    /// A layer whose seed and domain offset derive from `seed`.
    pub(crate) fn new(seed: u64, wavelength_m: f64) -> Layer {
        let a = mix64(seed ^ 0x5851_F42D_4C95_7F2D);
        let b = mix64(a ^ 0x1405_7B7E_F767_814F);
        Layer {
            seed: mix64(b),
            // Offsets of up to 4096 wavelengths keep the lattice far from the origin's symmetry.
            offset_x: unit_from_hash(a) * 4096.0,
            offset_y: unit_from_hash(b) * 4096.0,
            wavelength_m,
        }
    }

    /// Fractional Brownian motion normalised to about `[-1, 1]`: `octaves` octaves (the last may
    /// be fractional), wavelength divided by `lacunarity` and amplitude multiplied by `gain` per
    /// octave; octaves finer than `2 * spacing_m` are faded out.
    pub(crate) fn fbm(
        &self,
        x_m: f64,
        y_m: f64,
        octaves: usize,
        lacunarity: f64,
        gain: f64,
        spacing_m: f64,
    ) -> f64 {
        let inv = 1.0 / self.wavelength_m;
        let mut x = x_m * inv + self.offset_x;
        let mut y = y_m * inv + self.offset_y;
        let mut wavelength = self.wavelength_m;
        let mut amp = 1.0;
        let mut sum = 0.0;
        let mut norm = 0.0;
        let mut seed = self.seed;
        for _ in 0..octaves {
            let w = octave_weight(wavelength, spacing_m);
            if w <= 0.0 {
                break;
            }
            sum += amp * w * gradient(seed, x, y);
            norm += amp;
            (x, y, seed) = next_octave(x, y, seed, lacunarity);
            wavelength /= lacunarity;
            amp *= gain;
        }
        if norm > 0.0 {
            sum / norm
        } else {
            0.0
        }
    }

    /// Musgrave's ridged multifractal with `offset = 1`, weight gain 2 and spectral
    /// exponent `h`: about `[0, 1]` (1 on the sharpest crests), normalised by the sum of the
    /// octave amplitudes. Octaves finer than `2 * spacing_m` are faded out.
    pub(crate) fn ridged(
        &self,
        x_m: f64,
        y_m: f64,
        octaves: usize,
        lacunarity: f64,
        h: f64,
        spacing_m: f64,
    ) -> f64 {
        const GAIN: f64 = 2.0;
        let inv = 1.0 / self.wavelength_m;
        let mut x = x_m * inv + self.offset_x;
        let mut y = y_m * inv + self.offset_y;
        let mut wavelength = self.wavelength_m;
        // Amplitude of octave i is lacunarity^(-i h); computed with libm so it is exact anywhere.
        let amp_step = libm::pow(lacunarity, -h);
        let mut amp = 1.0;
        let mut weight = 1.0;
        let mut sum = 0.0;
        let mut norm = 0.0;
        let mut seed = self.seed;
        for _ in 0..octaves {
            let w = octave_weight(wavelength, spacing_m);
            if w <= 0.0 {
                break;
            }
            let mut signal = 1.0 - gradient(seed, x, y).abs();
            signal *= signal;
            signal *= weight;
            weight = (signal * GAIN).clamp(0.0, 1.0);
            sum += signal * amp * w;
            norm += amp;
            (x, y, seed) = next_octave(x, y, seed, lacunarity);
            wavelength /= lacunarity;
            amp *= amp_step;
        }
        if norm > 0.0 {
            sum / norm
        } else {
            0.0
        }
    }
}

/// Cubic smoothstep of `x` between `e0` and `e1`.
#[inline]
pub(crate) fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Moves sample coordinates to the next octave: rotated (so octave lattices do not align),
/// scaled by `lacunarity`, offset, and given a fresh seed.
#[inline]
fn next_octave(x: f64, y: f64, seed: u64, lacunarity: f64) -> (f64, f64, u64) {
    let (rx, ry) = (ROT_COS * x - ROT_SIN * y, ROT_SIN * x + ROT_COS * y);
    (
        rx * lacunarity + 17.31,
        ry * lacunarity - 5.77,
        mix64(seed.wrapping_add(0x9E37_79B9_7F4A_7C15)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_noise_is_zero_on_the_lattice_and_bounded() {
        let mut max = 0.0f64;
        for i in 0..20_000 {
            let x = i as f64 * 0.137 - 300.0;
            let y = i as f64 * 0.071 + 11.0;
            let n = gradient(7, x, y);
            max = max.max(n.abs());
        }
        assert!(max > 0.5 && max <= 1.0 + 1e-9, "max |n| = {max}");
        assert_eq!(gradient(7, 3.0, -4.0), 0.0);
    }

    #[test]
    fn fbm_mean_is_near_zero_and_layers_differ() {
        let a = Layer::new(1, 1000.0);
        let b = Layer::new(2, 1000.0);
        let mut mean = 0.0;
        let mut diff = 0.0;
        let n = 10_000;
        for i in 0..n {
            let x = (i % 100) as f64 * 230.0;
            let y = (i / 100) as f64 * 230.0;
            let va = a.fbm(x, y, 4, 2.0, 0.5, 30.0);
            mean += va;
            diff += (va - b.fbm(x, y, 4, 2.0, 0.5, 30.0)).abs();
        }
        mean /= n as f64;
        diff /= n as f64;
        assert!(mean.abs() < 0.05, "mean {mean}");
        assert!(diff > 0.1, "layers too similar: {diff}");
    }

    #[test]
    fn octaves_below_nyquist_are_dropped() {
        assert_eq!(octave_weight(50.0, 30.0), 0.0);
        assert_eq!(octave_weight(120.0, 30.0), 1.0);
        assert!((octave_weight(90.0, 30.0) - 0.5).abs() < 1e-12);
    }
}
