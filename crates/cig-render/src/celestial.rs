//! The moon and the stars of the sky pass: their GPU data (`@group(2)` of the sky pipeline) and
//! the per-frame values that `shaders/celestial.wgsl`'s `celestial_radiance(dir, sky_behind)` reads.
//!
//! Algorithm: per frame, the ephemeris (`cig_environment::ephemeris`, topocentric at the view's
//! eye) gives the moon's and the sun's directions (turned from east-north-up to ECEF), the moon's
//! distance and phase angle; the shader draws the moon as a sphere of the moon's angular radius
//! lit by the sun, each pixel of the disc taking the sphere's normal there and the
//! Lommel–Seeliger law `2 cos i / (cos i + cos e)` times the surface luminance of
//! `cig_environment::moon_disc` (so the phase, the bright limb's orientation and the terminator
//! follow from the geometry), plus earthshine, times a schematic albedo map: the 13 large
//! near-side maria as soft discs at their selenographic places and sizes (albedo 0.57 of the
//! highlands', scaled so the near side's mean is 1 and the disc's total stays the phase law's),
//! oriented by the moon's axis (taken as the ecliptic's pole) and the sub-Earth point (the disc's
//! centre); the disc's edge is antialiased by its pixel coverage. Stars: the 904 catalogue stars (`cig_environment::stars`) are kept on the GPU as
//! J2000 directions (proper motion to the date, refreshed when the date moves) with their
//! illuminance `E = 10^(−0.4 (V + 13.99))` lux and colour; the pixel's direction is turned from
//! ECEF to J2000 by the transpose of the precession–nutation–sidereal-time matrix of the
//! frame, and looked up in a cube map of 6 × 32 × 32 cells in which every star is listed in each
//! cell within 0.6° of it, so each pixel tests only the stars of its cell (0.6 on average); by
//! day, when the eye's threshold is above every star, the lookup is skipped. A star
//! is a gaussian of unit integral and σ = 0.6 pixel (so its total is the same at any field of
//! view and it does not flicker as it drifts across pixels) times its illuminance; it fades with the eye's point-source threshold against the luminance
//! of the sky behind it (Schaefer 1990; the pixel's own physical sky radiance from the sky-view
//! table, moonlit and twilit parts included), compared with the star's illuminance at the eye
//! after extinction: not drawn under the threshold, drawn whole one magnitude over it (a
//! threshold is the faintest star seen at all, so a star there must not stand out on a display
//! whose pixel spread, in a narrow view, concentrates it far above what the eye's own spread
//! would), so stars come out at dusk and vanish by day without any gate on
//! the sun's altitude. Moon and stars are dimmed by the atmosphere's extinction along the air
//! mass of Kasten and Young (1989), 0.13/0.20/0.34 magnitudes per air mass in R/G/B for a clear
//! sky at sea level (Rayleigh, λ⁻⁴, scale height 8 km, plus grey aerosol, 1.2 km; less above a
//! high eye), hidden below the apparent horizon, and then pass through the sky's ground fog
//! like the sky itself (sky.wgsl adds them before its fog). Radiance is physical: a luminance of
//! L cd/m² shows `π L LIGHTING_UNITS_PER_LUX` ([`radiance_per_cd_per_m2`]).
//!
//! The moon's disc alone is adapted locally (the one exception to the frame's single tone map):
//! the eye looking at the moon adapts to the disc, not to the landscape, so it sees the phase,
//! the maria and the earthshine of a disc that, under the frame's automatic night exposure, is
//! 10⁴–10⁵ times the moonlit ground's luminance and far over the tone map's clip. As in the
//! local ("dodging") operators of Reinhard et al. (2002, "Photographic tone reproduction for
//! digital images", §3.2) and the eye's local adaptation of Durand and Dorsey (2000,
//! "Interactive tone mapping"), the disc is compressed about its own adaptation level `A`, the
//! exposed luminance of an element lit and seen head-on at the current phase (the surface
//! luminance of `moon_disc`, known on the CPU, after extinction): while `A` is under the
//! display level `D` = 1 (pre-tone-map; ACES shows 0.8 of its white there) the disc is left
//! physical, so the pale daytime moon against the blue sky and the moon at dusk are unchanged;
//! above it each exposed luminance `v` of the disc becomes `D (v / A)^γ`, with γ going from 1 at
//! `A = D` (continuous with the physical disc) to 0.5 at `A ≥ 100 D` (log-linear in `A / D`).
//! The brightest limb (2.3 A: the Lommel–Seeliger limb times the maria map's highlands) then
//! shows at 1.5, under the clip, and the earthshine keeps its order below the lit side, its
//! ratio to it square-rooted (10⁻³ at a quarter becomes 3 · 10⁻², just visible, as to the naked
//! eye). The compression is on luminance (the extinction's reddening and the moon's colour are
//! kept) and is applied before the edge's pixel coverage, so the antialiased edge is a linear
//! blend with the sky; the stars are not compressed.
//!
//! Limits: the maria are a schematic of discs, not a map; libration (up to 8°), the axis's 1.5°
//! tilt from the ecliptic pole and surface roughness are left out (a Lommel–Seeliger sphere); the
//! moon and stars are not refracted (geometric directions, like the sun disc), and the
//! extinction is a fixed clear-sky one, not the atmosphere model's; a star's point spread is the
//! pixel's, not the eye's (radiometrically right: a star's flux is kept, and a pixel of a
//! 60°/640 view, 5.6′, is within the eye's spatial summation area, so the star is as detectable
//! on a display reproducing the scene's contrast; but in bright twilight its contrast in one
//! pixel, E / (Ω_pixel B), is only a few percent, fainter than the naked eye's impression); no
//! planets, Milky Way or zodiacal light. The disc's local adaptation is a fixed curve, not a
//! model of the eye's time course (no adaptation delay when looking from the ground to the moon)
//! nor of glare: the disc's contrast to the sky beside it is the display's, not the scene's
//! 10⁴, and the halo a bright moon casts in the eye is not drawn; under a photographer's fixed
//! exposure (`SkySettings::fixed_exposure_ev`) that keeps the disc under the display level the
//! disc is physical.

