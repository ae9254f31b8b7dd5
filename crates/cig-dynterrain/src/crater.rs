//! Craters: cube-root scaling of surface-burst craters.
//!
//! # Algorithm
//!
//! Hopkinson–Cranz (cube-root) scaling: geometrically similar explosions scale with the cube
//! root of the charge, so a surface burst of `W` kg of TNT-equivalent leaves an apparent crater
//! of radius `R = C_R W^(1/3)` and depth `D = C_D W^(1/3)` measured at and below the original
//! ground level; its lip (the rim of thrown-out soil) reaches out to `1.25 R` and stands
//! `0.25 D` high, and the ejecta blanket reaches about `2.15 R` ([`CraterDimensions`]).
//!
//! # Table
//!
//! Coefficients `C_R` / `C_D`, in m/kg^(1/3), as compiled in the project's reference notes
//! (`dynamic_terrain.md`, from the `lErrorl404l/AEE` crater tables and their tests; 10–30 %
//! scatter between shots):
//!
//! | constant | C_R | C_D |
//! |---|---|---|
//! | [`SOIL`] (generic soil) | 0.40 | 0.20 |
//! | [`DRY_SANDY_CLAY`] | 0.389 | 0.218 |
//! | [`DRY_SAND`] | 0.297 | 0.149 |
//! | [`WET_CLAY`] | 0.456 | 0.228 |
//! | [`CONCRETE`] | 0.151 | 0.079 |
//!
//! Materials map to rows as follows ([`coefficients`]):
//!
//! | material | dry | wet |
//! |---|---|---|
//! | sand | dry sand | soil |
//! | dry clay | dry sandy clay | wet clay |
//! | grass, forest, dirt road | soil | wet clay |
//! | snow | soil | soil |
//! | paved road | concrete | concrete |
//! | rock | concrete | concrete |
//! | water | — (no crater) | — |
//!
//! Choices made here, not by a source: the table has no wet-sand row; moisture enlarges
//! craters in granular soil (saturated soils crater the most), so wet sand takes the generic
//! soil row, between dry sand and wet clay. The table has no rock row either: sound rock
//! craters at most like concrete, so rock uses the concrete row as an upper bound. Snow cover
//! is blown clear and the crater is the ground's beneath it, taken as generic soil.
//!
//! The generic-soil row reproduces the reference's surface-burst sanity figures exactly when
//! fed each munition's effective charge ([`crate::munitions`]): 1 kg gives 0.8 m across and
//! 0.20 m deep (81 mm mortar), 7 kg 1.53 m / 0.38 m (155 mm), 100 kg 3.7 m / 0.93 m (500 lb
//! bomb), 450 kg 6.1 m / 1.5 m (2000 lb bomb).
//!
//! # Limits
//!
//! - Surface (impact-fuzed) bursts only. Buried (delay-fuzed) bursts crater far more (a 2000 lb
//!   bomb about 15 m across and over 4.5 m deep); the munition table folds that into a larger
//!   effective charge rather than a depth-of-burst law. Air bursts leave no crater.
//! - One charge, one crater: no overlap with earlier craters, no layered ground, no slope.
//! - Charges up to [`MAX_CHARGE_KG`] (20 t); nuclear yields follow another law and are refused.

use cig_terrain::Material;

use crate::soil::SoilMoisture;

/// Cube-root scaling coefficients, m/kg^(1/3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CraterCoefficients {
    /// Apparent crater radius per cube root of the charge, m/kg^(1/3).
    pub c_r: f64,
    /// Apparent crater depth per cube root of the charge, m/kg^(1/3).
    pub c_d: f64,
}

/// Generic soil.
pub const SOIL: CraterCoefficients = CraterCoefficients {
    c_r: 0.40,
    c_d: 0.20,
};

/// Dry sandy clay.
pub const DRY_SANDY_CLAY: CraterCoefficients = CraterCoefficients {
    c_r: 0.389,
    c_d: 0.218,
};

/// Dry sand.
pub const DRY_SAND: CraterCoefficients = CraterCoefficients {
    c_r: 0.297,
    c_d: 0.149,
};

