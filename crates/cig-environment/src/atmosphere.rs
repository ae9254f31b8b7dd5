//! A physically based Earth atmosphere: transmittance, single and multiple scattering, sky
//! radiance and sky irradiance.
//!
//! Algorithm: the atmosphere of E. Bruneton, "A Qualitative and Quantitative Evaluation of 8
//! Clear Sky Models" / "Precomputed Atmospheric Scattering" (2017 reference implementation
//! parameters) as used by S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere
//! Rendering Technique" (EGSR 2020): a spherical planet of radius 6360 km under a 100 km shell;
//! Rayleigh scattering (scale height 8 km, β = 5.802, 13.558, 33.1 ×10⁻⁶ /m at 680, 550,
//! 440 nm, phase `3/(16π)(1+μ²)`), Mie scattering (scale height 1.2 km, scattering 3.996×10⁻⁶ /m,
//! extinction 4.44×10⁻⁶ /m, Cornette–Shanks phase with g = 0.8), an ozone layer absorbing
//! (0.650, 1.881, 0.085)×10⁻⁶ /m at its peak, a tent profile between 10 and 40 km peaking at
//! 25 km, and a Lambertian ground of albedo 0.3. Channels are red, green and blue (680, 550,
//! 440 nm), as linear sRGB primaries.
//!
//! - Transmittance to the top of the atmosphere is tabulated in Bruneton's (r, μ) mapping
//!   (section 4 of the 2017 documentation: `x_r = ρ/H`, `x_μ = (d − d_min)/(d_max − d_min)`)
//!   on a 256 × 64 grid, by a 64-step midpoint integral of the extinction (steps growing
//!   quadratically from the start).
//! - Multiple scattering follows Hillaire 2020 section 5.5: for each altitude and sun zenith
//!   cosine (32 × 32), second-order light `L₂` and the transfer factor `f_ms` are integrated over
//!   64 directions with an isotropic phase, and all orders are summed as the geometric series
//!   `Ψ_ms = L₂ / (1 − f_ms)` (ground bounce included).
//! - [`Atmosphere::sky_radiance`] marches a view ray (32 steps, energy-conserving step integral
//!   of Hillaire's section 5.2) adding single scattering (sun transmittance from the table, the
//!   planet's shadow giving the earth's shadow at dusk) and `σ_s Ψ_ms`.
//! - [`Atmosphere::sky_irradiance`] integrates the sky radiance on a horizontal surface from a
//!   table over (altitude, sun zenith cosine) filled with a 6 × 16 direction quadrature.
//!
//! All radiances are per unit solar illuminance at the top of the atmosphere (1/sr);
//! illuminances are fractions of it. Multiply by [`SUN_ILLUMINANCE_TOA_LUX`] for lux and cd/m².
//!
//! Limits: three wavelengths stand in for the spectrum (no spectral rendering, so colours near
//! the horizon at deep twilight are approximate); a clear standard atmosphere (no humidity or
//! volcanic aerosol, no refraction of the view rays); the sun is a point for scattering; the
//! planet is a sphere (altitudes above the WGS84 ellipsoid are used as heights above it).

use std::sync::OnceLock;

/// Solar illuminance at the top of the atmosphere at 1 AU, lux (the extraterrestrial solar
/// illuminance, about 128 klx; it gives about 1.2×10⁵ lux at the ground for a zenith sun).
pub const SUN_ILLUMINANCE_TOA_LUX: f64 = 128_000.0;

/// The sun's angular radius, degrees (mean, 0.2666°).
pub const SUN_ANGULAR_RADIUS_DEG: f64 = 0.2666;

/// Transmittance table size (μ, r).
pub const TRANSMITTANCE_LUT_SIZE: (usize, usize) = (256, 64);
/// Multiple-scattering table size (sun zenith cosine, altitude).
pub const MULTI_SCATTERING_LUT_SIZE: (usize, usize) = (32, 32);
/// Sky-irradiance table size (sun zenith cosine, altitude).
const IRRADIANCE_LUT_SIZE: (usize, usize) = (64, 16);

