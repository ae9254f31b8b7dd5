//! Buoyant plume rise: Briggs's equations in the form the EPA's ISC3 model uses.
//!
//! Algorithm (ISC3 user's guide, volume II, section 1.1.4, after Briggs 1969/1975; the thesis,
//! source 000 chapter III.A.1, takes its plume rise from Briggs):
//! - buoyancy flux `F = g v_s d^2 (T_s - T_a) / (4 T_s)` (m^4/s^3) from the stack exit velocity
//!   `v_s`, diameter `d`, exit temperature `T_s` and air temperature `T_a`; or, for an open fire,
//!   `F = g Q_h / (pi rho c_p T_a)` from the heat release `Q_h` (Briggs 1975);
//! - neutral or unstable air (classes A-D): final rise `21.425 F^(3/4) / u` reached at
//!   `x_f = 49 F^(5/8)` when `F < 55`, and `38.71 F^(3/5) / u` at `x_f = 119 F^(2/5)` when
//!   `F >= 55`;
//! - stable air (E, F): final rise `2.6 (F / (u s))^(1/3)` with the stability parameter
//!   `s = (g / T_a) d(theta)/dz`, reached at `x_f = 2.0715 u / sqrt(s)`;
//! - before `x_f`, the transitional rise `1.6 F^(1/3) x^(2/3) / u`, never above the final rise.
//!
//! The constants make the transitional rise meet the final rise at `x_f` to within their
//! rounding (1.6 * 49^(2/3) = 21.4248, 1.6 * 119^(2/3) = 38.7094, 1.6 * 2.0715^(2/3) = 2.6006).
//! `g` is ISC3's 9.80616 m/s^2.
//!
//! Limits: buoyancy-dominated rise only (ISC3's momentum rise, stack-tip downwash and building
//! downwash are not modelled); a source no warmer than the air has `F = 0` and no rise. The fits
//! were made for hot windy plumes (the thesis: exit velocities of 6-30 m/s, 120-260 C); `u` is
//! the wind at source height, and the particle system floors it at 1 m/s as ISC3 does.

use crate::dispersion::StabilityClass;
use crate::error::{non_negative, positive, EffectsError};

/// Acceleration of gravity used by ISC3, m/s^2.
pub const GRAVITY_MPS2: f64 = 9.80616;
/// Air density for the heat-release form of the buoyancy flux, kg/m^3.
pub const AIR_DENSITY_KG_M3: f64 = 1.2;
/// Specific heat of air at constant pressure, J/(kg K).
pub const AIR_CP_J_KG_K: f64 = 1005.0;
/// The wind speed floor the particle system applies before using these formulas, m/s.
pub const MIN_WIND_MPS: f64 = 1.0;

/// Stack exit conditions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stack {
    /// Exit velocity of the gas, m/s.
    pub exit_velocity_mps: f64,
    /// Inside diameter at the exit, m.
    pub diameter_m: f64,
    /// Exit gas temperature, K.
    pub exit_temperature_k: f64,
    /// Ambient air temperature, K.
    pub air_temperature_k: f64,
}

/// Buoyancy flux of a stack, m^4/s^3 (0 when the gas is no warmer than the air).
pub fn buoyancy_flux_m4_s3(stack: &Stack) -> Result<f64, EffectsError> {
    let v = non_negative("stack exit velocity (m/s)", stack.exit_velocity_mps)?;
    let d = non_negative("stack diameter (m)", stack.diameter_m)?;
    let ts = positive("stack exit temperature (K)", stack.exit_temperature_k)?;
    let ta = positive("air temperature (K)", stack.air_temperature_k)?;
    Ok((GRAVITY_MPS2 * v * d * d * (ts - ta) / (4.0 * ts)).max(0.0))
}

/// Buoyancy flux of an open fire from its convective heat release, m^4/s^3.
pub fn buoyancy_flux_from_heat_release(
    heat_release_w: f64,
    air_temperature_k: f64,
) -> Result<f64, EffectsError> {
    let q = non_negative("heat release (W)", heat_release_w)?;
    let ta = positive("air temperature (K)", air_temperature_k)?;
    Ok(GRAVITY_MPS2 * q / (std::f64::consts::PI * AIR_DENSITY_KG_M3 * AIR_CP_J_KG_K * ta))
}

/// Stability parameter `s = (g / T_a) d(theta)/dz`, 1/s^2.
pub fn stability_parameter_per_s2(
    dtheta_dz_k_per_m: f64,
    air_temperature_k: f64,
) -> Result<f64, EffectsError> {
    let gradient = positive("potential temperature gradient (K/m)", dtheta_dz_k_per_m)?;
    let ta = positive("air temperature (K)", air_temperature_k)?;
    Ok(GRAVITY_MPS2 / ta * gradient)
}