/// Wet clay.
pub const WET_CLAY: CraterCoefficients = CraterCoefficients {
    c_r: 0.456,
    c_d: 0.228,
};

/// Concrete (also paved road, and rock as an upper bound).
pub const CONCRETE: CraterCoefficients = CraterCoefficients {
    c_r: 0.151,
    c_d: 0.079,
};

/// Lip (rim) outer radius over crater radius.
pub const LIP_RADIUS_RATIO: f64 = 1.25;

/// Lip height over crater depth.
pub const LIP_HEIGHT_RATIO: f64 = 0.25;

/// Ejecta blanket radius over crater radius.
pub const EJECTA_RADIUS_RATIO: f64 = 2.15;

/// Largest charge accepted, kg of TNT: 20 t, above the heaviest conventional bombs (GBU-43/B,
/// about 8.5 t of H6) with room for a delay-fuzed effective charge.
pub const MAX_CHARGE_KG: f64 = 20_000.0;

/// Why a crater call refused its input: one line naming the value and the reason.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CraterError {
    /// A value outside its range, or not finite.
    #[error("{name} must be {range}, not {value}")]
    OutOfRange {
        /// The parameter's name, with its unit.
        name: &'static str,
        /// The accepted range, in words.
        range: &'static str,
        /// The value refused.
        value: f64,
    },
}

/// The size of one crater, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CraterDimensions {
    /// Apparent radius, at the original ground level, m.
    pub radius_m: f64,
    /// Apparent depth below the original ground level, m.
    pub depth_m: f64,
    /// Outer radius of the lip, m.
    pub lip_radius_m: f64,
    /// Height of the lip's crest above the original ground level, m.
    pub lip_height_m: f64,
}

impl CraterDimensions {
    /// Apparent diameter, m.
    pub fn diameter_m(&self) -> f64 {
        2.0 * self.radius_m
    }

    /// Radius reached by the ejecta blanket, m.
    pub fn ejecta_radius_m(&self) -> f64 {
        EJECTA_RADIUS_RATIO * self.radius_m
    }

    /// Height of the deformed ground relative to the original level at `distance_m` from the
    /// centre, m (negative in the bowl). An assumed shape, not a measured one: a paraboloid
    /// bowl `-D (1 - (r/R)^2)` out to `R`, then a half-sine lip `H sin(pi (r - R) / (L - R))`
    /// peaking halfway between `R` and the lip radius `L`, then untouched ground. NaN is 0.
    pub fn height_offset_m(&self, distance_m: f64) -> f64 {
        let r_m = distance_m.abs();
        if r_m.is_nan() || self.radius_m <= 0.0 {
            0.0
        } else if r_m <= self.radius_m {
            let x = r_m / self.radius_m;
            -self.depth_m * (1.0 - x * x)
        } else if r_m < self.lip_radius_m {
            let t = (r_m - self.radius_m) / (self.lip_radius_m - self.radius_m);
            self.lip_height_m * (std::f64::consts::PI * t).sin()
        } else {
            0.0
        }
    }
}

/// Scaling coefficients of `material` in the given moisture (module table); `None` for water.
pub fn coefficients(material: Material, moisture: SoilMoisture) -> Option<CraterCoefficients> {
    use SoilMoisture::{Dry, Wet};
    match (material, moisture) {
        (Material::Water, _) => None,
        (Material::Sand, Dry) => Some(DRY_SAND),
        (Material::Sand, Wet) | (Material::Snow, _) => Some(SOIL),
        (Material::DryClay, Dry) => Some(DRY_SANDY_CLAY),
        (Material::Grass | Material::Forest | Material::DirtRoad, Dry) => Some(SOIL),
        (Material::DryClay | Material::Grass | Material::Forest | Material::DirtRoad, Wet) => {
            Some(WET_CLAY)
        }
        (Material::PavedRoad | Material::Rock, _) => Some(CONCRETE),
    }
}