/// Parameters of a planetary atmosphere (SI units; coefficients per metre, per channel R, G, B).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtmosphereParams {
    pub bottom_radius_m: f64,
    pub top_radius_m: f64,
    pub rayleigh_scattering_per_m: [f64; 3],
    pub rayleigh_scale_height_m: f64,
    pub mie_scattering_per_m: f64,
    pub mie_extinction_per_m: f64,
    pub mie_scale_height_m: f64,
    /// Cornette–Shanks asymmetry.
    pub mie_g: f64,
    /// Ozone absorption at the layer's peak density.
    pub ozone_absorption_per_m: [f64; 3],
    /// Altitude of the ozone peak; the density falls linearly to 0 at ± `ozone_half_width_m`.
    pub ozone_peak_altitude_m: f64,
    pub ozone_half_width_m: f64,
    pub ground_albedo: [f64; 3],
}

impl AtmosphereParams {
    /// The Earth's clear standard atmosphere (Bruneton 2017, Hillaire 2020 defaults).
    pub const EARTH: AtmosphereParams = AtmosphereParams {
        bottom_radius_m: 6_360_000.0,
        top_radius_m: 6_460_000.0,
        rayleigh_scattering_per_m: [5.802e-6, 13.558e-6, 33.1e-6],
        rayleigh_scale_height_m: 8000.0,
        mie_scattering_per_m: 3.996e-6,
        mie_extinction_per_m: 4.44e-6,
        mie_scale_height_m: 1200.0,
        mie_g: 0.8,
        ozone_absorption_per_m: [0.650e-6, 1.881e-6, 0.085e-6],
        ozone_peak_altitude_m: 25_000.0,
        ozone_half_width_m: 15_000.0,
        ground_albedo: [0.3, 0.3, 0.3],
    };

    /// Relative densities (Rayleigh, Mie, ozone) at an altitude.
    pub fn densities(&self, altitude_m: f64) -> (f64, f64, f64) {
        let h = altitude_m.max(0.0);
        let rayleigh = (-h / self.rayleigh_scale_height_m).exp();
        let mie = (-h / self.mie_scale_height_m).exp();
        let ozone = (1.0 - (h - self.ozone_peak_altitude_m).abs() / self.ozone_half_width_m)
            .clamp(0.0, 1.0);
        (rayleigh, mie, ozone)
    }

    /// Extinction coefficient at an altitude, per channel, 1/m.
    pub fn extinction_per_m(&self, altitude_m: f64) -> [f64; 3] {
        let (r, m, o) = self.densities(altitude_m);
        std::array::from_fn(|c| {
            self.rayleigh_scattering_per_m[c] * r
                + self.mie_extinction_per_m * m
                + self.ozone_absorption_per_m[c] * o
        })
    }

    /// (Rayleigh, Mie) scattering coefficients at an altitude, per channel, 1/m.
    pub fn scattering_per_m(&self, altitude_m: f64) -> ([f64; 3], [f64; 3]) {
        let (r, m, _) = self.densities(altitude_m);
        (
            self.rayleigh_scattering_per_m.map(|b| b * r),
            [self.mie_scattering_per_m * m; 3],
        )
    }

    fn horizon_h(&self) -> f64 {
        (self.top_radius_m * self.top_radius_m - self.bottom_radius_m * self.bottom_radius_m).sqrt()
    }
}

/// Rayleigh phase function, 1/sr.
pub fn rayleigh_phase(cos_theta: f64) -> f64 {
    3.0 / (16.0 * std::f64::consts::PI) * (1.0 + cos_theta * cos_theta)
}

/// Cornette–Shanks phase function, 1/sr.
pub fn cornette_shanks_phase(g: f64, cos_theta: f64) -> f64 {
    let g2 = g * g;
    let denom = (1.0 + g2 - 2.0 * g * cos_theta).max(1e-9);
    3.0 / (8.0 * std::f64::consts::PI) * (1.0 - g2) * (1.0 + cos_theta * cos_theta)
        / ((2.0 + g2) * denom * denom.sqrt())
}

/// Distance along a ray from radius `r` with zenith cosine `mu` to the sphere of radius
/// `radius`, the far intersection (None when the ray misses it).
fn distance_to_sphere_far(r: f64, mu: f64, radius: f64) -> Option<f64> {
    let disc = r * r * (mu * mu - 1.0) + radius * radius;
    (disc >= 0.0).then(|| (-r * mu + disc.sqrt()).max(0.0))
}

