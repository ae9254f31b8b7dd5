//! A ship's wake: the Kelvin wave pattern, the bow wave and the foam of the turbulent wake.
//!
//! Algorithms and sources:
//!
//! - Wake angle. Kelvin's wedge bounds the waves of a moving disturbance on deep water at the
//!   half-angle `asin(1/3)` = 19.47°, at any speed. Rabaud & Moisy ("Ship wakes: Kelvin or
//!   Mach angle?", Phys. Rev. Lett. 110, 214503, 2013) showed from airborne images that the
//!   *visible* wake, the angle of maximum wave amplitude, narrows as `1/Fr` above a hull
//!   Froude number `Fr = U / √(g L)` of about 0.5, because a hull of length `L` makes no
//!   waves much longer than itself. Their model's Mach-like limit is the group velocity of the
//!   longest wave, `c_g = ½ √(g L / 2π)`, over the speed: `α ≈ 1 / (2 √(2π) Fr)` ≈ 0.20 / Fr
//!   radians. [`kelvin_half_angle_deg`] is the smaller of 19.47° and that, which switches at
//!   Fr ≈ 0.59 (the paper's measured transition is gradual, around 0.5). Darmon, Benzaquen &
//!   Raphaël (J. Fluid Mech. 738, R3, 2014) confirm the `1/Fr` law for the angle of maximum
//!   amplitude while the wedge that bounds all waves stays at 19.47°: so the wake's bright
//!   arms lie at [`kelvin_half_angle_deg`] and nothing is drawn outside 19.47°.
//! - Wake intensity ([`wake_intensity`], a shape 0..=1 for the renderer to scale): the arms
//!   are a Gaussian in angle about the apparent angle (width a quarter of it) decaying with the
//!   distance `r` from the bow as `(1 + r / L)^(−1/3)`, the decay of Kelvin's cusp waves;
//!   zero ahead of the bow and outside the 19.47° wedge. The transverse waves inside the wedge
//!   are left to the renderer ([`transverse_wavelength_m`]: `2π U² / g`).
//! - Bow wave height, after Noblesse, Delhommeau, Guilbaud, Hendrix & Yang ("Simple analytical
//!   relations for ship bow waves", J. Fluid Mech. 600, 2008) for a wedge-shaped bow of
//!   waterline entrance half-angle `α_E` and draft `D`:
//!   `Z_b = 2.2 tan α_E / (1 + F_D) · U² / g` with `F_D = U / √(g D)`, capped by the
//!   stagnation head `U² / 2g`. The coefficient is as this module's author recalls the paper;
//!   check it against the paper before relying on exact heights.
//! - Foam of the turbulent wake: white water is made at a strength rising smoothly from none
//!   at 1 m/s (2 kn) to full at 8 m/s (15.5 kn) (a rendering choice), then fades as
//!   `exp(−age / τ)` with the e-folding time τ = 90 s by default (a choice in the 60–120 s
//!   range: at 15 kn the white trail stays visible for 1–2 km). The foam band starts a beam
//!   wide at the stern and widens as the self-propelled (momentumless) turbulent wake,
//!   `width = B · max(1, s / B)^(1/5)` at a distance `s` astern (Tennekes & Lumley, *A First
//!   Course in Turbulence*, 1972, ch. 4); across it the coverage falls as
//!   `(1 − (2 d / width)²)²`. [`FoamTrail::coverage`] follows the ship's recorded track, so
//!   a turning ship leaves a curved trail (the renderer's foam follows the stern's past places
//!   the same way, `cig-scene::sea::WakeTrack`); [`wake_intensity`] assumes a straight course.
//!
//! Limits: deep water (no finite-depth wake, which widens near depth Froude number 1); calm
//! water (the ambient sea is added by the renderer); no wave-wave interaction, no wake of
//! a planing hull's spray, no bow-wave breaking; foam from a stopped ship is not made; track
//! points are the stern's positions.

use crate::{checked, SeaError, G_MPS2};

/// Kelvin's wedge half-angle, degrees: `asin(1/3)`.
pub const KELVIN_HALF_ANGLE_DEG: f64 = 19.471_220_634_490_69;

/// The Mach-like coefficient of Rabaud & Moisy's wake angle, radians: `1 / (2 √(2π))`, the
/// angle being this over the hull Froude number.
pub const MACH_COEFFICIENT: f64 = 0.199_471_140_200_716_35;

