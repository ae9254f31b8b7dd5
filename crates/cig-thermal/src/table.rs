//! Surface temperatures of every material for a set of surface orientations, spun up over the
//! days before the start and advanced with the simulation clock.
//!
//! Algorithm: the source's two steps (source 001, "Infrared Gray Level Prediction"): first the
//! exterior temperature of plates whose normals point in standard directions is computed from
//! the environment and tabulated; then each surface's normal is looked up in that table and the
//! temperature interpolated. The source used twelve directions; here there are 26, on five
//! rings of tilt (0, 45, 90, 135 and 180 degrees from straight up) with eight azimuths on the
//! three middle rings, interpolated bilinearly in tilt and azimuth. Each (material, direction)
//! is a [`Slab`] driven by the sun of the ephemeris on that direction, the sky and ground's
//! long-wave, the air, humidity and wind of a [`ThermalWeather`].
//!
//! The table is spun up from [`SPIN_UP_S`] before the start time (the nodes start on a line
//! from the air to the deep ground) with steps of at most [`MAX_STEP_S`], then advanced
//! incrementally: [`SurfaceTable::advance_to`] steps only the time that passed, never
//! recomputing from scratch, unless the clock jumped backwards or more than
//! [`RESPIN_AFTER_S`] ahead.
//!
//! Limits: one place (the table's latitude and longitude) for the sun and the local solar time;
//! no shadows (a surface in the shade of another still gets the direct sun of its
//! orientation), no lateral conduction.

use crate::material::{MaterialProperties, ThermalMaterial};
use crate::slab::{Slab, SurfaceForcing};
use crate::weather::{
    convection_w_m2_k, saturation_specific_humidity, sky_longwave_w_m2, solar_irradiance,
    ThermalWeather, GROUND_ALBEDO,
};
use crate::ThermalError;
use cig_environment::sun::AU_M;
use cig_environment::{ephemeris, Observer, UtcTime};

/// How long before the start the table is spun up, seconds (two days).
pub const SPIN_UP_S: f64 = 48.0 * 3600.0;
/// The longest step, seconds.
pub const MAX_STEP_S: f64 = 60.0;
/// Time below which an advance waits for more (the temperatures cannot change visibly).
pub const MIN_STEP_S: f64 = 0.25;
/// The most steps one advance takes.
pub const MAX_ADVANCE_STEPS: usize = 240;
/// A step back of the clock the table holds through (its temperatures kept), seconds.
pub const HOLD_BACK_S: f64 = 600.0;
/// A jump of the clock beyond which the table is spun up again rather than stepped.
pub const RESPIN_AFTER_S: f64 = 3.0 * 86_400.0;

/// Tilts of the standard rings, degrees from straight up.
pub const RING_TILTS_DEG: [f64; 5] = [0.0, 45.0, 90.0, 135.0, 180.0];
/// Azimuths on each of the three middle rings.
pub const RING_AZIMUTHS: usize = 8;

/// A surface's orientation: how far its normal leans from straight up, and which way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orientation {
    /// Angle of the normal from straight up, degrees: 0 horizontal facing up, 90 a wall, 180
    /// facing down.
    pub tilt_deg: f64,
    /// Azimuth the normal points to, degrees from north through east.
    pub facing_deg: f64,
}

impl Orientation {
    /// Checks the ranges: tilt 0..180, facing finite.
    pub fn new(tilt_deg: f64, facing_deg: f64) -> Result<Orientation, ThermalError> {
        if !(tilt_deg.is_finite() && (0.0..=180.0).contains(&tilt_deg)) {
            return Err(ThermalError::OutOfRange {
                name: "tilt",
                value: tilt_deg,
                expected: "0..180 degrees",
            });
        }
        if !facing_deg.is_finite() {
            return Err(ThermalError::OutOfRange {
                name: "facing",
                value: facing_deg,
                expected: "a finite azimuth in degrees",
            });
        }
        Ok(Orientation {
            tilt_deg,
            facing_deg: facing_deg.rem_euclid(360.0),
        })
    }

    /// The unit normal, east-north-up.
    pub fn normal_enu(&self) -> [f64; 3] {
        let (st, ct) = self.tilt_deg.to_radians().sin_cos();
        let (sf, cf) = self.facing_deg.to_radians().sin_cos();
        [st * sf, st * cf, ct]
    }

