//! The sea as a view draws it: the wave surface's cascade grids at the frame's time (from
//! `cig_sea::surface`), the plane they lie in, the sea level, the slope variance the grids do
//! not resolve and the water's colour. The renderer draws the sea from this and nothing else,
//! so what it draws is the surface the height queries sample.
//!
//! Limits: one wind sea per frame (the host's explicit waves may be confined to regions or
//! around entities), at one level (mean sea level plus the host's sea surface height); the
//! renderer draws at most 8 explicit waves (CIGI Wave Control; the highest) in at most 8
//! areas, where the height queries sample them all.

use cig_geo::Geodetic;
use cig_sea::motion::HullParameters;
use cig_sea::response::ShipRide;
pub use cig_sea::surface::{AreaKind, WaveArea};
use cig_sea::surface::{CascadeGrid, SeaSurface};

/// Cox and Munk's (1954) total mean square slope of a wind sea, `0.003 + 0.00512 U10`.
pub fn cox_munk_slope_variance(wind_speed_mps: f64) -> f64 {
    0.003 + 0.005_12 * wind_speed_mps.clamp(0.0, 60.0)
}

/// Least slope variance left to the shading where the grids resolve almost everything: the
/// capillary ripples no cascade carries.
const MIN_UNRESOLVED_SLOPE_VARIANCE: f64 = 0.000_5;

/// A database water post at most this far above mean sea level (or the sea's level, the
/// higher) is sea, metres: the height queries answer the waves there and the renderer draws
/// the sea instead of the post (a database's sea posts lie at MSL whatever the tide).
pub const SEA_POST_TOLERANCE_M: f64 = 0.5;

/// The waves' clock at a UTC instant: seconds since 2020-01-01T00:00:00Z modulo 2^29 s (17
/// years, inside the surface's ±1e9 s), so every channel and IG given the same time draws the
/// same waves at any date; the waves jump once every 17 years (next in 2037).
pub fn wave_clock_s(unix_time_s: f64) -> f64 {
    (unix_time_s - 1_577_836_800.0).rem_euclid(WAVE_CLOCK_PERIOD_S)
}

/// The period of [`wave_clock_s`], seconds (2^29).
pub const WAVE_CLOCK_PERIOD_S: f64 = 536_870_912.0;

/// Where a latitude and longitude lies in the sea's plane (east, north of its origin, metres):
/// its foot on the ellipsoid in the origin's tangent plane. The renderer, the height queries,
/// line of sight and the floating ships all sample the waves there.
pub fn sea_plane_xy(plane: &cig_geo::EnuFrame, lat_deg: f64, lon_deg: f64) -> [f64; 2] {
    let at = plane.geodetic_to_enu(Geodetic::new(lat_deg, lon_deg, 0.0));
    [at.x, at.y]
}

/// The origin of the plane the waves lie in for a database or view centred at a point: its
/// whole degrees, so nearby channels and IGs share one sea.
pub fn sea_origin(lat_deg: f64, lon_deg: f64) -> Geodetic {
    Geodetic::new(lat_deg.round().clamp(-89.0, 89.0), lon_deg.round(), 0.0)
}

/// One frame's sea.
#[derive(Clone, Debug)]
pub struct SeaDraw {
    /// The point whose tangent plane the wave grids lie in (east, north from it), so every
    /// view and IG samples the same waves at the same place.
    pub origin: Geodetic,
    /// The sea's level above mean sea level (the geoid), metres.
    pub level_m: f64,
    /// The cascades' grids at the frame's time.
    pub cascades: Vec<CascadeGrid>,
    /// Mean square slope (both axes together) of the waves shorter than the finest cascade
    /// carries: Cox-Munk's total less what the grids hold, for the sun's glitter.
    pub unresolved_slope_variance: f64,
    /// Where the summed displacement's Jacobian falls below this, whitecaps.
    pub whitecap_jacobian: f64,
    /// The water body's colour (diffuse reflectance of the light scattered up from below).
    pub water_rgb: [f32; 3],
    /// The water's surface temperature, °C (what a thermal sensor sees the sea emit).
    pub water_temperature_c: f64,
    /// The host's explicit waves (CIGI Wave Control), as the surface evaluates them.
    pub explicit_waves: Vec<cig_sea::surface::GerstnerWave>,
    /// Where each explicit wave applies: `None` everywhere, else its area in `wave_areas`.
    pub explicit_areas: Vec<Option<usize>>,
    /// The areas explicit waves are confined to (`cig_sea::surface::WaveArea`).
    pub wave_areas: Vec<WaveArea>,
    /// The surface's wave clock ([`wave_clock_s`]) the grids and waves are at, seconds.
    pub time_s: f64,
}