/// Air stratification for plume rise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stratification {
    /// Classes A-D.
    NeutralOrUnstable,
    /// Classes E-F with stability parameter `s` (1/s^2).
    Stable { s_per_s2: f64 },
}

impl Stratification {
    /// The stratification of a class: E and F use `dtheta_dz_k_per_m` when given, else ISC3's
    /// default gradient for the class.
    pub fn for_class(
        class: StabilityClass,
        dtheta_dz_k_per_m: Option<f64>,
        air_temperature_k: f64,
    ) -> Result<Stratification, EffectsError> {
        if !class.is_stable() {
            return Ok(Stratification::NeutralOrUnstable);
        }
        let gradient = dtheta_dz_k_per_m.unwrap_or(class.default_dtheta_dz_k_per_m());
        Ok(Stratification::Stable {
            s_per_s2: stability_parameter_per_s2(gradient, air_temperature_k)?,
        })
    }
}

/// Plume rise of one source in one wind: the final rise, where it is reached, and the curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlumeRise {
    /// Final rise above the source, m.
    pub final_rise_m: f64,
    /// Downwind distance at which the final rise is reached, m.
    pub final_rise_x_m: f64,
    /// `1.6 F^(1/3) / u`: the transitional rise is this times `x^(2/3)`.
    pub transitional_coefficient: f64,
}

impl PlumeRise {
    /// Briggs/ISC3 rise for buoyancy flux `F` (m^4/s^3) in wind `u` (m/s, > 0).
    pub fn new(
        buoyancy_flux_m4_s3: f64,
        wind_speed_mps: f64,
        stratification: Stratification,
    ) -> Result<PlumeRise, EffectsError> {
        let f = non_negative("buoyancy flux (m^4/s^3)", buoyancy_flux_m4_s3)?;
        let u = positive("wind speed (m/s)", wind_speed_mps)?;
        let (final_rise_m, final_rise_x_m) = match stratification {
            Stratification::NeutralOrUnstable => {
                if f < 55.0 {
                    (21.425 * libm::pow(f, 0.75) / u, 49.0 * libm::pow(f, 0.625))
                } else {
                    (38.71 * libm::pow(f, 0.6) / u, 119.0 * libm::pow(f, 0.4))
                }
            }
            Stratification::Stable { s_per_s2 } => {
                let s = positive("stability parameter (1/s^2)", s_per_s2)?;
                (2.6 * libm::cbrt(f / (u * s)), 2.0715 * u / libm::sqrt(s))
            }
        };
        Ok(PlumeRise {
            final_rise_m,
            final_rise_x_m,
            transitional_coefficient: 1.6 * libm::cbrt(f) / u,
        })
    }

    /// The transitional rise `1.6 F^(1/3) x^(2/3) / u` at `x_m` (no cap).
    pub fn transitional_rise_m(&self, x_m: f64) -> f64 {
        let c = libm::cbrt(x_m.max(0.0));
        self.transitional_coefficient * c * c
    }