/// Distance to the ground along a ray, None when the ray does not hit it.
fn distance_to_ground(r: f64, mu: f64, bottom: f64) -> Option<f64> {
    let disc = r * r * (mu * mu - 1.0) + bottom * bottom;
    if mu < 0.0 && disc >= 0.0 {
        Some((-r * mu - disc.sqrt()).max(0.0))
    } else {
        None
    }
}

/// A table of RGB values over a unit square, bilinearly interpolated, clamped at the edges.
#[derive(Clone, Debug, PartialEq)]
pub struct Lut {
    pub width: usize,
    pub height: usize,
    /// Row-major RGBA (alpha 1), rows from v = 0.
    pub texels: Vec<[f32; 4]>,
}

impl Lut {
    fn from_fn(width: usize, height: usize, f: impl Fn(f64, f64) -> [f64; 3]) -> Lut {
        let mut texels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                // The first and last texel centres hold the unit range's ends (Bruneton's
                // `GetTextureCoordFromUnitRange`); the GPU samples at 0.5/n + u (1 − 1/n).
                let u = x as f64 / (width - 1).max(1) as f64;
                let v = y as f64 / (height - 1).max(1) as f64;
                let c = f(u, v);
                texels.push([c[0] as f32, c[1] as f32, c[2] as f32, 1.0]);
            }
        }
        Lut {
            width,
            height,
            texels,
        }
    }

    /// Bilinear lookup at (u, v) in [0, 1]² (texel i at the unit coordinate i/(n − 1)).
    pub fn sample(&self, u: f64, v: f64) -> [f64; 3] {
        let fx = u.clamp(0.0, 1.0) * (self.width - 1) as f64;
        let fy = v.clamp(0.0, 1.0) * (self.height - 1) as f64;
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let at = |x: usize, y: usize| {
            self.texels
                .get(y * self.width + x)
                .copied()
                .unwrap_or([0.0; 4])
        };
        let (a, b, c, d) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
        std::array::from_fn(|i| {
            let top = f64::from(a[i]) * (1.0 - tx) + f64::from(b[i]) * tx;
            let bottom = f64::from(c[i]) * (1.0 - tx) + f64::from(d[i]) * tx;
            top * (1.0 - ty) + bottom * ty
        })
    }
}

/// The atmosphere with its precomputed tables.
#[derive(Clone, Debug)]
pub struct Atmosphere {
    pub params: AtmosphereParams,
    /// Transmittance to the top of the atmosphere, (x_μ, x_r) of Bruneton's mapping.
    pub transmittance: Lut,
    /// Hillaire's Ψ_ms, (μ_s × 0.5 + 0.5, altitude / thickness).
    pub multi_scattering: Lut,
    /// Sky irradiance on a horizontal surface, (μ_s × 0.5 + 0.5, altitude / thickness).
    irradiance: Lut,
}