impl SeaDraw {
    /// The sea of `surface` (updated to the frame's time) in the tangent plane of `origin`.
    pub fn new(surface: &SeaSurface, origin: Geodetic, level_m: f64) -> SeaDraw {
        let cascades = surface.grids().to_vec();
        let resolved: f64 = cascades.iter().map(slope_variance).sum();
        let total = cox_munk_slope_variance(surface.conditions().wind_speed_mps);
        SeaDraw {
            origin,
            level_m,
            cascades,
            unresolved_slope_variance: (total - resolved).max(MIN_UNRESOLVED_SLOPE_VARIANCE),
            whitecap_jacobian: cig_sea::surface::WHITECAP_JACOBIAN,
            // Open ocean: a deep blue-green of low reflectance (Morel's clear ocean water,
            // about 2 % in the blue, under 0.5 % in the red).
            water_rgb: [0.004, 0.016, 0.028],
            water_temperature_c: 15.0,
            explicit_waves: surface.gerstner_waves().to_vec(),
            explicit_areas: surface.explicit_wave_areas().to_vec(),
            wave_areas: surface.wave_areas().to_vec(),
            time_s: surface.time_s(),
        }
    }
}

/// The hull a built-in model floats on: the ships' (`destroyer` or `ship`, `merchant`,
/// `patrol_craft`) as their meshes are built ([`crate::models::ship_particulars`]); other
/// models do not float.
pub fn builtin_hull(model: &str) -> Option<HullParameters> {
    crate::models::ship_particulars(model).and_then(|p| {
        HullParameters::new(p.length_m, p.beam_m, p.draft_m, p.metacentric_height_m).ok()
    })
}

/// Sets a floating ship on the sea: its waterline (the model's origin) at the sea's mean level
/// under it (`level_ellipsoid_m`: above the ellipsoid) plus its heave, pitched and rolled by
/// `ride` (the hull's response to the sea at its heading and velocity, with what is left of
/// its last change, `cig_sea::response`) at the sea's time `sea_time_s`. `plane_origin` is the
/// sea's origin ([`SeaDraw::origin`]).
pub fn ride_the_sea(
    entity: &mut crate::EntityInstance,
    ride: &ShipRide,
    sea_time_s: f64,
    plane_origin: Geodetic,
    level_ellipsoid_m: f64,
) {
    let plane = cig_geo::EnuFrame::new(plane_origin);
    let [x_east_m, y_north_m] =
        sea_plane_xy(&plane, entity.position.lat_deg, entity.position.lon_deg);
    let motion = ride.motion_at(x_east_m, y_north_m, sea_time_s);
    entity.position.alt_m = level_ellipsoid_m + motion.heave_m;
    entity.orientation.pitch_deg = motion.pitch_deg;
    entity.orientation.roll_deg = motion.roll_deg;
}