    /// Rise at downwind distance `x_m`: transitional before `x_f` (never above the final rise),
    /// final from `x_f` on. Negative distances give 0.
    pub fn rise_m(&self, x_m: f64) -> f64 {
        if x_m >= self.final_rise_x_m {
            self.final_rise_m
        } else {
            self.transitional_rise_m(x_m).min(self.final_rise_m)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn neutral(f: f64, u: f64) -> PlumeRise {
        PlumeRise::new(f, u, Stratification::NeutralOrUnstable).unwrap()
    }

    #[test]
    fn transitional_rise_meets_final_rise_at_xf_on_both_branches_and_in_stable_air() {
        let stable = Stratification::for_class(StabilityClass::F, None, 293.0).unwrap();
        for (f, strat) in [
            (10.0, Stratification::NeutralOrUnstable),
            (54.9, Stratification::NeutralOrUnstable),
            (55.0, Stratification::NeutralOrUnstable),
            (400.0, Stratification::NeutralOrUnstable),
            (10.0, stable),
            (400.0, stable),
        ] {
            let r = PlumeRise::new(f, 4.0, strat).unwrap();
            let t = r.transitional_rise_m(r.final_rise_x_m);
            assert!(
                (t - r.final_rise_m).abs() <= 3e-4 * r.final_rise_m,
                "F {f}: transitional {t} vs final {}",
                r.final_rise_m
            );
        }
    }

    #[test]
    fn branch_values_by_hand() {
        // F = 16: 21.425 * 16^0.75 / 5 = 21.425 * 8 / 5; x_f = 49 * 16^0.625 = 49 * 5.6569.
        let r = neutral(16.0, 5.0);
        assert!((r.final_rise_m - 34.28).abs() < 1e-9);
        assert!((r.final_rise_x_m - 49.0 * 2f64.powf(2.5)).abs() < 1e-9);
        // F = 243 (3^5): 38.71 * 3^3 / 2; x_f = 119 * 3^2.
        let r = neutral(243.0, 2.0);
        assert!((r.final_rise_m - 38.71 * 27.0 / 2.0).abs() < 1e-9);
        assert!((r.final_rise_x_m - 119.0 * 9.0).abs() < 1e-9);
        // Stable: s = 9.80616 / 300 * 0.035; F = 100, u = 3.
        let s = 9.80616 / 300.0 * 0.035;
        let strat = Stratification::for_class(StabilityClass::F, None, 300.0).unwrap();
        assert_eq!(strat, Stratification::Stable { s_per_s2: s });
        let r = PlumeRise::new(100.0, 3.0, strat).unwrap();
        assert!((r.final_rise_m - 2.6 * (100.0 / (3.0 * s)).cbrt()).abs() < 1e-9);
        assert!((r.final_rise_x_m - 2.0715 * 3.0 / s.sqrt()).abs() < 1e-9);
        // Transitional at half of x_f is (1/2)^(2/3) of the final rise, to the constants' rounding.
        let r = neutral(16.0, 5.0);
        let half = r.rise_m(0.5 * r.final_rise_x_m);
        assert!((half / r.final_rise_m - 0.5f64.powf(2.0 / 3.0)).abs() < 1e-4);
    }

    #[test]
    fn buoyancy_flux_of_a_stack_and_a_fire() {
        let stack = Stack {
            exit_velocity_mps: 10.0,
            diameter_m: 2.0,
            exit_temperature_k: 400.0,
            air_temperature_k: 300.0,
        };
        let f = buoyancy_flux_m4_s3(&stack).unwrap();
        assert!((f - 9.80616 * 10.0 * 4.0 * 100.0 / 1600.0).abs() < 1e-12);
        let cold = Stack {
            exit_temperature_k: 280.0,
            ..stack
        };
        assert_eq!(buoyancy_flux_m4_s3(&cold).unwrap(), 0.0);
        // 1 MW fire: about 8.9 m^4/s^3 (Briggs's 8.8e-6 per watt at 293 K).
        let f = buoyancy_flux_from_heat_release(1.0e6, 293.0).unwrap();
        assert!((f - 8.85).abs() < 0.05, "{f}");
        for bad in [
            Stack {
                diameter_m: -1.0,
                ..stack
            },
            Stack {
                exit_velocity_mps: f64::NAN,
                ..stack
            },
            Stack {
                exit_temperature_k: 0.0,
                ..stack
            },
            Stack {
                air_temperature_k: f64::INFINITY,
                ..stack
            },
        ] {
            assert!(buoyancy_flux_m4_s3(&bad).is_err());
        }
        assert!(PlumeRise::new(10.0, 0.0, Stratification::NeutralOrUnstable).is_err());
        assert!(PlumeRise::new(-1.0, 1.0, Stratification::NeutralOrUnstable).is_err());
        assert!(Stratification::for_class(StabilityClass::E, Some(-0.01), 290.0).is_err());
    }

    proptest! {
        #[test]
        fn rise_is_monotone_in_distance_and_flat_after_xf(
            f in 0.0f64..2000.0, u in 0.5f64..30.0, x in 0.0f64..20_000.0, dx in 0.0f64..5_000.0,
            class_index in 0usize..6, gradient in 0.001f64..0.1,
        ) {
            let class = StabilityClass::ALL[class_index];
            let strat = Stratification::for_class(class, Some(gradient), 290.0).unwrap();
            let r = PlumeRise::new(f, u, strat).unwrap();
            prop_assert!(r.rise_m(x + dx) >= r.rise_m(x));
            prop_assert!(r.rise_m(x) <= r.final_rise_m);
            prop_assert_eq!(r.rise_m(r.final_rise_x_m + x), r.final_rise_m);
        }

        #[test]
        fn more_buoyancy_rises_higher_and_more_wind_lower(f in 0.1f64..2000.0, u in 0.5f64..30.0) {
            let a = PlumeRise::new(f, u, Stratification::NeutralOrUnstable).unwrap();
            let b = PlumeRise::new(f * 1.5, u, Stratification::NeutralOrUnstable).unwrap();
            let c = PlumeRise::new(f, u * 1.5, Stratification::NeutralOrUnstable).unwrap();
            prop_assert!(b.final_rise_m > a.final_rise_m);
            prop_assert!(c.final_rise_m < a.final_rise_m);
        }
    }
}