    /// The 26 standard orientations, in table order: up; the 45-degree ring from north through
    /// east; the walls; the 135-degree ring; down.
    pub fn standard() -> Vec<Orientation> {
        let mut list = vec![Orientation {
            tilt_deg: 0.0,
            facing_deg: 0.0,
        }];
        for &tilt_deg in &RING_TILTS_DEG[1..4] {
            for a in 0..RING_AZIMUTHS {
                list.push(Orientation {
                    tilt_deg,
                    facing_deg: a as f64 * 360.0 / RING_AZIMUTHS as f64,
                });
            }
        }
        list.push(Orientation {
            tilt_deg: 180.0,
            facing_deg: 0.0,
        });
        list
    }
}

/// Which orientations a table holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Orientations {
    /// The 26 standard directions, interpolated by normal.
    Standard,
    /// One orientation (the command line's `--tilt-deg --facing-deg`).
    Single(Orientation),
}

/// Weights of the standard orientations for a normal: up to four (index, weight) pairs.
pub fn standard_weights(normal_enu: [f64; 3]) -> [(usize, f64); 4] {
    let [e, n, u] = normal_enu;
    let len = (e * e + n * n + u * u).sqrt();
    let up = if len > 0.0 { u / len } else { 1.0 };
    let tilt = up.clamp(-1.0, 1.0).acos().to_degrees();
    let azimuth = e.atan2(n).to_degrees().rem_euclid(360.0);
    let ring_f = (tilt / 45.0).clamp(0.0, 4.0);
    let r0 = (ring_f.floor() as usize).min(3);
    let wr = ring_f - r0 as f64;
    let sector = azimuth / (360.0 / RING_AZIMUTHS as f64);
    let a0 = (sector.floor() as usize) % RING_AZIMUTHS;
    let a1 = (a0 + 1) % RING_AZIMUTHS;
    let wa = sector - sector.floor();
    let ring = |r: usize| -> [(usize, f64); 2] {
        match r {
            0 => [(0, 1.0), (0, 0.0)],
            4 => [(1 + 3 * RING_AZIMUTHS, 1.0), (0, 0.0)],
            _ => {
                let base = 1 + (r - 1) * RING_AZIMUTHS;
                [(base + a0, 1.0 - wa), (base + a1, wa)]
            }
        }
    };
    let lower = ring(r0);
    let upper = ring(r0 + 1);
    [
        (lower[0].0, lower[0].1 * (1.0 - wr)),
        (lower[1].0, lower[1].1 * (1.0 - wr)),
        (upper[0].0, upper[0].1 * wr),
        (upper[1].0, upper[1].1 * wr),
    ]
}

/// The surroundings at one instant, shared by every slab.
#[derive(Clone, Copy, Debug)]
struct Surroundings {
    sun_enu: [f64; 3],
    direct_normal_w_m2: f64,
    diffuse_horizontal_w_m2: f64,
    global_horizontal_w_m2: f64,
    sky_longwave_w_m2: f64,
    ground_longwave_w_m2: f64,
    air_k: f64,
    air_specific_humidity: f64,
    convection_w_m2_k: f64,
    deep_ground_k: f64,
}

impl Surroundings {
    fn at(observer: &Observer, weather: &ThermalWeather, time: UtcTime) -> Surroundings {
        let g = observer.geodetic();
        let eph = ephemeris(observer, time);
        let sun = solar_irradiance(
            eph.sun.altitude_deg,
            eph.sun.distance_m / AU_M,
            weather.cloud_cover,
        );
        let air_k = weather.air.at(time, g.lat_deg, g.lon_deg);
        let (q_sat, _) = saturation_specific_humidity(air_k);
        Surroundings {
            sun_enu: eph.sun.direction_enu,
            direct_normal_w_m2: sun.direct_normal_w_m2,
            diffuse_horizontal_w_m2: sun.diffuse_horizontal_w_m2,
            global_horizontal_w_m2: sun.global_horizontal_w_m2,
            sky_longwave_w_m2: sky_longwave_w_m2(
                air_k,
                weather.relative_humidity_pct,
                weather.cloud_cover,
            ),
            ground_longwave_w_m2: crate::planck::STEFAN_BOLTZMANN * air_k.powi(4),
            air_k,
            air_specific_humidity: q_sat * weather.relative_humidity_pct / 100.0,
            convection_w_m2_k: convection_w_m2_k(weather.wind_mps),
            deep_ground_k: weather.deep_ground_k(),
        }
    }