/// The default e-folding time of the foam trail, s.
pub const DEFAULT_FOAM_E_FOLDING_S: f64 = 90.0;

/// Foam older than this many e-folding times is dropped (less than 5·10⁻⁵ of its start).
const FOAM_MAX_E_FOLDS: f64 = 10.0;

fn speed(speed_mps: f64) -> Result<f64, SeaError> {
    checked("speed_mps", speed_mps, 0.0, 40.0, "0..=40 m/s")
}

fn length(hull_length_m: f64) -> Result<f64, SeaError> {
    checked("hull_length_m", hull_length_m, 1.0, 500.0, "1..=500 m")
}

fn beam(beam_m: f64) -> Result<f64, SeaError> {
    checked("beam_m", beam_m, 0.2, 100.0, "0.2..=100 m")
}

/// The hull Froude number `U / √(g L)` of a hull `hull_length_m` long (1..=500 m) at
/// `speed_mps` (0..=40 m/s).
pub fn hull_froude_number(speed_mps: f64, hull_length_m: f64) -> Result<f64, SeaError> {
    let u = speed(speed_mps)?;
    let l = length(hull_length_m)?;
    Ok(u / (G_MPS2 * l).sqrt())
}

/// The half-angle of the visible wake (the angle of maximum wave amplitude), degrees:
/// 19.47° up to a hull Froude number of about 0.59, `1 / (2 √(2π) Fr)` radians above it
/// (Rabaud & Moisy 2013).
pub fn kelvin_half_angle_deg(speed_mps: f64, hull_length_m: f64) -> Result<f64, SeaError> {
    let fr = hull_froude_number(speed_mps, hull_length_m)?;
    Ok(apparent_angle_deg(fr))
}

fn apparent_angle_deg(fr: f64) -> f64 {
    if fr <= 0.0 {
        KELVIN_HALF_ANGLE_DEG
    } else {
        KELVIN_HALF_ANGLE_DEG.min((MACH_COEFFICIENT / fr).to_degrees())
    }
}

/// The wavelength of the transverse waves following a ship at `speed_mps` (0..=40 m/s), m:
/// waves whose phase speed is the ship's, `2π U² / g`.
pub fn transverse_wavelength_m(speed_mps: f64) -> Result<f64, SeaError> {
    let u = speed(speed_mps)?;
    Ok(std::f64::consts::TAU * u * u / G_MPS2)
}

/// Height of the bow wave's crest above the calm sea, m, for a wedge-shaped bow of waterline
/// entrance half-angle `entrance_half_angle_deg` (1..=60°) and draft `draft_m` (0.1..=30 m) at
/// `speed_mps` (0..=40 m/s): `2.2 tan α_E / (1 + F_D) · U² / g` (Noblesse et al. 2008), at
/// most the stagnation head `U² / 2g`.
pub fn bow_wave_height_m(
    speed_mps: f64,
    draft_m: f64,
    entrance_half_angle_deg: f64,
) -> Result<f64, SeaError> {
    let u = speed(speed_mps)?;
    let d = checked("draft_m", draft_m, 0.1, 30.0, "0.1..=30 m")?;
    let a = checked(
        "entrance_half_angle_deg",
        entrance_half_angle_deg,
        1.0,
        60.0,
        "1..=60 deg",
    )?;
    let head = u * u / G_MPS2;
    let f_d = u / (G_MPS2 * d).sqrt();
    let ratio = 2.2 * a.to_radians().tan() / (1.0 + f_d);
    Ok(ratio.min(0.5) * head)
}

/// The width of the turbulent (foam) wake `distance_astern_m` (0..=1000 km) behind the stern
/// of a ship of beam `beam_m` (0.2..=100 m), m: `B · max(1, s / B)^(1/5)`.
pub fn turbulent_wake_width_m(beam_m: f64, distance_astern_m: f64) -> Result<f64, SeaError> {
    let b = beam(beam_m)?;
    let s = checked(
        "distance_astern_m",
        distance_astern_m,
        0.0,
        1.0e6,
        "0..=1000000 m",
    )?;
    Ok(wake_width(b, s))
}

fn wake_width(b: f64, s: f64) -> f64 {
    b * (s / b).max(1.0).powf(0.2)
}