/// A ship's wake as the sea draws it (`cig_sea::wake`): the Kelvin arms from the bow and the
/// bow wave on the present course, and the foam of the turbulent wake astern along the stern's
/// past track (straight on where the track ends).
#[derive(Clone, Debug, PartialEq)]
pub struct WakeDraw {
    /// The ship's reference point (the middle of its waterline), above the ellipsoid.
    pub position: Geodetic,
    /// The course made good, degrees true.
    pub heading_deg: f64,
    pub speed_mps: f64,
    pub length_m: f64,
    pub beam_m: f64,
    /// The arms' apparent half-angle (`cig_sea::wake::kelvin_half_angle_deg`), degrees.
    pub arm_half_angle_deg: f64,
    /// The white water the hull makes at this speed, 0..=1 (`cig_sea::wake::foam_generation`).
    pub foam_generation: f64,
    /// The foam's e-folding time, seconds.
    pub foam_e_folding_s: f64,
    /// The stern's past places, newest first, each with its age (seconds): the turbulent
    /// wake follows them ([`WakeTrack`]). Empty: astern along the present course.
    pub track: Vec<(Geodetic, f64)>,
}

/// Most past places of a stern a wake keeps ([`WakeTrack`]).
pub const WAKE_TRACK_POINTS: usize = 12;
/// The newest past places of a stern are kept this far apart in time, seconds: the first
/// [`WAKE_TRACK_NEAR_POINTS`] cover the last 40 s of a turn, where its foam is the brightest,
/// in chords of at most 15 degrees of the tightest turn (3 degrees a second: they sag under
/// 2 m from a 190 m circle).
pub const WAKE_TRACK_SPACING_S: f64 = 5.0;
/// Past places kept at [`WAKE_TRACK_SPACING_S`].
pub const WAKE_TRACK_NEAR_POINTS: usize = 8;
/// Older places are kept one in each span of this many seconds (of the caller's clock), so
/// the track reaches two minutes back; the foam older than that is drawn on along the last
/// chord.
pub const WAKE_TRACK_FAR_SPACING_S: f64 = 20.0;

/// The ages of a track's places (seconds) for a steady ship, newest first: the spacing
/// [`WakeTrack`] keeps.
fn steady_track_ages_s() -> impl Iterator<Item = f64> {
    let near = WAKE_TRACK_NEAR_POINTS as f64 * WAKE_TRACK_SPACING_S;
    (1..=WAKE_TRACK_POINTS).map(move |k| {
        if k <= WAKE_TRACK_NEAR_POINTS {
            k as f64 * WAKE_TRACK_SPACING_S
        } else {
            near + (k - WAKE_TRACK_NEAR_POINTS) as f64 * WAKE_TRACK_FAR_SPACING_S
        }
    })
}

/// A ship's stern's past places, for its wake to follow the track it made: one in each
/// [`WAKE_TRACK_SPACING_S`] of the clock for the newest [`WAKE_TRACK_NEAR_POINTS`], then one
/// in each [`WAKE_TRACK_FAR_SPACING_S`], at most [`WAKE_TRACK_POINTS`]; forgotten when the
/// ship jumps (moved faster than any ship) or was not seen for a while.
#[derive(Clone, Debug, Default)]
pub struct WakeTrack {
    /// (time in seconds of the caller's clock, the stern's place), newest first.
    points: std::collections::VecDeque<(f64, Geodetic)>,
}

/// A ship that moved faster than this between two of its places jumped (a host moved it): its
/// wake's track, its ride on the sea and its speed made good start again, m/s.
pub const SHIP_JUMP_MPS: f64 = 60.0;

impl WakeTrack {
    /// Notes the stern's place at `now_s` (the caller's monotonic clock).
    pub fn record(&mut self, now_s: f64, stern: Geodetic) {
        if let Some(&(then_s, place)) = self.points.front() {
            let dt_s = now_s - then_s;
            let moved_m = cig_geo::EnuFrame::new(place)
                .geodetic_to_enu(stern)
                .truncate()
                .length();
            // Written so that a NaN place or time starts the track again.
            let plausible = (0.0..=3.0 * WAKE_TRACK_SPACING_S).contains(&dt_s)
                && (0.0..=SHIP_JUMP_MPS * dt_s + 5.0).contains(&moved_m);
            // One place in each span of the clock (not one a span after the last), so channels
            // of one IG, drawing the same frames, keep the same places.
            let span = |t: f64| (t / WAKE_TRACK_SPACING_S).floor();
            if !plausible {
                self.points.clear();
            } else if span(now_s) == span(then_s) {
                return;
            }
        }
        self.points.push_front((now_s, stern));
        // Past the near places, one in each far span of the clock: a place that has just
        // left the near ones stays only if no older kept place shares its span.
        let span = |t: f64| (t / WAKE_TRACK_FAR_SPACING_S).floor();
        if let Some(&(t, _)) = self.points.get(WAKE_TRACK_NEAR_POINTS) {
            let older = self.points.get(WAKE_TRACK_NEAR_POINTS + 1);
            if older.is_some_and(|&(o, _)| span(o) == span(t)) {
                self.points.remove(WAKE_TRACK_NEAR_POINTS);
            }
        }
        self.points.truncate(WAKE_TRACK_POINTS);
    }