    /// The forcing on a surface with unit normal `normal_enu`.
    fn forcing(&self, normal_enu: [f64; 3]) -> SurfaceForcing {
        let cos_tilt = normal_enu[2];
        let sky_view = 0.5 * (1.0 + cos_tilt);
        let ground_view = 0.5 * (1.0 - cos_tilt);
        let cos_incidence = normal_enu[0] * self.sun_enu[0]
            + normal_enu[1] * self.sun_enu[1]
            + normal_enu[2] * self.sun_enu[2];
        SurfaceForcing {
            incident_shortwave_w_m2: self.direct_normal_w_m2 * cos_incidence.max(0.0)
                + self.diffuse_horizontal_w_m2 * sky_view
                + GROUND_ALBEDO * self.global_horizontal_w_m2 * ground_view,
            incident_longwave_w_m2: self.sky_longwave_w_m2 * sky_view
                + self.ground_longwave_w_m2 * ground_view,
            air_k: self.air_k,
            air_specific_humidity: self.air_specific_humidity,
            convection_w_m2_k: self.convection_w_m2_k,
            deep_ground_k: self.deep_ground_k,
        }
    }
}

/// Surface temperatures per material and orientation, advanced with the clock.
#[derive(Clone, Debug)]
pub struct SurfaceTable {
    observer: Observer,
    weather: ThermalWeather,
    time: UtcTime,
    materials: Vec<ThermalMaterial>,
    layout: Orientations,
    orientations: Vec<Orientation>,
    /// Slabs, material-major: `slabs[m * orientations + o]`.
    slabs: Vec<Slab>,
    steps: u64,
}

impl SurfaceTable {
    /// Builds the table for `materials` at a place and spins it up to `time`.
    pub fn spin_up(
        lat_deg: f64,
        lon_deg: f64,
        time: UtcTime,
        weather: ThermalWeather,
        materials: &[ThermalMaterial],
        layout: Orientations,
    ) -> Result<SurfaceTable, ThermalError> {
        weather.validate()?;
        let observer = Observer::new(lat_deg, lon_deg, 0.0)
            .map_err(|e| ThermalError::InvalidPlace(e.to_string()))?;
        let orientations = match &layout {
            Orientations::Standard => Orientation::standard(),
            Orientations::Single(o) => vec![*o],
        };
        let mut table = SurfaceTable {
            observer,
            weather,
            time,
            materials: materials.to_vec(),
            layout,
            orientations,
            slabs: Vec::new(),
            steps: 0,
        };
        table.respin(time);
        Ok(table)
    }

    fn respin(&mut self, time: UtcTime) {
        let start = time.plus_seconds(-SPIN_UP_S);
        let g = self.observer.geodetic();
        let air_k = self.weather.air.at(start, g.lat_deg, g.lon_deg);
        let deep_k = self.weather.deep_ground_k();
        self.slabs.clear();
        for &m in &self.materials {
            let props: &MaterialProperties = m.properties();
            for _ in &self.orientations {
                let mut slab = Slab::new(props, air_k);
                slab.set_linear_profile(air_k, deep_k);
                self.slabs.push(slab);
            }
        }
        self.time = start;
        self.step_to(time, false);
    }

    /// Steps to `target` in steps of at most [`MAX_STEP_S`], or with `capped` in at most
    /// [`MAX_ADVANCE_STEPS`] (a long jump forward, a host setting a later time, does not hold
    /// a frame up; the implicit steps stay stable, only coarser).
    fn step_to(&mut self, target: UtcTime, capped: bool) {
        let span = target.seconds_since_j2000() - self.time.seconds_since_j2000();
        if span <= 0.0 {
            return;
        }
        let mut steps = (span / MAX_STEP_S).ceil().max(1.0) as usize;
        if capped {
            steps = steps.min(MAX_ADVANCE_STEPS);
        }
        let dt = span / steps as f64;
        let normals: Vec<[f64; 3]> = self.orientations.iter().map(|o| o.normal_enu()).collect();
        let per_material = self.orientations.len();
        for s in 1..=steps {
            // Implicit steps take the surroundings at the end of the step.
            let at = self.time.plus_seconds(dt * s as f64);
            let surroundings = Surroundings::at(&self.observer, &self.weather, at);
            let forcings: Vec<SurfaceForcing> =
                normals.iter().map(|n| surroundings.forcing(*n)).collect();
            for (i, slab) in self.slabs.iter_mut().enumerate() {
                slab.step(dt, &forcings[i % per_material]);
            }
            self.steps += 1;
        }
        self.time = target;
    }