/// The foam made by a ship at `speed_mps` (0..=40 m/s), 0..=1: none up to 1 m/s, rising
/// smoothly (smoothstep) to full at 8 m/s.
pub fn foam_generation(speed_mps: f64) -> Result<f64, SeaError> {
    Ok(generation(speed(speed_mps)?))
}

fn generation(u: f64) -> f64 {
    let x = ((u - 1.0) / 7.0).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The across-wake profile of the foam: `(1 − (2 d / w)²)²` inside the band, 0 outside.
fn band(across_m: f64, width_m: f64) -> f64 {
    let x = 2.0 * across_m / width_m;
    if x.abs() >= 1.0 {
        0.0
    } else {
        let y = 1.0 - x * x;
        y * y
    }
}

/// One point of a ship's recorded track: where its stern was at a time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrackPoint {
    /// Time, s.
    pub t_s: f64,
    /// Stern position east of the frame's origin, m.
    pub x_east_m: f64,
    /// Stern position north of the frame's origin, m.
    pub y_north_m: f64,
}

/// The foam trail: how long the white water of the turbulent wake lasts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoamTrail {
    e_folding_s: f64,
}

impl Default for FoamTrail {
    /// [`FoamTrail::DEFAULT`].
    fn default() -> FoamTrail {
        FoamTrail::DEFAULT
    }
}

impl FoamTrail {
    /// Foam fading with an e-folding time of 90 s.
    pub const DEFAULT: FoamTrail = FoamTrail {
        e_folding_s: DEFAULT_FOAM_E_FOLDING_S,
    };

    /// Foam fading with an e-folding time `e_folding_s` (1..=3600 s).
    pub fn new(e_folding_s: f64) -> Result<FoamTrail, SeaError> {
        Ok(FoamTrail {
            e_folding_s: checked("e_folding_s", e_folding_s, 1.0, 3600.0, "1..=3600 s")?,
        })
    }

    /// The e-folding time, s.
    pub fn e_folding_s(&self) -> f64 {
        self.e_folding_s
    }

    /// The foam coverage (0..=1) on the wake's centreline `age_s` (0..=10⁹ s) after a ship at
    /// `speed_mps` (0..=40 m/s) passed: [`foam_generation`] × `exp(−age / τ)`.
    pub fn coverage_at_age(&self, age_s: f64, speed_mps: f64) -> Result<f64, SeaError> {
        let age = checked("age_s", age_s, 0.0, 1.0e9, "0..=1e9 s")?;
        Ok(generation(speed(speed_mps)?) * self.fade(age))
    }

    fn fade(&self, age: f64) -> f64 {
        if age > FOAM_MAX_E_FOLDS * self.e_folding_s {
            0.0
        } else {
            (-age / self.e_folding_s).exp()
        }
    }