    /// `wake` at `now_s`, its stern's place noted first, following the places kept.
    pub fn follow(&mut self, now_s: f64, mut wake: WakeDraw) -> WakeDraw {
        self.record(now_s, wake.stern());
        wake.track = self.drawn(now_s);
        wake
    }

    /// The places with their ages at `now_s`, newest first, for [`WakeDraw::track`].
    pub fn drawn(&self, now_s: f64) -> Vec<(Geodetic, f64)> {
        self.points
            .iter()
            .map(|&(then_s, place)| (place, (now_s - then_s).max(0.0)))
            .collect()
    }
}

/// Ships under way slower than this leave no wake drawn, m/s (about 1 knot).
pub const MIN_WAKE_SPEED_MPS: f64 = 0.5;

impl WakeDraw {
    /// The wake of a built-in ship (`model`, see [`crate::models::ship_particulars`]) at
    /// `position` on `heading_deg` at `speed_mps`; `None` for other models, a ship slower than
    /// [`MIN_WAKE_SPEED_MPS`] or values out of range.
    pub fn of_ship(
        model: &str,
        position: Geodetic,
        heading_deg: f64,
        speed_mps: f64,
    ) -> Option<WakeDraw> {
        let hull = crate::models::ship_particulars(model)?;
        if !(speed_mps.is_finite() && speed_mps >= MIN_WAKE_SPEED_MPS && heading_deg.is_finite()) {
            return None;
        }
        let speed_mps = speed_mps.min(40.0);
        Some(WakeDraw {
            position,
            heading_deg,
            speed_mps,
            length_m: hull.length_m,
            beam_m: hull.beam_m,
            arm_half_angle_deg: cig_sea::wake::kelvin_half_angle_deg(speed_mps, hull.length_m)
                .ok()?,
            foam_generation: cig_sea::wake::foam_generation(speed_mps).ok()?,
            foam_e_folding_s: cig_sea::wake::DEFAULT_FOAM_E_FOLDING_S,
            track: Vec::new(),
        })
    }

    /// The middle of the stern's waterline: half a length astern of the reference point along
    /// the course.
    pub fn stern(&self) -> Geodetic {
        let frame = cig_geo::EnuFrame::new(self.position);
        let (s, c) = self.heading_deg.to_radians().sin_cos();
        let half = 0.5 * self.length_m;
        frame.enu_to_geodetic(glam::DVec3::new(-s * half, -c * half, 0.0))
    }

    /// This wake as a ship's that has been turning at `turn_deg_s` (positive to starboard) at
    /// its present speed: its stern's past places on that circle, as far apart as a
    /// [`WakeTrack`] keeps them (a single picture's stand-in for the track a running IG
    /// records).
    pub fn turning(mut self, turn_deg_s: f64) -> WakeDraw {
        if !turn_deg_s.is_finite() {
            return self;
        }
        let frame = cig_geo::EnuFrame::new(self.position);
        let omega = turn_deg_s.to_radians();
        const STEP_S: f64 = 0.5;
        let (mut east_m, mut north_m, mut age_s) = (0.0, 0.0, 0.0);
        let mut heading = self.heading_deg.to_radians();
        let mut track = Vec::with_capacity(WAKE_TRACK_POINTS);
        for wanted_s in steady_track_ages_s() {
            // Back along the circle: each half second the ship came along its heading at the
            // middle of it.
            while age_s < wanted_s - 1e-9 {
                let middle = heading - 0.5 * omega * STEP_S;
                east_m -= self.speed_mps * middle.sin() * STEP_S;
                north_m -= self.speed_mps * middle.cos() * STEP_S;
                heading -= omega * STEP_S;
                age_s += STEP_S;
            }
            let then = WakeDraw {
                position: frame.enu_to_geodetic(glam::DVec3::new(east_m, north_m, 0.0)),
                heading_deg: heading.to_degrees(),
                track: Vec::new(),
                ..self.clone()
            };
            track.push((then.stern(), age_s));
        }
        self.track = track;
        self
    }
}