impl Atmosphere {
    /// The Earth's atmosphere, computed once per process and shared.
    pub fn earth() -> &'static Atmosphere {
        static EARTH: OnceLock<Atmosphere> = OnceLock::new();
        EARTH.get_or_init(|| Atmosphere::new(AtmosphereParams::EARTH))
    }

    /// Computes the tables of an atmosphere (a few hundred milliseconds in an optimised build).
    pub fn new(params: AtmosphereParams) -> Atmosphere {
        let (tw, th) = TRANSMITTANCE_LUT_SIZE;
        let transmittance = Lut::from_fn(tw, th, |u, v| {
            let (r, mu) = transmittance_uv_to_r_mu(&params, u, v);
            integrate_transmittance(&params, r, mu)
        });
        let mut atmosphere = Atmosphere {
            params,
            transmittance,
            multi_scattering: Lut {
                width: 1,
                height: 1,
                texels: vec![[0.0; 4]],
            },
            irradiance: Lut {
                width: 1,
                height: 1,
                texels: vec![[0.0; 4]],
            },
        };
        let (mw, mh) = MULTI_SCATTERING_LUT_SIZE;
        atmosphere.multi_scattering = Lut::from_fn(mw, mh, |u, v| {
            let mu_s = (u * 2.0 - 1.0).clamp(-1.0, 1.0);
            let r = params.bottom_radius_m + v * (params.top_radius_m - params.bottom_radius_m);
            atmosphere.integrate_multi_scattering(r, mu_s)
        });
        let (iw, ih) = IRRADIANCE_LUT_SIZE;
        atmosphere.irradiance = Lut::from_fn(iw, ih, |u, v| {
            let mu_s = (u * 2.0 - 1.0).clamp(-1.0, 1.0);
            let altitude_m = v * (params.top_radius_m - params.bottom_radius_m);
            atmosphere.integrate_sky_irradiance(altitude_m, mu_s)
        });
        atmosphere
    }

    fn thickness_m(&self) -> f64 {
        self.params.top_radius_m - self.params.bottom_radius_m
    }

    fn radius(&self, altitude_m: f64) -> f64 {
        self.params.bottom_radius_m + altitude_m.clamp(0.0, self.thickness_m() - 1.0)
    }

    /// Transmittance from radius `r` along zenith cosine `mu` to the top of the atmosphere, from
    /// the table (0 where the ray meets the ground).
    pub fn transmittance_to_top(&self, r: f64, mu: f64) -> [f64; 3] {
        let p = &self.params;
        if distance_to_ground(r, mu, p.bottom_radius_m).is_some() {
            return [0.0; 3];
        }
        let (u, v) = transmittance_r_mu_to_uv(p, r, mu);
        self.transmittance.sample(u, v)
    }

    /// Transmittance of sunlight reaching radius `r` with the sun at zenith cosine `mu_s`,
    /// the sun's disc partly below the planet's horizon fading linearly (Bruneton 2017).
    fn sun_transmittance_at(&self, r: f64, mu_s: f64) -> [f64; 3] {
        let p = &self.params;
        let sin_h = p.bottom_radius_m / r;
        let cos_h = -(1.0 - sin_h * sin_h).max(0.0).sqrt();
        let radius = SUN_ANGULAR_RADIUS_DEG.to_radians();
        let visible = ((mu_s - cos_h) / (2.0 * radius * sin_h) + 0.5).clamp(0.0, 1.0);
        if visible <= 0.0 {
            return [0.0; 3];
        }
        let (u, v) = transmittance_r_mu_to_uv(p, r, mu_s.max(cos_h));
        self.transmittance.sample(u, v).map(|t| t * visible)
    }

    /// Transmittance of the direct sunlight reaching an observer at `altitude_m` with the sun
    /// `sun_altitude_deg` above the (geometric) horizon: the sun's colour at the eye is this
    /// times the solar illuminance at the top of the atmosphere.
    pub fn sun_transmittance(&self, altitude_m: f64, sun_altitude_deg: f64) -> [f64; 3] {
        if !altitude_m.is_finite() || !sun_altitude_deg.is_finite() {
            return [0.0; 3];
        }
        let mu_s = sun_altitude_deg.clamp(-90.0, 90.0).to_radians().sin();
        self.sun_transmittance_at(self.radius(altitude_m), mu_s)
    }

    /// Sky irradiance on a horizontal surface at `altitude_m`, per unit solar illuminance at
    /// the top of the atmosphere, for a sun `sun_altitude_deg` above the horizon (the diffuse
    /// skylight, not the direct sun).
    pub fn sky_irradiance(&self, altitude_m: f64, sun_altitude_deg: f64) -> [f64; 3] {
        if !altitude_m.is_finite() || !sun_altitude_deg.is_finite() {
            return [0.0; 3];
        }
        let mu_s = sun_altitude_deg.clamp(-90.0, 90.0).to_radians().sin();
        let v = altitude_m.clamp(0.0, self.thickness_m()) / self.thickness_m();
        self.irradiance.sample(mu_s * 0.5 + 0.5, v)
    }

    /// Hillaire's Ψ_ms at radius `r` for sun zenith cosine `mu_s`.
    pub fn multi_scattering_at(&self, r: f64, mu_s: f64) -> [f64; 3] {
        let v = (r - self.params.bottom_radius_m) / self.thickness_m();
        self.multi_scattering.sample(mu_s * 0.5 + 0.5, v)
    }

    /// Sky radiance (1/sr, per unit solar illuminance at the top of the atmosphere) seen from
    /// `altitude_m` along the unit `view_dir` (east-north-up, any frame with z up) with the
    /// sun along the unit `sun_dir`: single and multiple scattering, without the sun's disc.
    /// Rays that meet the ground stop there (the ground itself is not added).
    pub fn sky_radiance(&self, altitude_m: f64, view_dir: [f64; 3], sun_dir: [f64; 3]) -> [f64; 3] {
        self.march(altitude_m, view_dir, sun_dir, f64::INFINITY, 32)
            .0
    }

    /// In-scattered radiance and transmittance along `view_dir` from `altitude_m` up to
    /// `max_distance_m` (aerial perspective), `steps` march steps.
    pub fn march(
        &self,
        altitude_m: f64,
        view_dir: [f64; 3],
        sun_dir: [f64; 3],
        max_distance_m: f64,
        steps: usize,
    ) -> ([f64; 3], [f64; 3]) {
        let p = &self.params;
        let norm = |v: [f64; 3]| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.0 && l.is_finite() {
                v.map(|c| c / l)
            } else {
                [0.0, 0.0, 1.0]
            }
        };
        let (view, sun) = (norm(view_dir), norm(sun_dir));
        if !altitude_m.is_finite() {
            return ([0.0; 3], [1.0; 3]);
        }
        let r = self.radius(altitude_m);
        let mu = view[2];
        let Some(top) = distance_to_sphere_far(r, mu, p.top_radius_m) else {
            return ([0.0; 3], [1.0; 3]);
        };
        let length = distance_to_ground(r, mu, p.bottom_radius_m)
            .unwrap_or(top)
            .min(max_distance_m.max(0.0));
        let nu = view[0] * sun[0] + view[1] * sun[1] + view[2] * sun[2];
        let phase_r = rayleigh_phase(nu);
        let phase_m = cornette_shanks_phase(p.mie_g, nu);
        let mut radiance = [0.0; 3];
        let mut throughput = [1.0; 3];
        let steps = steps.max(1);
        let mut t_prev = 0.0;
        for i in 0..steps {
            // Steps grow quadratically: fine near the eye, coarse far away.
            let f1 = (i as f64 + 1.0) / steps as f64;
            let t1 = length * f1 * f1;
            let t = 0.5 * (t_prev + t1);
            let dt = t1 - t_prev;
            t_prev = t1;
            // Position relative to the planet's centre: eye at (0, 0, r).
            let pos = [view[0] * t, view[1] * t, r + view[2] * t];
            let rs = (pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]).sqrt();
            let altitude = rs - p.bottom_radius_m;
            let up = pos.map(|c| c / rs);
            let mu_s = up[0] * sun[0] + up[1] * sun[1] + up[2] * sun[2];
            let sigma_t = p.extinction_per_m(altitude);
            let (sigma_r, sigma_m) = p.scattering_per_m(altitude);
            let t_sun = self.sun_transmittance_at(rs, mu_s);
            let psi = self.multi_scattering_at(rs, mu_s);
            for c in 0..3 {
                let single = (sigma_r[c] * phase_r + sigma_m[c] * phase_m) * t_sun[c];
                let multi = (sigma_r[c] + sigma_m[c]) * psi[c];
                let source = single + multi;
                let step_t = (-sigma_t[c] * dt).exp();
                let integral = if sigma_t[c] > 0.0 {
                    (source - source * step_t) / sigma_t[c]
                } else {
                    source * dt
                };
                radiance[c] += throughput[c] * integral;
                throughput[c] *= step_t;
            }
        }
        (radiance, throughput)
    }

    /// Hillaire 2020 §5.5: Ψ_ms = L₂ / (1 − f_ms) at radius `r`, sun zenith cosine `mu_s`.
    fn integrate_multi_scattering(&self, r: f64, mu_s: f64) -> [f64; 3] {
        const DIRS: usize = 8;
        const STEPS: usize = 20;
        let p = &self.params;
        let sun = [(1.0 - mu_s * mu_s).max(0.0).sqrt(), 0.0, mu_s];
        let isotropic = 1.0 / (4.0 * std::f64::consts::PI);
        let mut l2 = [0.0; 3];
        let mut f_ms = [0.0; 3];
        let n = (DIRS * DIRS) as f64;
        for i in 0..DIRS {
            for j in 0..DIRS {
                // Uniform directions on the sphere (stratified in cos θ and φ).
                let cos_t = 1.0 - 2.0 * (i as f64 + 0.5) / DIRS as f64;
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / DIRS as f64;
                let dir = [sin_t * phi.cos(), sin_t * phi.sin(), cos_t];
                let mu = dir[2];
                let Some(top) = distance_to_sphere_far(r, mu, p.top_radius_m) else {
                    continue;
                };
                let ground = distance_to_ground(r, mu, p.bottom_radius_m);
                let length = ground.unwrap_or(top);
                let dt = length / STEPS as f64;
                let mut throughput = [1.0; 3];
                let mut lum = [0.0; 3];
                let mut transfer = [0.0; 3];
                for s in 0..STEPS {
                    let t = (s as f64 + 0.5) * dt;
                    let pos = [dir[0] * t, dir[1] * t, r + dir[2] * t];
                    let rs = (pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]).sqrt();
                    let altitude = rs - p.bottom_radius_m;
                    let up = pos.map(|c| c / rs);
                    let mu_sp = up[0] * sun[0] + up[1] * sun[1] + up[2] * sun[2];
                    let sigma_t = p.extinction_per_m(altitude);
                    let (sigma_r, sigma_m) = p.scattering_per_m(altitude);
                    let t_sun = self.sun_transmittance_at(rs, mu_sp);
                    for c in 0..3 {
                        let sigma_s = sigma_r[c] + sigma_m[c];
                        let step_t = (-sigma_t[c] * dt).exp();
                        let k = if sigma_t[c] > 0.0 {
                            (1.0 - step_t) / sigma_t[c]
                        } else {
                            dt
                        };
                        lum[c] += throughput[c] * sigma_s * isotropic * t_sun[c] * k;
                        transfer[c] += throughput[c] * sigma_s * k;
                        throughput[c] *= step_t;
                    }
                }
                if let Some(d) = ground {
                    let pos = [dir[0] * d, dir[1] * d, r + dir[2] * d];
                    let rs = (pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]).sqrt();
                    let up = pos.map(|c| c / rs);
                    let mu_sg = up[0] * sun[0] + up[1] * sun[1] + up[2] * sun[2];
                    let t_sun = self.sun_transmittance_at(rs, mu_sg);
                    for c in 0..3 {
                        lum[c] += throughput[c] * t_sun[c] * mu_sg.max(0.0) * p.ground_albedo[c]
                            / std::f64::consts::PI;
                    }
                }
                for c in 0..3 {
                    // Integrate over the sphere (4π / n per direction) with the isotropic phase.
                    l2[c] += lum[c] * 4.0 * std::f64::consts::PI / n * isotropic;
                    f_ms[c] += transfer[c] * 4.0 * std::f64::consts::PI / n * isotropic;
                }
            }
        }
        std::array::from_fn(|c| l2[c] / (1.0 - f_ms[c].min(0.999)))
    }

    /// Sky irradiance on a horizontal surface by quadrature over the upper hemisphere.
    fn integrate_sky_irradiance(&self, altitude_m: f64, mu_s: f64) -> [f64; 3] {
        const RINGS: usize = 6;
        const SECTORS: usize = 16;
        let sun = [(1.0 - mu_s * mu_s).max(0.0).sqrt(), 0.0, mu_s];
        let mut e = [0.0; 3];
        for i in 0..RINGS {
            // Equal steps in cos²θ: the cosine weight becomes uniform.
            let c2 = (i as f64 + 0.5) / RINGS as f64;
            let cos_t = c2.sqrt();
            let sin_t = (1.0 - c2).sqrt();
            for j in 0..SECTORS {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / SECTORS as f64;
                let dir = [sin_t * phi.cos(), sin_t * phi.sin(), cos_t];
                let l = self.march(altitude_m, dir, sun, f64::INFINITY, 12).0;
                for c in 0..3 {
                    // ∫ L cosθ dω = π × mean of L over cos²θ-uniform directions.
                    e[c] += l[c] * std::f64::consts::PI / (RINGS * SECTORS) as f64;
                }
            }
        }
        e
    }
}