use crate::gpu::Gpu;
use cig_environment::moon_disc;
use cig_environment::stars::{self, Star};
use cig_environment::{Observer, UtcTime};
use cig_geo::Geodetic;
use cig_scene::FrameSnapshot;
use glam::DVec3;

/// Cells along each edge of a cube-map face (the shader's `STAR_GRID`).
pub const STAR_GRID: usize = 32;
/// Every star is listed in each cell within this angle of it: the reach (4 σ) of its point
/// spread in pixels up to 0.15° (a 90° view 600 pixels across; a coarser view clips the spread
/// of a star at a cell's edge).
const CELL_MARGIN_RAD: f64 = 0.010_472;
/// Point-spread sigma of a star, pixels.
const STAR_SIGMA_PX: f32 = 0.6;
/// Rayleigh extinction in R, G, B at sea level, magnitudes per air mass (λ⁻⁴ from 0.12 at
/// 550 nm), and its scale height.
const RAYLEIGH_MAG_PER_AIR_MASS: [f64; 3] = [0.05, 0.12, 0.26];
const RAYLEIGH_SCALE_HEIGHT_M: f64 = 8_000.0;
/// Aerosol extinction of a clear sky at sea level (grey), and its scale height.
const AEROSOL_MAG_PER_AIR_MASS: f64 = 0.08;
const AEROSOL_SCALE_HEIGHT_M: f64 = 1_200.0;