    /// The foam coverage (0..=1) at (`x_east_m`, `y_north_m`) at `t_s` behind a ship of beam
    /// `beam_m` (0.2..=100 m) whose stern followed `track` (times increasing; positions
    /// finite). Points of the track after `t_s` are not yet sailed; the track's segments are
    /// straight, the foam made on each at its own speed; the coverage is the largest over the
    /// segments, 0 beyond the track's ends and for foam older than ten e-folding times.
    pub fn coverage(
        &self,
        track: &[TrackPoint],
        beam_m: f64,
        x_east_m: f64,
        y_north_m: f64,
        t_s: f64,
    ) -> Result<f64, SeaError> {
        let b = beam(beam_m)?;
        let qx = checked("x_east_m", x_east_m, -1.0e7, 1.0e7, "-1e7..=1e7 m")?;
        let qy = checked("y_north_m", y_north_m, -1.0e7, 1.0e7, "-1e7..=1e7 m")?;
        let t = checked("t_s", t_s, -1.0e12, 1.0e12, "finite, |t| <= 1e12 s")?;
        let mut previous = f64::NEG_INFINITY;
        for p in track {
            if !p.t_s.is_finite() || p.t_s <= previous {
                return Err(SeaError::OutOfRange {
                    name: "track time",
                    range: "finite and increasing",
                    value: p.t_s,
                });
            }
            checked("track x_east_m", p.x_east_m, -1.0e7, 1.0e7, "-1e7..=1e7 m")?;
            checked(
                "track y_north_m",
                p.y_north_m,
                -1.0e7,
                1.0e7,
                "-1e7..=1e7 m",
            )?;
            previous = p.t_s;
        }
        // The track sailed by `t`: the points up to it and, inside a segment, where the
        // stern is at `t`.
        let sailed = track.partition_point(|p| p.t_s <= t);
        let mut path: Vec<TrackPoint> = track[..sailed].to_vec();
        if let (Some(&a), Some(&b2)) = (path.last(), track.get(sailed)) {
            let u = (t - a.t_s) / (b2.t_s - a.t_s);
            if u > 0.0 {
                path.push(TrackPoint {
                    t_s: t,
                    x_east_m: a.x_east_m + u * (b2.x_east_m - a.x_east_m),
                    y_north_m: a.y_north_m + u * (b2.y_north_m - a.y_north_m),
                });
            }
        }
        let segments = path.len().saturating_sub(1);
        let oldest_age = FOAM_MAX_E_FOLDS * self.e_folding_s;
        let mut best: f64 = 0.0;
        // Distance along the track from the stern's latest position, m.
        let mut astern = 0.0;
        for i in (0..segments).rev() {
            let (a, bp) = (path[i], path[i + 1]);
            if t - bp.t_s > oldest_age {
                break;
            }
            let (dx, dy) = (bp.x_east_m - a.x_east_m, bp.y_north_m - a.y_north_m);
            let len2 = dx * dx + dy * dy;
            let len = len2.sqrt();
            let seg_astern = astern;
            astern += len;
            if len2 == 0.0 {
                continue;
            }
            let mut u = ((qx - a.x_east_m) * dx + (qy - a.y_north_m) * dy) / len2;
            // Past a segment's newer end the next segment (clamped to its older end) or
            // nothing (ahead of the stern) covers the point; before the oldest end, nothing.
            if u > 1.0 || (i == 0 && u < 0.0) {
                continue;
            }
            u = u.clamp(0.0, 1.0);
            let (cx, cy) = (a.x_east_m + u * dx, a.y_north_m + u * dy);
            let across = (qx - cx).hypot(qy - cy);
            let tau = a.t_s + u * (bp.t_s - a.t_s);
            let age = (t - tau).max(0.0);
            let s = seg_astern + (1.0 - u) * len;
            let made = generation((len / (bp.t_s - a.t_s)).min(40.0));
            let value = made * self.fade(age) * band(across, wake_width(b, s));
            best = best.max(value);
        }
        Ok(best.clamp(0.0, 1.0))
    }
}

/// A ship making a wake: hull length and beam and its speed through the water.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WakeShip {
    length_m: f64,
    beam_m: f64,
    speed_mps: f64,
}

impl WakeShip {
    /// A hull `length_m` long (1..=500 m) and `beam_m` wide (0.2..=100 m, at most the length)
    /// at `speed_mps` (0..=40 m/s).
    pub fn new(length_m: f64, beam_m: f64, speed_mps: f64) -> Result<WakeShip, SeaError> {
        let length_m = length(length_m)?;
        let beam_m = beam(beam_m)?;
        if beam_m > length_m {
            return Err(SeaError::OutOfRange {
                name: "beam_m",
                range: "at most length_m",
                value: beam_m,
            });
        }
        Ok(WakeShip {
            length_m,
            beam_m,
            speed_mps: speed(speed_mps)?,
        })
    }

    /// Hull length, m.
    pub fn length_m(&self) -> f64 {
        self.length_m
    }

    /// Beam, m.
    pub fn beam_m(&self) -> f64 {
        self.beam_m
    }

    /// Speed through the water, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.speed_mps
    }

    /// The hull Froude number `U / √(g L)`.
    pub fn froude_number(&self) -> f64 {
        self.speed_mps / (G_MPS2 * self.length_m).sqrt()
    }

    /// The half-angle of the visible wake, degrees ([`kelvin_half_angle_deg`]).
    pub fn half_angle_deg(&self) -> f64 {
        apparent_angle_deg(self.froude_number())
    }
}

/// The wake at a point near a ship on a straight course, each part 0..=1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WakeIntensity {
    /// The Kelvin wave arms (scale by the bow wave height for an amplitude).
    pub kelvin: f64,
    /// Foam coverage of the turbulent wake.
    pub foam: f64,
}