    /// Advances the table to `time`: steps the time that passed (nothing below
    /// [`MIN_STEP_S`]; a long jump in at most 240 steps); a step back of up to
    /// [`HOLD_BACK_S`] keeps the temperatures (they change little in minutes) and takes the
    /// time; a longer one, or a jump ahead beyond [`RESPIN_AFTER_S`], spins up again.
    pub fn advance_to(&mut self, time: UtcTime) {
        let span = time.seconds_since_j2000() - self.time.seconds_since_j2000();
        if span.is_nan() {
            return;
        }
        if !(-HOLD_BACK_S..=RESPIN_AFTER_S).contains(&span) {
            self.respin(time);
        } else if span < 0.0 {
            self.time = time;
        } else if span >= MIN_STEP_S {
            self.step_to(time, true);
        }
    }

    /// Replaces the weather from now on (the state carries over).
    pub fn set_weather(&mut self, weather: ThermalWeather) -> Result<(), ThermalError> {
        weather.validate()?;
        self.weather = weather;
        Ok(())
    }

    /// The weather driving the table.
    pub fn weather(&self) -> &ThermalWeather {
        &self.weather
    }

    /// The instant the temperatures are for.
    pub fn time(&self) -> UtcTime {
        self.time
    }

    /// Implicit steps taken since construction (spin-ups included).
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The materials, in table order.
    pub fn materials(&self) -> &[ThermalMaterial] {
        &self.materials
    }

    /// The orientations, in table order.
    pub fn orientations(&self) -> &[Orientation] {
        &self.orientations
    }

    /// Air temperature now, kelvin.
    pub fn air_k(&self) -> f64 {
        let g = self.observer.geodetic();
        self.weather.air.at(self.time, g.lat_deg, g.lon_deg)
    }

    /// Surface temperature of the `material`-th material at the `orientation`-th orientation.
    pub fn surface_k(&self, material: usize, orientation: usize) -> f64 {
        self.slabs[material * self.orientations.len() + orientation].surface_k()
    }

    /// The slab of one material and orientation (its node temperatures).
    pub fn slab(&self, material: usize, orientation: usize) -> &Slab {
        &self.slabs[material * self.orientations.len() + orientation]
    }

    /// Surface temperature of `material` for a surface with normal `normal_enu`
    /// (east-north-up, need not be unit), interpolated over the standard orientations; `None`
    /// if the table does not hold the material.
    pub fn temperature_k(&self, material: ThermalMaterial, normal_enu: [f64; 3]) -> Option<f64> {
        let m = self.materials.iter().position(|&x| x == material)?;
        Some(match self.layout {
            Orientations::Single(_) => self.surface_k(m, 0),
            Orientations::Standard => standard_weights(normal_enu)
                .iter()
                .map(|&(o, w)| w * self.surface_k(m, o))
                .sum(),
        })
    }

    /// Every surface temperature, material-major (`[m * orientations + o]`), kelvin, for
    /// upload to the renderer.
    pub fn surface_temperatures_k(&self) -> Vec<f32> {
        self.slabs.iter().map(|s| s.surface_k() as f32).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_weights_hit_the_table_directions_and_sum_to_one() {
        let list = Orientation::standard();
        assert_eq!(list.len(), 26);
        for (i, o) in list.iter().enumerate() {
            let w = standard_weights(o.normal_enu());
            let total: f64 = w.iter().map(|x| x.1).sum();
            assert!((total - 1.0).abs() < 1e-12);
            let on_self: f64 = w.iter().filter(|x| x.0 == i).map(|x| x.1).sum();
            assert!(on_self > 1.0 - 1e-9, "{i}: {w:?}");
        }
        // Half-way between a south wall and the south-west wall.
        let mid = Orientation::new(90.0, 202.5).expect("valid").normal_enu();
        let w = standard_weights(mid);
        let south = 1 + RING_AZIMUTHS + 4;
        assert!(
            w.contains(&(south, 0.5)) || w.iter().any(|x| x.0 == south && (x.1 - 0.5).abs() < 1e-9)
        );
    }

    proptest::proptest! {
        #[test]
        fn weights_are_a_partition_of_unity(e in -1.0f64..1.0, n in -1.0f64..1.0, u in -1.0f64..1.0) {
            let w = standard_weights([e, n, u]);
            let total: f64 = w.iter().map(|x| x.1).sum();
            proptest::prop_assert!((total - 1.0).abs() < 1e-9);
            proptest::prop_assert!(w.iter().all(|x| x.1 >= -1e-12 && x.0 < 26));
        }
    }
}