/// Extinction (magnitudes per air mass) in R, G, B above an eye at `altitude_m`: the Rayleigh
/// and aerosol parts thin out with their scale heights (0.13/0.20/0.34 at sea level).
pub fn extinction_mag_per_air_mass(altitude_m: f64) -> [f64; 3] {
    let h = if altitude_m.is_finite() {
        altitude_m.max(0.0)
    } else {
        0.0
    };
    let rayleigh = (-h / RAYLEIGH_SCALE_HEIGHT_M).exp();
    let aerosol = AEROSOL_MAG_PER_AIR_MASS * (-h / AEROSOL_SCALE_HEIGHT_M).exp();
    RAYLEIGH_MAG_PER_AIR_MASS.map(|k| k * rayleigh + aerosol)
}
/// The moon's colour index B−V (its colour is sunlight's, slightly reddened).
const MOON_B_MINUS_V: f64 = 0.92;

/// The shader's source (the sky module is `common.wgsl` + this + `sky.wgsl`).
pub(crate) const WGSL: &str = include_str!("shaders/celestial.wgsl");

/// Light-unit radiance of a luminance of 1 cd/m² (the contract's `π L units`).
pub fn radiance_per_cd_per_m2() -> f64 {
    std::f64::consts::PI * cig_scene::lighting::LIGHTING_UNITS_PER_LUX
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CelestialUniform {
    moon_dir: [f32; 4],
    moon_sun: [f32; 4],
    moon_colour: [f32; 4],
    moon_north: [f32; 4],
    ecef_to_celestial: [[f32; 4]; 3],
    stars: [f32; 4],
    extinction: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct StarRecord {
    dir_lux: [f32; 4],
    colour: [f32; 4],
}

/// The cube-map cell of a direction: face 0..6 (+x, −x, +y, −y, +z, −z) and the cell on it.
pub fn cell_of(d: DVec3) -> usize {
    let a = d.abs();
    let (face, u, v, major) = if a.x >= a.y && a.x >= a.z {
        (usize::from(d.x <= 0.0), d.y, d.z, a.x)
    } else if a.y >= a.z {
        (2 + usize::from(d.y <= 0.0), d.x, d.z, a.y)
    } else {
        (4 + usize::from(d.z <= 0.0), d.x, d.y, a.z)
    };
    let index = |t: f64| {
        let f = ((t / major) * 0.5 + 0.5).clamp(0.0, 1.0) * STAR_GRID as f64;
        (f as usize).min(STAR_GRID - 1)
    };
    (face * STAR_GRID + index(v)) * STAR_GRID + index(u)
}

/// For each cube-map cell, the indices of the stars within [`CELL_MARGIN_RAD`] of it: per cell
/// (first, count) into the returned index list.
pub fn bin_stars(directions: &[DVec3]) -> (Vec<[u32; 2]>, Vec<u32>) {
    let cells = 6 * STAR_GRID * STAR_GRID;
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); cells];
    let cell_uv = 2.0 / STAR_GRID as f64;
    for (i, d) in directions.iter().enumerate() {
        for face in 0..6 {
            let (major, u, v) = match face {
                0 => (d.x, d.y, d.z),
                1 => (-d.x, d.y, d.z),
                2 => (d.y, d.x, d.z),
                3 => (-d.y, d.x, d.z),
                4 => (d.z, d.x, d.y),
                _ => (-d.z, d.x, d.y),
            };
            // A star that can be within the margin of a face's pixels has its major component
            // at least cos(54.7° + margin) there.
            if major < 0.5 {
                continue;
            }
            let (u, v) = (u / major, v / major);
            // The gnomonic face's scale is at most sec² of the angle from its centre, 1 + u² + v²
            // (taken a little wider, for the margin's own extent).
            let margin_uv = CELL_MARGIN_RAD * (1.0 + u * u + v * v) * 1.1;
            let range = |t: f64| {
                let lo = (((t - margin_uv) + 1.0) / cell_uv).floor().max(0.0) as usize;
                let hi = (((t + margin_uv) + 1.0) / cell_uv).floor().max(0.0) as usize;
                (lo.min(STAR_GRID - 1), hi.min(STAR_GRID - 1))
            };
            let (u0, u1) = range(u);
            let (v0, v1) = range(v);
            for cv in v0..=v1 {
                for cu in u0..=u1 {
                    lists[(face * STAR_GRID + cv) * STAR_GRID + cu].push(i as u32);
                }
            }
        }
    }
    let mut ranges = Vec::with_capacity(cells);
    let mut index = Vec::new();
    for list in lists {
        ranges.push([index.len() as u32, list.len() as u32]);
        index.extend(list);
    }
    (ranges, index)
}

