//! The sea as a view draws it: the wave surface's cascade grids at the frame's time (from
//! `cig_sea::surface`), the plane they lie in, the sea level, the slope variance the grids do
//! not resolve and the water's colour. The renderer draws the sea from this and nothing else,
//! so what it draws is the surface the height queries sample.
//!
//! Limits: one sea per frame (no regional conditions), at one level (mean sea level plus the
//! host's sea surface height); explicit waves (CIGI Wave Control) are sampled by queries but not
//! yet drawn.

use cig_geo::Geodetic;
use cig_sea::motion::{HullParameters, ShipMotionModel, ShipPose};
use cig_sea::surface::{CascadeGrid, SeaSurface};

/// Cox and Munk's (1954) total mean square slope of a wind sea, `0.003 + 0.00512 U10`.
pub fn cox_munk_slope_variance(wind_speed_mps: f64) -> f64 {
    0.003 + 0.005_12 * wind_speed_mps.clamp(0.0, 60.0)
}

/// Least slope variance left to the shading where the grids resolve almost everything: the
/// capillary ripples no cascade carries.
const MIN_UNRESOLVED_SLOPE_VARIANCE: f64 = 0.000_5;

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
        }
    }
}

/// The hull a built-in model floats on: the `ship` model's 90 m frigate (12 m beam, 3 m
/// draft, 1.2 m metacentric height); other models do not float.
pub fn builtin_hull(model: &str) -> Option<HullParameters> {
    (model == "ship")
        .then(|| HullParameters::new(90.0, 12.0, 3.0, 1.2))
        .and_then(Result::ok)
}

/// Sets a floating entity on the sea at the surface's time: its waterline (the model's
/// origin) at the sea level under it (`geoid_m`: the geoid's height above the ellipsoid there)
/// plus the heave, pitched and rolled to the waves it spans, waves shorter than the hull
/// filtered out (`cig_sea::motion`'s wave-following equilibrium: no dynamics of its own).
///
/// # Errors
/// When the sea cannot be sampled there (a position thousands of kilometres from the origin).
pub fn ride_the_sea(
    entity: &mut crate::EntityInstance,
    hull: HullParameters,
    surface: &SeaSurface,
    sea: &SeaDraw,
    geoid_m: f64,
) -> Result<(), cig_sea::SeaError> {
    let plane = cig_geo::EnuFrame::new(sea.origin);
    let at = plane.geodetic_to_enu(entity.position);
    let pose = ShipPose {
        x_east_m: at.x,
        y_north_m: at.y,
        heading_deg: entity.orientation.heading_deg,
    };
    let motion = ShipMotionModel::new(hull).equilibrium(
        |x, y, _| surface.sample(x, y).height_m,
        pose,
        surface.time_s(),
    )?;
    entity.position.alt_m = geoid_m + sea.level_m + motion.heave_m;
    entity.orientation.pitch_deg = motion.pitch_deg;
    entity.orientation.roll_deg = motion.roll_deg;
    Ok(())
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
                ride_the_sea(&mut ship, hull, &surface, &sea, -30.0).expect("ride");
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