/// Mean square slope of one grid, both axes together.
pub fn slope_variance(grid: &CascadeGrid) -> f64 {
    let n = grid.slopes.len().max(1) as f64;
    grid.slopes
        .iter()
        .map(|s| f64::from(s[0]).powi(2) + f64::from(s[1]).powi(2))
        .sum::<f64>()
        / n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn destroyer(heading_deg: f64) -> WakeDraw {
        WakeDraw::of_ship(
            "destroyer",
            Geodetic::new(36.0, -121.0, 0.0),
            heading_deg,
            10.0,
        )
        .expect("a wake")
    }

    #[test]
    fn a_wake_track_keeps_the_sterns_places_apart_and_forgets_a_jump() {
        let mut track = WakeTrack::default();
        let wake = destroyer(0.0);
        let frame = cig_geo::EnuFrame::new(wake.stern());
        // North at 10 m/s, noted every frame for 200 s.
        for k in 0..=12_000 {
            let t = f64::from(k) / 60.0;
            track.record(
                t,
                frame.enu_to_geodetic(glam::DVec3::new(0.0, 10.0 * t, 0.0)),
            );
            if k % 600 == 0 {
                let ages: Vec<f64> = track.drawn(t).iter().map(|(_, a)| *a).collect();
                assert!(ages.windows(2).all(|a| a[1] > a[0]), "{ages:?}");
            }
        }
        let drawn = track.drawn(200.0);
        assert_eq!(drawn.len(), WAKE_TRACK_POINTS);
        for (k, (place, age_s)) in drawn.iter().enumerate() {
            let north = frame.geodetic_to_enu(*place).y;
            assert!((north - 10.0 * (200.0 - age_s)).abs() < 0.01, "{north}");
            if k < WAKE_TRACK_NEAR_POINTS {
                assert!(
                    (age_s - k as f64 * WAKE_TRACK_SPACING_S).abs() < 0.02,
                    "{drawn:?}"
                );
            } else {
                // One in each 20 s span of the clock, so 5 to 25 s apart.
                let gap = age_s - drawn[k - 1].1;
                assert!(gap > 4.9 && gap < 25.1, "{drawn:?}");
            }
        }
        // About two minutes back.
        let oldest = drawn[WAKE_TRACK_POINTS - 1].1;
        assert!((100.0..=125.0).contains(&oldest), "{drawn:?}");
        // A jump of a kilometre in a frame starts the track again.
        track.record(
            200.02,
            frame.enu_to_geodetic(glam::DVec3::new(1000.0, 1000.0, 0.0)),
        );
        assert_eq!(track.drawn(200.02).len(), 1);
        // So does a clock gone back.
        track.record(50.0, wake.stern());
        assert_eq!(track.drawn(50.0).len(), 1);
    }

    #[test]
    fn a_turning_ships_wake_lies_on_its_circle_and_a_steady_ones_straight_astern() {
        let frame = cig_geo::EnuFrame::new(destroyer(0.0).stern());
        let straight = destroyer(0.0).turning(0.0);
        assert_eq!(straight.track.len(), WAKE_TRACK_POINTS);
        for (place, age_s) in &straight.track {
            let at = frame.geodetic_to_enu(*place);
            assert!(
                at.x.abs() < 0.01 && (at.y + 10.0 * age_s).abs() < 0.05,
                "{at}"
            );
        }
        // Turning to starboard at 1.5 degrees a second it came from the south-east (heading
        // north-west before; the track's two minutes are half the circle): its circle's
        // radius is V / omega about a centre to starboard (east of the ship), and the stern's
        // past places keep their distance from it.
        let turning = destroyer(0.0).turning(1.5);
        let radius_m = 10.0 / 1.5f64.to_radians();
        let ship = frame.geodetic_to_enu(turning.position);
        let centre = [ship.x + radius_m, ship.y];
        let half = 0.5 * turning.length_m;
        for (place, _) in &turning.track {
            let at = frame.geodetic_to_enu(*place);
            let r = (at.x - centre[0]).hypot(at.y - centre[1]);
            // The stern lies half a length astern along the tangent, just off the circle.
            assert!(
                (r - radius_m.hypot(half)).abs() < 0.5,
                "{r} against {radius_m}"
            );
            assert!(at.x > ship.x + 0.01, "{at}");
        }
        assert!(turning.track.iter().all(|(_, a)| a.is_finite()));
        assert!(destroyer(0.0).turning(f64::NAN).track.is_empty());
    }
    use cig_sea::spectrum::SeaConditions;
    use cig_sea::surface::SurfaceConfig;

    #[test]
    fn the_grids_and_the_unresolved_slopes_make_up_cox_munk() {
        for wind in [3.0, 8.0, 15.0] {
            let conditions = SeaConditions::new(wind, 270.0).expect("conditions");
            let mut surface =
                SeaSurface::new(&conditions, 3, SurfaceConfig::default()).expect("surface");
            surface.update(10.0).expect("update");
            let sea = SeaDraw::new(&surface, Geodetic::new(36.0, -122.0, 0.0), 0.0);
            let resolved: f64 = sea.cascades.iter().map(slope_variance).sum();
            let total = cox_munk_slope_variance(wind);
            // The cascades carry most of the slopes (waves down to 0.3 m); what they miss is
            // left to the glitter.
            assert!(
                (0.3 * total..1.2 * total).contains(&resolved),
                "{wind}: the grids' {resolved} against Cox-Munk's {total}"
            );
            assert!(
                (resolved + sea.unresolved_slope_variance - total.max(resolved)).abs() < 1e-3,
                "{wind}: {resolved} + {}",
                sea.unresolved_slope_variance
            );
        }
    }

    #[test]
    fn a_ship_rides_higher_seas_harder() {
        let origin = Geodetic::new(36.0, -122.0, 0.0);
        let hull = builtin_hull("ship").expect("the ship floats");
        assert!(builtin_hull("tank").is_none());
        let motion = |code: u8| {
            let conditions = SeaConditions::for_sea_state(code, 270.0).expect("sea state");
            let mut surface =
                SeaSurface::new(&conditions, 5, SurfaceConfig::default()).expect("surface");
            let response =
                cig_sea::response::ResponseCache::of(&surface).response(&hull, 30.0, [2.0, 3.0]);
            let mut sum = 0.0;
            for k in 0..12 {
                surface.update(f64::from(k) * 1.7).expect("update");
                let sea = SeaDraw::new(&surface, origin, 0.0);
                let mut ship = crate::EntityInstance {
                    id: 1,
                    model: "ship".into(),
                    position: Geodetic::new(36.001, -122.001, 0.0),
                    orientation: crate::Hpr {
                        heading_deg: 30.0,
                        ..Default::default()
                    },
                    cue_important: false,
                    critical_radius_m: None,
                };
                ride_the_sea(
                    &mut ship,
                    &ShipRide::steady(std::sync::Arc::clone(&response), None, [2.0, 3.0]),
                    surface.time_s(),
                    sea.origin,
                    sea.level_m - 30.0,
                );
                sum += (ship.position.alt_m + 30.0).abs()
                    + ship.orientation.pitch_deg.abs()
                    + ship.orientation.roll_deg.abs();
            }
            sum
        };
        let calm = motion(2);
        let rough = motion(6);
        assert!(rough > 4.0 * calm, "sea state 2: {calm}, 6: {rough}");
    }
}