/// The clamped instant of a frame (the ephemeris covers 1900..=2100).
fn frame_time(unix_time_s: f64) -> Option<UtcTime> {
    let lo = UtcTime::from_calendar(1900, 1, 1, 0, 0, 0.0)
        .ok()?
        .unix_seconds();
    let hi = UtcTime::from_calendar(2100, 12, 31, 23, 59, 59.0)
        .ok()?
        .unix_seconds();
    let t = if unix_time_s.is_finite() {
        unix_time_s.clamp(lo, hi)
    } else {
        lo
    };
    UtcTime::from_unix_seconds(t).ok()
}

/// The moon of one frame as the shader draws it (for tests and statistics).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoonView {
    /// Unit direction from the eye to the moon's centre, ECEF.
    pub direction_ecef: DVec3,
    /// Unit direction from the eye to the sun, ECEF.
    pub sun_direction_ecef: DVec3,
    /// Angular radius, degrees.
    pub angular_radius_deg: f64,
    /// Topocentric phase angle, degrees.
    pub phase_angle_deg: f64,
    /// Illuminated fraction of the disc.
    pub illuminated_fraction: f64,
}

/// The moon seen from `eye` at `unix_time_s` (None for an eye the ephemeris refuses).
pub fn moon_view(unix_time_s: f64, eye: Geodetic) -> Option<MoonView> {
    let time = frame_time(unix_time_s)?;
    let observer = Observer::new(
        eye.lat_deg.clamp(-90.0, 90.0),
        eye.lon_deg,
        eye.alt_m.clamp(-12_000.0, 100_000.0),
    )
    .ok()?;
    let e = cig_environment::ephemeris(&observer, time);
    let frame = observer.enu_frame();
    let to_ecef = |enu: [f64; 3]| frame.enu_vector_to_ecef(DVec3::from_array(enu)).normalize();
    Some(MoonView {
        direction_ecef: to_ecef(e.moon.direction_enu),
        sun_direction_ecef: to_ecef(e.sun.direction_enu),
        angular_radius_deg: moon_disc::moon_angular_radius_deg(e.moon.distance_m),
        phase_angle_deg: e.moon_phase_angle_deg,
        illuminated_fraction: e.moon_illuminated_fraction,
    })
}

/// The sky pass's moon and star resources.
pub(crate) struct CelestialPass {
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    uniform: wgpu::Buffer,
    star_buffer: wgpu::Buffer,
    /// Julian years since J2000 of the proper motion in `star_buffer` (NaN before the first).
    star_epoch_years: f64,
    /// Whether the uploaded stars are weighted for an image intensifier.
    stars_for_goggles: bool,
}

/// A read-only storage buffer the sky's fragment shader reads.
fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        visibility: wgpu::ShaderStages::FRAGMENT,
        ..crate::pass::storage_entry(binding)
    }
}