/// The crater a surface burst of `charge_kg` of TNT-equivalent leaves in `material`.
///
/// `Ok(None)` on water and for a zero charge; an error for a negative, NaN or infinite charge
/// or one above [`MAX_CHARGE_KG`].
pub fn dimensions(
    material: Material,
    moisture: SoilMoisture,
    charge_kg: f64,
) -> Result<Option<CraterDimensions>, CraterError> {
    if !(charge_kg.is_finite() && (0.0..=MAX_CHARGE_KG).contains(&charge_kg)) {
        return Err(CraterError::OutOfRange {
            name: "charge_kg",
            range: "finite, from 0 to 20000 kg of TNT",
            value: charge_kg,
        });
    }
    if charge_kg == 0.0 {
        return Ok(None);
    }
    Ok(coefficients(material, moisture).map(|c| {
        let scale = charge_kg.cbrt();
        let radius_m = c.c_r * scale;
        let depth_m = c.c_d * scale;
        CraterDimensions {
            radius_m,
            depth_m,
            lip_radius_m: LIP_RADIUS_RATIO * radius_m,
            lip_height_m: LIP_HEIGHT_RATIO * depth_m,
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(actual: f64, expected: f64, rel: f64) -> bool {
        (actual - expected).abs() <= rel * expected.abs()
    }

    fn crater(material: Material, moisture: SoilMoisture, charge_kg: f64) -> CraterDimensions {
        dimensions(material, moisture, charge_kg).unwrap().unwrap()
    }

    #[test]
    fn dimensions_follow_the_scaling_law() {
        // Coefficients written out from the reference table, not read from the constants.
        let cases = [
            (Material::Sand, SoilMoisture::Dry, 0.297, 0.149),
            (Material::DryClay, SoilMoisture::Dry, 0.389, 0.218),
            (Material::DryClay, SoilMoisture::Wet, 0.456, 0.228),
            (Material::PavedRoad, SoilMoisture::Dry, 0.151, 0.079),
        ];
        for (material, moisture, c_r, c_d) in cases {
            for (charge_kg, cube_root) in [(1.0, 1.0), (7.0, 1.912_931_2), (100.0, 4.641_588_8)] {
                let c = crater(material, moisture, charge_kg);
                assert!(close(c.radius_m, c_r * cube_root, 1e-7), "{material} {c:?}");
                assert!(close(c.depth_m, c_d * cube_root, 1e-7), "{material} {c:?}");
                assert!(close(c.lip_radius_m, 1.25 * c_r * cube_root, 1e-7));
                assert!(close(c.lip_height_m, 0.25 * c_d * cube_root, 1e-7));
            }
        }
        // Eight times the charge, twice the size.
        let one = crater(Material::Grass, SoilMoisture::Dry, 12.5);
        let eight = crater(Material::Grass, SoilMoisture::Dry, 100.0);
        assert!(close(eight.radius_m, 2.0 * one.radius_m, 1e-12));
        assert!(close(eight.depth_m, 2.0 * one.depth_m, 1e-12));
    }

    #[test]
    fn generic_soil_reproduces_the_reference_surface_bursts() {
        // (charge kg, diameter m, depth m) from the reference notes.
        for (charge_kg, diameter_m, depth_m) in [
            (1.0, 0.8, 0.20),
            (7.0, 1.53, 0.38),
            (100.0, 3.7, 0.93),
            (450.0, 6.1, 1.5),
        ] {
            let c = crater(Material::Grass, SoilMoisture::Dry, charge_kg);
            assert!(
                close(c.diameter_m(), diameter_m, 0.02),
                "{charge_kg}: {c:?}"
            );
            assert!(close(c.depth_m, depth_m, 0.03), "{charge_kg}: {c:?}");
        }
    }

    #[test]
    fn hard_ground_craters_less_than_sand_or_clay() {
        for charge_kg in [1.0, 7.0, 100.0, 450.0] {
            for moisture in [SoilMoisture::Dry, SoilMoisture::Wet] {
                for hard in [Material::Rock, Material::PavedRoad] {
                    let h = crater(hard, moisture, charge_kg);
                    for soft in [Material::Sand, Material::DryClay, Material::Grass] {
                        let s = crater(soft, moisture, charge_kg);
                        assert!(h.radius_m < s.radius_m, "{hard} vs {soft}");
                        assert!(h.depth_m < s.depth_m, "{hard} vs {soft}");
                    }
                }
            }
        }
        // Wet clay craters more than dry sandy clay.
        assert!(
            crater(Material::DryClay, SoilMoisture::Wet, 7.0).radius_m
                > crater(Material::DryClay, SoilMoisture::Dry, 7.0).radius_m
        );
    }

    #[test]
    fn water_and_zero_charges_leave_no_crater() {
        assert_eq!(coefficients(Material::Water, SoilMoisture::Dry), None);
        assert_eq!(
            dimensions(Material::Water, SoilMoisture::Dry, 100.0),
            Ok(None)
        );
        assert_eq!(
            dimensions(Material::Water, SoilMoisture::Wet, 1.0),
            Ok(None)
        );
        assert_eq!(dimensions(Material::Sand, SoilMoisture::Dry, 0.0), Ok(None));
        for material in Material::ALL {
            let has = coefficients(material, SoilMoisture::Dry).is_some();
            assert_eq!(has, material != Material::Water, "{material}");
        }
    }

    #[test]
    fn bad_charges_are_refused_with_a_one_line_message() {
        for bad in [
            -1.0,
            -1e-9,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            20_000.5,
            1e12,
        ] {
            let err = dimensions(Material::Sand, SoilMoisture::Dry, bad).unwrap_err();
            let text = err.to_string();
            assert!(text.starts_with("charge_kg must be finite"), "{text}");
            assert!(!text.contains('\n'));
        }
        assert_eq!(
            dimensions(Material::Sand, SoilMoisture::Dry, -3.0)
                .unwrap_err()
                .to_string(),
            "charge_kg must be finite, from 0 to 20000 kg of TNT, not -3"
        );
        // The limit itself is accepted, and water still refuses a bad charge.
        assert!(dimensions(Material::Sand, SoilMoisture::Dry, MAX_CHARGE_KG).is_ok());
        assert!(dimensions(Material::Water, SoilMoisture::Dry, f64::NAN).is_err());
    }

    #[test]
    fn profile_is_a_bowl_with_a_lip() {
        let c = crater(Material::Grass, SoilMoisture::Dry, 100.0);
        assert!(close(c.height_offset_m(0.0), -c.depth_m, 1e-12));
        assert!(c.height_offset_m(c.radius_m).abs() < 1e-12);
        let crest_m = 0.5 * (c.radius_m + c.lip_radius_m);
        assert!(close(c.height_offset_m(crest_m), c.lip_height_m, 1e-12));
        assert!(close(c.height_offset_m(-crest_m), c.lip_height_m, 1e-12));
        assert_eq!(c.height_offset_m(c.lip_radius_m), 0.0);
        assert_eq!(c.height_offset_m(10.0 * c.radius_m), 0.0);
        assert_eq!(c.height_offset_m(f64::NAN), 0.0);
        // Deepest at the centre, monotone up to the rim.
        let mut last = c.height_offset_m(0.0);
        for i in 1..=100 {
            let h = c.height_offset_m(c.radius_m * f64::from(i) / 100.0);
            assert!(h >= last);
            last = h;
        }
        assert!(close(c.ejecta_radius_m(), 2.15 * c.radius_m, 1e-12));
    }

    proptest! {
        #[test]
        fn never_panics_on_any_charge(charge in proptest::num::f64::ANY) {
            for material in Material::ALL {
                for moisture in [SoilMoisture::Dry, SoilMoisture::Wet] {
                    match dimensions(material, moisture, charge) {
                        Ok(Some(c)) => {
                            prop_assert!(charge > 0.0 && charge <= MAX_CHARGE_KG);
                            prop_assert!(c.radius_m.is_finite() && c.radius_m > 0.0);
                            prop_assert!(c.depth_m.is_finite() && c.depth_m > 0.0);
                            prop_assert!(c.lip_radius_m > c.radius_m);
                        }
                        Ok(None) => prop_assert!(material == Material::Water || charge == 0.0),
                        Err(_) => prop_assert!(
                            !(0.0..=MAX_CHARGE_KG).contains(&charge)
                        ),
                    }
                }
            }
        }
    }
}