/// Bruneton's mapping from (r, μ) to transmittance-table coordinates.
pub fn transmittance_r_mu_to_uv(p: &AtmosphereParams, r: f64, mu: f64) -> (f64, f64) {
    let h = p.horizon_h();
    let rho = (r * r - p.bottom_radius_m * p.bottom_radius_m)
        .max(0.0)
        .sqrt();
    let d = distance_to_sphere_far(r, mu.clamp(-1.0, 1.0), p.top_radius_m).unwrap_or(0.0);
    let d_min = p.top_radius_m - r;
    let d_max = rho + h;
    let x_mu = ((d - d_min) / (d_max - d_min).max(1e-9)).clamp(0.0, 1.0);
    let x_r = (rho / h).clamp(0.0, 1.0);
    (x_mu, x_r)
}

/// The inverse of [`transmittance_r_mu_to_uv`].
pub fn transmittance_uv_to_r_mu(p: &AtmosphereParams, u: f64, v: f64) -> (f64, f64) {
    let h = p.horizon_h();
    let rho = h * v.clamp(0.0, 1.0);
    let r = (rho * rho + p.bottom_radius_m * p.bottom_radius_m).sqrt();
    let d_min = p.top_radius_m - r;
    let d_max = rho + h;
    let d = d_min + u.clamp(0.0, 1.0) * (d_max - d_min);
    let mu = if d <= 0.0 {
        1.0
    } else {
        ((h * h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
    };
    (r, mu)
}

/// Transmittance from radius `r` along `mu` to the top, by a 64-step midpoint integral
/// with quadratically growing steps.
fn integrate_transmittance(p: &AtmosphereParams, r: f64, mu: f64) -> [f64; 3] {
    const STEPS: usize = 64;
    let length = distance_to_sphere_far(r, mu, p.top_radius_m).unwrap_or(0.0);
    let mut depth = [0.0; 3];
    let mut t_prev = 0.0;
    for i in 0..STEPS {
        // Quadratically growing steps: fine in the dense air near the start.
        let f1 = (i as f64 + 1.0) / STEPS as f64;
        let t1 = length * f1 * f1;
        let (t, dt) = (0.5 * (t_prev + t1), t1 - t_prev);
        t_prev = t1;
        let rs = (r * r + t * t + 2.0 * r * mu * t).max(0.0).sqrt();
        let e = p.extinction_per_m(rs - p.bottom_radius_m);
        for c in 0..3 {
            depth[c] += e[c] * dt;
        }
    }
    depth.map(|d| (-d).exp())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn earth() -> &'static Atmosphere {
        Atmosphere::earth()
    }

    fn dir(azimuth_deg: f64, elevation_deg: f64) -> [f64; 3] {
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        let (se, ce) = elevation_deg.to_radians().sin_cos();
        [ce * sa, ce * ca, se]
    }

    #[test]
    fn zenith_transmittance_matches_the_closed_form_of_the_exponential_profiles() {
        let p = AtmosphereParams::EARTH;
        let top = p.top_radius_m - p.bottom_radius_m;
        // ∫₀^top exp(−h/H) dh = H (1 − exp(−top/H)); the ozone tent integrates to its half width.
        let closed: [f64; 3] = std::array::from_fn(|c| {
            let ray = p.rayleigh_scattering_per_m[c]
                * p.rayleigh_scale_height_m
                * (1.0 - (-top / p.rayleigh_scale_height_m).exp());
            let mie = p.mie_extinction_per_m
                * p.mie_scale_height_m
                * (1.0 - (-top / p.mie_scale_height_m).exp());
            let ozone = p.ozone_absorption_per_m[c] * p.ozone_half_width_m;
            (-(ray + mie + ozone)).exp()
        });
        let t = earth().sun_transmittance(0.0, 90.0);
        for c in 0..3 {
            assert!(
                (t[c] - closed[c]).abs() < 2e-3,
                "{c}: {} vs {}",
                t[c],
                closed[c]
            );
        }
        // Blue is dimmed most at the zenith.
        assert!(t[2] < t[1] && t[1] < t[0]);
    }

    #[test]
    fn noon_zenith_sky_is_blue() {
        let l = earth().sky_radiance(0.0, [0.0, 0.0, 1.0], dir(180.0, 60.0));
        assert!(l[2] > l[1] && l[1] > l[0], "{l:?}");
        // Zenith luminance of a clear day: a few thousand cd/m².
        let lum = (0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]) * SUN_ILLUMINANCE_TOA_LUX;
        assert!((1000.0..15000.0).contains(&lum), "{lum}");
    }

    #[test]
    fn the_horizon_toward_a_setting_sun_is_red() {
        let sun = dir(270.0, 0.5);
        let l = earth().sky_radiance(0.0, dir(270.0, 2.0), sun);
        assert!(l[0] > l[2], "{l:?}");
        let t = earth().sun_transmittance(0.0, 0.5);
        assert!(t[0] > 3.0 * t[2], "{t:?}");
    }

    #[test]
    fn the_night_sky_is_dark() {
        let night = earth().sky_radiance(0.0, [0.0, 0.0, 1.0], dir(0.0, -20.0));
        let noon = earth().sky_radiance(0.0, [0.0, 0.0, 1.0], dir(0.0, 60.0));
        for c in 0..3 {
            assert!(night[c] < noon[c] * 1e-5, "{night:?} {noon:?}");
        }
        assert_eq!(earth().sun_transmittance(0.0, -5.0), [0.0; 3]);
    }

    #[test]
    fn the_earths_shadow_darkens_the_sky_opposite_a_set_sun() {
        // Sun 3 degrees below the horizon: low in the east (away from the sun) the sky is in
        // the planet's shadow, higher up it is still lit.
        let sun = dir(270.0, -3.0);
        let low = earth().sky_radiance(0.0, dir(90.0, 1.0), sun);
        let high = earth().sky_radiance(0.0, dir(90.0, 15.0), sun);
        assert!(low[1] < high[1], "{low:?} {high:?}");
    }

    #[test]
    fn sky_irradiance_plus_sun_matches_the_natural_illuminance_at_noon() {
        let sun_alt = 90.0;
        let t = earth().sun_transmittance(0.0, sun_alt);
        let e = earth().sky_irradiance(0.0, sun_alt);
        let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let total = (lum(t) + lum(e)) * SUN_ILLUMINANCE_TOA_LUX;
        let usno = crate::illuminance::sun_illuminance_lux(sun_alt);
        assert!((total / usno - 1.0).abs() < 0.15, "{total} vs {usno}");
        // The sky is a tenth to a fifth of the total.
        let frac = lum(e) / (lum(t) + lum(e));
        assert!((0.05..0.25).contains(&frac), "{frac}");
        // Skylight is blue.
        assert!(e[2] > e[0]);
    }

    #[test]
    fn multiple_scattering_brightens_the_sky() {
        let single_only = {
            let mut a = earth().clone();
            a.multi_scattering
                .texels
                .iter_mut()
                .for_each(|t| *t = [0.0; 4]);
            a.sky_radiance(0.0, [0.0, 0.0, 1.0], dir(0.0, 30.0))
        };
        let full = earth().sky_radiance(0.0, [0.0, 0.0, 1.0], dir(0.0, 30.0));
        for c in 0..3 {
            assert!(full[c] > single_only[c] * 1.02, "{full:?} {single_only:?}");
            assert!(full[c] < single_only[c] * 2.0, "{full:?} {single_only:?}");
        }
    }

    proptest! {
        #[test]
        fn transmittance_mapping_round_trips(u in 0.0f64..1.0, v in 0.01f64..1.0) {
            let p = AtmosphereParams::EARTH;
            let (r, mu) = transmittance_uv_to_r_mu(&p, u, v);
            let (u2, v2) = transmittance_r_mu_to_uv(&p, r, mu);
            prop_assert!((u - u2).abs() < 1e-6, "{u} {u2}");
            prop_assert!((v - v2).abs() < 1e-6, "{v} {v2}");
        }

        #[test]
        fn transmittance_falls_as_the_sun_sinks_and_rises_with_altitude(
            alt in 0.0f64..20_000.0, sun in 1.0f64..89.0,
        ) {
            let a = earth();
            let here = a.sun_transmittance(alt, sun);
            let lower_sun = a.sun_transmittance(alt, sun - 0.9);
            let higher_eye = a.sun_transmittance(alt + 2000.0, sun);
            for c in 0..3 {
                prop_assert!((0.0..=1.0).contains(&here[c]));
                prop_assert!(lower_sun[c] <= here[c] + 1e-4);
                prop_assert!(higher_eye[c] >= here[c] - 1e-4);
            }
        }

        #[test]
        fn sky_radiance_is_symmetric_about_the_sun_azimuth(
            offset in 1.0f64..179.0, elevation in 0.0f64..80.0, sun_alt in -5.0f64..60.0,
        ) {
            let a = earth();
            let sun = dir(100.0, sun_alt);
            let left = a.sky_radiance(500.0, dir(100.0 - offset, elevation), sun);
            let right = a.sky_radiance(500.0, dir(100.0 + offset, elevation), sun);
            for c in 0..3 {
                prop_assert!((left[c] - right[c]).abs() <= 1e-6 + 1e-4 * left[c].abs());
                prop_assert!(left[c] >= 0.0);
            }
        }
    }
}