impl CelestialPass {
    pub(crate) fn new(gpu: &Gpu) -> CelestialPass {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("celestial"),
            entries: &[
                crate::pass::uniform_entry(0),
                storage_entry(1),
                storage_entry(2),
                storage_entry(3),
            ],
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("celestial"),
            size: std::mem::size_of::<CelestialUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let catalogue = stars::catalogue();
        let star_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stars"),
            size: (catalogue.len().max(1) * std::mem::size_of::<StarRecord>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Cells from the J2000 positions: proper motion over 1900-2100 moves no catalogue star
        // by more than 0.25°, well inside the cells' margin.
        let j2000: Vec<DVec3> = catalogue.iter().map(|s| s.direction_j2000(0.0)).collect();
        let (ranges, index) = bin_stars(&j2000);
        let buffer = |label, bytes: &[u8]| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (bytes.len() as u64).max(16).next_multiple_of(4),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            gpu.queue.write_buffer(&b, 0, bytes);
            b
        };
        let cells = buffer("star cells", bytemuck::cast_slice(&ranges));
        let index = buffer("star index", bytemuck::cast_slice(&index));
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("celestial"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: star_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: cells.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: index.as_entire_binding(),
                },
            ],
        });
        CelestialPass {
            layout,
            bind_group,
            uniform,
            star_buffer,
            star_epoch_years: f64::NAN,
            stars_for_goggles: false,
        }
    }

    pub(crate) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    pub(crate) fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// Writes the frame's moon, sun and sky rotation for a view of `snapshot` from `eye` (its
    /// time, moon and star switches), and the stars' proper motion when the date has moved by
    /// more than a few days. On goggles (`goggles`) the moon's disc and each star are weighted
    /// for the photocathode (`cig_environment::nvg`: moonlight's factor; a blackbody at the
    /// star's temperature from its B−V) and drawn grey.
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        snapshot: &FrameSnapshot,
        eye: Geodetic,
        goggles: bool,
    ) {
        let unix_time_s = snapshot.unix_time_s;
        let units = radiance_per_cd_per_m2();
        let intensity = if snapshot.star_intensity.is_finite() {
            snapshot.star_intensity.clamp(0.0, 1.0)
        } else {
            1.0
        };
        let mut u = CelestialUniform {
            stars: [
                units as f32,
                if snapshot.stars_visible && intensity > 0.0 {
                    1.0
                } else {
                    0.0
                },
                STAR_SIGMA_PX,
                intensity as f32,
            ],
            extinction: {
                let k = extinction_mag_per_air_mass(eye.alt_m);
                [k[0] as f32, k[1] as f32, k[2] as f32, 1.0]
            },
            ..Default::default()
        };
        let v4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let moon_k = if goggles {
            cig_environment::nvg::MOON_NVG_PER_LUX
        } else {
            1.0
        };
        if let Some(moon) = moon_view(unix_time_s, eye).filter(|_| snapshot.moon_visible) {
            let colour = if goggles {
                [1.0; 3]
            } else {
                stars::star_colour_linear_srgb(Some(MOON_B_MINUS_V))
            };
            u.moon_dir = v4(
                moon.direction_ecef,
                moon.angular_radius_deg.to_radians().sin(),
            );
            u.moon_sun = v4(
                moon.sun_direction_ecef,
                moon_disc::moon_surface_luminance_cd_per_m2(moon.phase_angle_deg) * units * moon_k,
            );
            u.moon_colour = [
                colour[0] as f32,
                colour[1] as f32,
                colour[2] as f32,
                (moon_disc::earthshine_luminance_cd_per_m2(moon.phase_angle_deg) * units * moon_k)
                    as f32,
            ];
        }
        if let Some(time) = frame_time(unix_time_s) {
            let m = stars::celestial_to_ecef(time);
            // The moon's axis is within 1.5° of the ecliptic's pole (J2000 obliquity).
            let eps = 23.439_28_f64.to_radians();
            u.moon_north = v4(m * DVec3::new(0.0, -eps.sin(), eps.cos()), 1.0);
            // Rows of the inverse (the transpose) are the columns of `m`.
            u.ecef_to_celestial = [v4(m.x_axis, 0.0), v4(m.y_axis, 0.0), v4(m.z_axis, 0.0)];
            let years = stars::julian_years_since_j2000(time);
            let stale = (years - self.star_epoch_years).abs();
            if stale.is_nan() || stale >= 0.01 || goggles != self.stars_for_goggles {
                let records: Vec<StarRecord> = stars::catalogue()
                    .iter()
                    .map(|s: &Star| {
                        let (c, k) = if goggles {
                            let t = stars::temperature_k_from_b_minus_v(s.b_minus_v.unwrap_or(0.6));
                            ([1.0; 3], cig_environment::nvg::blackbody_nvg_per_lux(t))
                        } else {
                            (stars::star_colour_linear_srgb(s.b_minus_v), 1.0)
                        };
                        StarRecord {
                            dir_lux: v4(s.direction_j2000(years), s.illuminance_lux() * k),
                            colour: [c[0] as f32, c[1] as f32, c[2] as f32, 0.0],
                        }
                    })
                    .collect();
                gpu.queue
                    .write_buffer(&self.star_buffer, 0, bytemuck::cast_slice(&records));
                self.star_epoch_years = years;
                self.stars_for_goggles = goggles;
            }
        }
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn every_star_is_listed_in_the_cell_of_each_direction_near_it() {
        let dirs: Vec<DVec3> = stars::catalogue()
            .iter()
            .map(|s| s.direction_j2000(0.0))
            .collect();
        let (ranges, index) = bin_stars(&dirs);
        assert_eq!(ranges.len(), 6 * STAR_GRID * STAR_GRID);
        // Under one star per cell on average (what each sky pixel tests).
        let mean = index.len() as f64 / ranges.len() as f64;
        assert!(mean < 0.8, "{mean}");
        // Directions 0.55° from every star, in 8 directions, find it in their cell.
        for (i, d) in dirs.iter().enumerate() {
            let east = DVec3::Z.cross(*d).normalize_or(DVec3::X);
            let north = d.cross(east);
            for k in 0..8 {
                let a = f64::from(k) * std::f64::consts::FRAC_PI_4;
                let off = (east * a.cos() + north * a.sin()) * 0.55f64.to_radians();
                let p = (*d + off).normalize();
                let [first, count] = ranges[cell_of(p)];
                let list = &index[first as usize..(first + count) as usize];
                assert!(list.contains(&(i as u32)), "star {i} missing at offset {k}");
            }
        }
    }

    proptest! {
        #[test]
        fn cells_are_in_range(x in -1.0f64..1.0, y in -1.0f64..1.0, z in -1.0f64..1.0) {
            let d = DVec3::new(x, y, z);
            prop_assume!(d.length() > 1e-3);
            prop_assert!(cell_of(d.normalize()) < 6 * STAR_GRID * STAR_GRID);
        }
    }

    #[test]
    fn extinction_is_bluest_and_thins_out_with_height() {
        let sea = extinction_mag_per_air_mass(0.0);
        assert!(sea[2] > sea[1] && sea[1] > sea[0]);
        // V-band extinction at a clear sea-level site is about 0.2 mag per air mass.
        assert!((sea[1] - 0.20).abs() < 0.01);
        let high = extinction_mag_per_air_mass(10_000.0);
        assert!(high.iter().zip(sea).all(|(h, s)| *h < 0.35 * s), "{high:?}");
        assert_eq!(extinction_mag_per_air_mass(f64::NAN), sea);
    }

    #[test]
    fn the_moon_view_matches_the_ephemeris() {
        let eye = Geodetic::new(36.0, -121.0, 100.0);
        let t = UtcTime::from_calendar(2026, 12, 24, 8, 0, 0.0).unwrap();
        let v = moon_view(t.unix_seconds(), eye).unwrap();
        assert!((v.direction_ecef.length() - 1.0).abs() < 1e-12);
        // 356 000 - 407 000 km from the centre, the eye up to 6378 km nearer: 14.6' - 17'.
        assert!(
            (0.243..0.285).contains(&v.angular_radius_deg),
            "{}",
            v.angular_radius_deg
        );
        assert!(
            (v.illuminated_fraction - moon_disc::illuminated_fraction(v.phase_angle_deg)).abs()
                < 1e-9
        );
        // Out-of-range times are clamped, not refused.
        assert!(moon_view(f64::NAN, eye).is_some());
        assert!(moon_view(1e15, eye).is_some());
    }
}