/// The wake of `ship` at `along_m` astern of its bow (negative: ahead; |along| <= 1000 km) and
/// `across_m` to either side of its track (|across| <= 1000 km), for a straight course at
/// constant speed, with the foam fading as `foam` says. Zero ahead of the bow, outside the
/// 19.47° wedge and for a ship at rest.
pub fn wake_intensity(
    along_m: f64,
    across_m: f64,
    ship: &WakeShip,
    foam: &FoamTrail,
) -> Result<WakeIntensity, SeaError> {
    let along = checked("along_m", along_m, -1.0e6, 1.0e6, "-1e6..=1e6 m")?;
    let across = checked("across_m", across_m, -1.0e6, 1.0e6, "-1e6..=1e6 m")?;
    let u = ship.speed_mps;
    if along <= 0.0 || u <= 0.0 {
        return Ok(WakeIntensity::default());
    }
    let theta = across.abs().atan2(along);
    let kelvin_rad = KELVIN_HALF_ANGLE_DEG.to_radians();
    if theta > kelvin_rad {
        return Ok(WakeIntensity::default());
    }
    let alpha = ship.half_angle_deg().to_radians();
    let sigma = 0.25 * alpha;
    let r = along.hypot(across);
    let arm =
        (-((theta - alpha) / sigma).powi(2)).exp() * (1.0 + r / ship.length_m).powf(-1.0 / 3.0);
    let astern = along - ship.length_m;
    let foam_part = if astern > 0.0 {
        let age = astern / u;
        generation(u) * foam.fade(age) * band(across, wake_width(ship.beam_m, astern))
    } else {
        0.0
    };
    Ok(WakeIntensity {
        kelvin: arm.clamp(0.0, 1.0),
        foam: foam_part.clamp(0.0, 1.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kelvin_angle_at_low_froude_numbers() {
        assert!((KELVIN_HALF_ANGLE_DEG - (1.0f64 / 3.0).asin().to_degrees()).abs() < 1e-12);
        assert!((MACH_COEFFICIENT - 1.0 / (2.0 * std::f64::consts::TAU.sqrt())).abs() < 1e-15);
        // A destroyer at 10 kn (Fr 0.13) and a ship at rest.
        assert_eq!(
            kelvin_half_angle_deg(5.14, 150.0).unwrap(),
            KELVIN_HALF_ANGLE_DEG
        );
        assert_eq!(
            kelvin_half_angle_deg(0.0, 150.0).unwrap(),
            KELVIN_HALF_ANGLE_DEG
        );
        let fr = hull_froude_number(5.14, 150.0).unwrap();
        assert!((fr - 0.134).abs() < 0.001, "{fr}");
    }

    #[test]
    fn the_wake_narrows_at_high_froude_numbers() {
        // A 30 m patrol craft: 20 kn (Fr 0.60), 30 kn (0.90), 40 kn (1.20).
        let a20 = kelvin_half_angle_deg(10.3, 30.0).unwrap();
        let a30 = kelvin_half_angle_deg(15.4, 30.0).unwrap();
        let a40 = kelvin_half_angle_deg(20.6, 30.0).unwrap();
        assert!(
            a20 < KELVIN_HALF_ANGLE_DEG && a30 < a20 && a40 < a30,
            "{a20} {a30} {a40}"
        );
        // As 1/Fr: 0.2/Fr radians.
        let fr = hull_froude_number(20.6, 30.0).unwrap();
        assert!((a40 - (0.1995 / fr).to_degrees()).abs() < 0.01, "{a40}");
        assert!((a40 * fr - a30 * hull_froude_number(15.4, 30.0).unwrap()).abs() < 1e-9);
        // Fr = 1: 11.4°.
        let u = (G_MPS2 * 30.0f64).sqrt();
        assert!((kelvin_half_angle_deg(u, 30.0).unwrap() - 11.43).abs() < 0.01);
        let ship = WakeShip::new(30.0, 6.0, 20.6).unwrap();
        assert_eq!(ship.half_angle_deg(), a40);
    }

    #[test]
    fn foam_decays_with_age() {
        let foam = FoamTrail::DEFAULT;
        let u = 10.0;
        let c0 = foam.coverage_at_age(0.0, u).unwrap();
        let c1 = foam.coverage_at_age(90.0, u).unwrap();
        let c2 = foam.coverage_at_age(300.0, u).unwrap();
        assert_eq!(c0, 1.0);
        assert!((c1 - (-1.0f64).exp()).abs() < 1e-12, "{c1}");
        assert!(c2 < c1 && c2 > 0.0);
        assert_eq!(foam.coverage_at_age(2000.0, u).unwrap(), 0.0);
        // No foam from a ship barely moving, half at 4.5 m/s.
        assert_eq!(foam.coverage_at_age(0.0, 0.5).unwrap(), 0.0);
        assert!((foam_generation(4.5).unwrap() - 0.5).abs() < 1e-12);
        let quick = FoamTrail::new(30.0).unwrap();
        assert!(quick.coverage_at_age(60.0, u).unwrap() < c1);
    }

    #[test]
    fn wake_intensity_inside_and_outside_the_wedge() {
        let ship = WakeShip::new(150.0, 18.0, 10.0).unwrap();
        let foam = FoamTrail::DEFAULT;
        let at = |along: f64, across: f64| wake_intensity(along, across, &ship, &foam).unwrap();
        // On the arm, 500 m astern of the bow.
        let alpha = ship.half_angle_deg().to_radians();
        let arm = at(500.0 * alpha.cos(), 500.0 * alpha.sin());
        assert!(arm.kelvin > 0.5, "{arm:?}");
        let far_arm = at(5000.0 * alpha.cos(), 5000.0 * alpha.sin());
        assert!(far_arm.kelvin < arm.kelvin && far_arm.kelvin > 0.0);
        // Outside the 19.47° wedge and ahead of the bow: nothing.
        let outside = 25.0f64.to_radians();
        assert_eq!(
            at(500.0 * outside.cos(), 500.0 * outside.sin()),
            WakeIntensity::default()
        );
        assert_eq!(at(-10.0, 0.0), WakeIntensity::default());
        assert_eq!(at(1000.0, 400.0), WakeIntensity::default());
        // Foam on the centreline astern of the stern, fading with distance, none beside it.
        let near = at(300.0, 0.0);
        let far = at(5000.0, 0.0);
        assert!(
            near.foam > 0.8 && far.foam < near.foam && far.foam > 0.0,
            "{near:?} {far:?}"
        );
        assert_eq!(at(300.0, 30.0).foam, 0.0);
        assert_eq!(at(100.0, 0.0).foam, 0.0);
        // A ship at rest makes no wake.
        let still = WakeShip::new(150.0, 18.0, 0.0).unwrap();
        assert_eq!(
            wake_intensity(300.0, 0.0, &still, &foam).unwrap(),
            WakeIntensity::default()
        );
    }

    #[test]
    fn foam_trail_follows_the_track() {
        let foam = FoamTrail::DEFAULT;
        // Stern north at 10 m/s from (0, 0) at t = 0 to (0, 3000) at t = 300.
        let track: Vec<TrackPoint> = (0..=300)
            .map(|i| TrackPoint {
                t_s: f64::from(i),
                x_east_m: 0.0,
                y_north_m: 10.0 * f64::from(i),
            })
            .collect();
        let cov = |x: f64, y: f64, t: f64| foam.coverage(&track, 18.0, x, y, t).unwrap();
        let young = cov(0.0, 2900.0, 300.0);
        let old = cov(0.0, 500.0, 300.0);
        assert!(young > old && old > 0.0, "{young} {old}");
        assert!((young - (-10.0f64 / 90.0).exp()).abs() < 1e-9, "{young}");
        // Beside the trail, ahead of the stern, and where the ship has not yet been.
        assert_eq!(cov(200.0, 2900.0, 300.0), 0.0);
        assert_eq!(cov(0.0, 3100.0, 300.0), 0.0);
        assert_eq!(cov(0.0, 2000.0, 100.0), 0.0);
        // Between track samples at t = 150.5 the stern is at 1505 m.
        assert!(cov(0.0, 1504.0, 150.5) > 0.98);
        assert_eq!(cov(0.0, 1506.0, 150.5), 0.0);
        // The band widens astern: 8 m off the centreline there is more foam 2 km astern than
        // in the first 100 m, relative to the centreline.
        let rel = |y: f64| cov(8.0, y, 300.0) / cov(0.0, y, 300.0);
        assert!(rel(1000.0) > rel(2950.0), "{} {}", rel(1000.0), rel(2950.0));
        assert!(turbulent_wake_width_m(18.0, 2000.0).unwrap() > 18.0);
        assert_eq!(turbulent_wake_width_m(18.0, 10.0).unwrap(), 18.0);
        // A turn: the trail follows the corner.
        let turn = [
            TrackPoint {
                t_s: 0.0,
                x_east_m: 0.0,
                y_north_m: 0.0,
            },
            TrackPoint {
                t_s: 100.0,
                x_east_m: 0.0,
                y_north_m: 1000.0,
            },
            TrackPoint {
                t_s: 200.0,
                x_east_m: 1000.0,
                y_north_m: 1000.0,
            },
        ];
        let on_leg = foam.coverage(&turn, 18.0, 500.0, 1000.0, 200.0).unwrap();
        let on_first = foam.coverage(&turn, 18.0, 0.0, 500.0, 200.0).unwrap();
        assert!(on_leg > on_first && on_first > 0.0, "{on_leg} {on_first}");
        assert_eq!(
            foam.coverage(&turn, 18.0, 500.0, 500.0, 200.0).unwrap(),
            0.0
        );
        assert_eq!(foam.coverage(&[], 18.0, 0.0, 0.0, 0.0).unwrap(), 0.0);
    }

    #[test]
    fn bow_wave_rule() {
        // A destroyer (draft 5.5 m, 2α_E = 20°) at 30 kn: a few metres.
        let h = bow_wave_height_m(15.4, 5.5, 10.0).unwrap();
        assert!((1.0..5.0).contains(&h), "{h}");
        let slower = bow_wave_height_m(7.7, 5.5, 10.0).unwrap();
        assert!(slower < h);
        assert_eq!(bow_wave_height_m(0.0, 5.5, 10.0).unwrap(), 0.0);
        // Never above the stagnation head.
        let blunt = bow_wave_height_m(10.0, 10.0, 60.0).unwrap();
        assert!(blunt <= 100.0 / (2.0 * G_MPS2) + 1e-12);
        let lt = transverse_wavelength_m(10.0).unwrap();
        assert!((lt - 64.07).abs() < 0.01, "{lt}");
    }

    #[test]
    fn bad_input_is_refused() {
        assert!(kelvin_half_angle_deg(-1.0, 150.0).is_err());
        assert!(kelvin_half_angle_deg(10.0, 0.0).is_err());
        assert!(kelvin_half_angle_deg(f64::NAN, 150.0).is_err());
        assert!(hull_froude_number(50.0, 150.0).is_err());
        assert!(bow_wave_height_m(10.0, 0.0, 10.0).is_err());
        assert!(bow_wave_height_m(10.0, 5.0, 90.0).is_err());
        assert!(turbulent_wake_width_m(0.0, 10.0).is_err());
        assert!(turbulent_wake_width_m(10.0, -1.0).is_err());
        assert!(foam_generation(f64::INFINITY).is_err());
        assert!(FoamTrail::new(0.0).is_err());
        assert!(FoamTrail::DEFAULT.coverage_at_age(-1.0, 5.0).is_err());
        assert!(WakeShip::new(10.0, 20.0, 5.0).is_err());
        assert!(WakeShip::new(100.0, 10.0, -5.0).is_err());
        let ship = WakeShip::new(100.0, 10.0, 5.0).unwrap();
        assert!(wake_intensity(f64::NAN, 0.0, &ship, &FoamTrail::DEFAULT).is_err());
        let foam = FoamTrail::DEFAULT;
        let p = |t_s: f64| TrackPoint {
            t_s,
            x_east_m: 0.0,
            y_north_m: 0.0,
        };
        assert!(foam
            .coverage(&[p(1.0), p(1.0)], 10.0, 0.0, 0.0, 2.0)
            .is_err());
        assert!(foam.coverage(&[p(f64::NAN)], 10.0, 0.0, 0.0, 2.0).is_err());
        let bad = TrackPoint {
            y_north_m: f64::NAN,
            ..p(0.0)
        };
        assert!(foam.coverage(&[bad], 10.0, 0.0, 0.0, 2.0).is_err());
        assert!(foam.coverage(&[p(0.0)], 10.0, f64::NAN, 0.0, 2.0).is_err());
        assert!(foam
            .coverage(&[p(0.0)], 10.0, 0.0, 0.0, f64::INFINITY)
            .is_err());
    }
}
