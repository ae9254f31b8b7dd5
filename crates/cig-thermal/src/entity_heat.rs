//! Heat of entities: engines, exhausts, running gear and crews as hot parts of models, warming
//! and cooling with first-order time constants; burning and destroyed vehicles; fresh craters
//! and impact points.
//!
//! Algorithm: each hot part's temperature rise above its surroundings (the skin temperature the
//! surface table gives the part's material) relaxes toward a target rise with a first-order
//! time constant, `dT/dt = (target - T) / tau`, the constant for warming while the target is
//! above the part and for cooling while it is below (an engine deck warms in minutes and cools
//! over half an hour). Targets follow the engine state (running or not), the speed (running
//! gear heats with work done against rolling resistance), and damage (a burning vehicle's hull
//! and flames; a destroyed one cooling). Point heat (craters, impacts, flares) decays from its
//! start temperature by a constant of its own. Stepped exactly for any step length
//! (`1 - exp(-dt / tau)`), so a frame or a jump of the clock gives the same state.
//!
//! Sources of the temperatures and time constants: R. G. Driggers et al., *Introduction to
//! Infrared and Electro-Optical Systems*, 2nd ed., Artech 2012, ch. 3 (targets: tank engine
//! compartment and exhaust, tracks and road wheels after movement, personnel); P. A. Jacobs,
//! *Thermal Infrared Characterization of Ground Targets and Backgrounds*, 2nd ed., SPIE 2006,
//! ch. 7 (vehicle signatures: exhaust 300-500 C, engine deck grilles 60-100 C, running gear
//! 20-40 K over ambient after a road march, cooling over tens of minutes; burning vehicles).
//! The numbers are typical values for the built-in models, documented here and overridable per
//! part.
//!
//! Limits: no conduction between parts or into the hull plates beyond the part's own rise; the
//! sun's loading on a part comes from the surface table of the part's material, not from its
//! own state; flames are a temperature, not a flickering shape (the obscurant plume draws them).

/// A hot part of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HotPart {
    /// Engine compartment deck and grilles.
    EngineDeck,
    /// Exhaust outlets and the hot gas just behind them.
    Exhaust,
    /// Tracks, road wheels, tyres, bearings.
    RunningGear,
    /// A crew member's exposed head and hands, or a dismount.
    Crew,
    /// Hull and turret when burning (every non-part surface of a burning entity).
    BurningHull,
}

impl HotPart {
    /// Every part, in order (the vertex codes are this order, see [`HotPart::code`]).
    pub const ALL: [HotPart; 5] = [
        HotPart::EngineDeck,
        HotPart::Exhaust,
        HotPart::RunningGear,
        HotPart::Crew,
        HotPart::BurningHull,
    ];

    /// The name on glTF nodes and materials (`cig_hot=engine_deck`, see `docs/models.md`).
    pub fn name(self) -> &'static str {
        match self {
            HotPart::EngineDeck => "engine_deck",
            HotPart::Exhaust => "exhaust",
            HotPart::RunningGear => "running_gear",
            HotPart::Crew => "crew",
            HotPart::BurningHull => "burning_hull",
        }
    }

    /// Parses a name of [`HotPart::name`].
    pub fn from_name(name: &str) -> Option<HotPart> {
        HotPart::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Index in [`HotPart::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The part's parameters.
    pub fn params(self) -> PartParams {
        match self {
            HotPart::EngineDeck => PartParams {
                running_rise_k: 55.0,
                per_speed_rise_k_per_mps: 1.0,
                warm_tau_s: 480.0,
                cool_tau_s: 2400.0,
            },
            HotPart::Exhaust => PartParams {
                running_rise_k: 280.0,
                per_speed_rise_k_per_mps: 4.0,
                warm_tau_s: 40.0,
                cool_tau_s: 600.0,
            },
            HotPart::RunningGear => PartParams {
                running_rise_k: 3.0,
                per_speed_rise_k_per_mps: 3.0,
                warm_tau_s: 600.0,
                cool_tau_s: 1500.0,
            },
            HotPart::Crew => PartParams {
                running_rise_k: 0.0,
                per_speed_rise_k_per_mps: 0.0,
                warm_tau_s: 60.0,
                cool_tau_s: 60.0,
            },
            HotPart::BurningHull => PartParams {
                running_rise_k: 0.0,
                per_speed_rise_k_per_mps: 0.0,
                warm_tau_s: 120.0,
                cool_tau_s: 3600.0,
            },
        }
    }
}

/// How a part heats.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartParams {
    /// Rise over the surroundings with the engine running at rest, K.
    pub running_rise_k: f64,
    /// Extra rise per m/s of speed, K (work against rolling resistance and engine load).
    pub per_speed_rise_k_per_mps: f64,
    /// Warming time constant, s.
    pub warm_tau_s: f64,
    /// Cooling time constant, s.
    pub cool_tau_s: f64,
}

/// Skin temperature of a crew member's exposed face, kelvin (about 34 C).
pub const CREW_SKIN_K: f64 = 307.0;
/// Hull temperature of a burning vehicle, kelvin (about 450 C on the hull, Jacobs ch. 7).
pub const BURNING_HULL_K: f64 = 723.0;
/// Flame temperature seen through the smoke (a sooty hydrocarbon flame), kelvin.
pub const FLAME_K: f64 = 1100.0;

/// What an entity is doing, as far as its heat goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntityThermalInput {
    /// Engine (power plant) running.
    pub engine_on: bool,
    /// Ground speed, m/s.
    pub speed_mps: f64,
    /// Burning now.
    pub burning: bool,
    /// Destroyed (hot after burning or an explosion, cooling).
    pub destroyed: bool,
}

/// One entity's hot parts: the rise of each part over its surroundings, K.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct EntityHeat {
    /// Rise over the surroundings per [`HotPart::ALL`], K (crew: absolute skin temperature is
    /// used instead; see [`EntityHeat::part_temperature_k`]).
    pub rise_k: [f64; 5],
}

impl EntityHeat {
    /// An entity whose engine has been running (or off) long enough to be steady.
    pub fn steady(input: &EntityThermalInput, ambient_k: f64) -> EntityHeat {
        let mut h = EntityHeat::default();
        for part in HotPart::ALL {
            h.rise_k[part.index()] = target_rise_k(part, input, ambient_k);
        }
        h
    }

    /// Advances the parts by `dt_s` under `input` (exact for the step).
    pub fn step(&mut self, dt_s: f64, input: &EntityThermalInput, ambient_k: f64) {
        if dt_s.is_nan() || dt_s <= 0.0 {
            return;
        }
        for part in HotPart::ALL {
            let target = target_rise_k(part, input, ambient_k);
            let now = &mut self.rise_k[part.index()];
            let p = part.params();
            let tau = if target > *now {
                p.warm_tau_s
            } else {
                p.cool_tau_s
            };
            *now = target + (*now - target) * (-dt_s / tau).exp();
        }
    }

    /// The temperature of `part` when its surroundings (the part's material in the surface
    /// table) are at `surface_k`, kelvin.
    pub fn part_temperature_k(&self, part: HotPart, surface_k: f64) -> f64 {
        surface_k + self.rise_k[part.index()]
    }
}

fn target_rise_k(part: HotPart, input: &EntityThermalInput, ambient_k: f64) -> f64 {
    let p = part.params();
    match part {
        HotPart::Crew => CREW_SKIN_K - ambient_k,
        HotPart::BurningHull => {
            if input.burning {
                BURNING_HULL_K - ambient_k
            } else {
                0.0
            }
        }
        _ => {
            let speed = input.speed_mps.clamp(0.0, 40.0);
            let running = if input.engine_on && !input.destroyed {
                p.running_rise_k + p.per_speed_rise_k_per_mps * speed
            } else {
                0.0
            };
            if input.burning {
                running.max(BURNING_HULL_K - ambient_k)
            } else {
                running
            }
        }
    }
}

/// A hot point on the ground or a surface: a fresh crater, an impact, a flare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HotSpot {
    /// Temperature rise at the start, K.
    pub initial_rise_k: f64,
    /// Decay time constant, s.
    pub tau_s: f64,
    /// Radius, m.
    pub radius_m: f64,
}

impl HotSpot {
    /// A fresh crater of an artillery round: 300 K over the ground, decaying over ten minutes
    /// (Jacobs ch. 7: disturbed soil stays warm for an hour, the hot core for minutes).
    pub fn crater(radius_m: f64) -> HotSpot {
        HotSpot {
            initial_rise_k: 300.0,
            tau_s: 600.0,
            radius_m,
        }
    }

    /// The disturbed, fractured soil of a crater's bowl and lip out to `1.25 radius_m`:
    /// 10 K over the ground, decaying over an hour (Jacobs ch. 7: disturbed soil stays warm
    /// for an hour; the freshly turned earth is also drier and darker).
    pub fn disturbed_soil(radius_m: f64) -> HotSpot {
        HotSpot {
            initial_rise_k: 10.0,
            tau_s: 3600.0,
            radius_m: 1.25 * radius_m,
        }
    }

    /// A small-arms or fragment impact point: 150 K, decaying within seconds.
    pub fn impact() -> HotSpot {
        HotSpot {
            initial_rise_k: 150.0,
            tau_s: 5.0,
            radius_m: 0.3,
        }
    }

    /// Rise over the ground `age_s` seconds after the event, K.
    pub fn rise_k(&self, age_s: f64) -> f64 {
        if age_s < 0.0 {
            return 0.0;
        }
        self.initial_rise_k * (-age_s / self.tau_s).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AMBIENT: f64 = 288.0;

    fn running(speed: f64) -> EntityThermalInput {
        EntityThermalInput {
            engine_on: true,
            speed_mps: speed,
            burning: false,
            destroyed: false,
        }
    }

    #[test]
    fn an_engine_warms_after_start_and_cools_after_stop_more_slowly() {
        let mut h = EntityHeat::default();
        let deck = HotPart::EngineDeck.index();
        let mut t = 0.0_f64;
        while h.rise_k[deck] < (1.0 - (-1.0_f64).exp()) * 55.0 {
            h.step(1.0, &running(0.0), AMBIENT);
            t += 1.0;
        }
        assert!((t - 480.0).abs() < 3.0, "warmed to 63 % in {t} s");
        let mut steady = EntityHeat::steady(&running(0.0), AMBIENT);
        let off = EntityThermalInput {
            engine_on: false,
            ..running(0.0)
        };
        let mut t = 0.0_f64;
        while steady.rise_k[deck] > (-1.0_f64).exp() * 55.0 {
            steady.step(1.0, &off, AMBIENT);
            t += 1.0;
        }
        assert!((t - 2400.0).abs() < 3.0, "cooled to 37 % in {t} s");
    }

    #[test]
    fn steps_of_any_length_agree() {
        let mut fine = EntityHeat::default();
        let mut coarse = EntityHeat::default();
        for _ in 0..6000 {
            fine.step(0.1, &running(10.0), AMBIENT);
        }
        coarse.step(600.0, &running(10.0), AMBIENT);
        for (a, b) in fine.rise_k.iter().zip(coarse.rise_k) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn exhaust_is_hottest_and_motion_heats_the_running_gear() {
        let moving = EntityHeat::steady(&running(12.0), AMBIENT);
        let parked = EntityHeat::steady(&running(0.0), AMBIENT);
        let r = |h: &EntityHeat, p: HotPart| h.rise_k[p.index()];
        assert!(r(&moving, HotPart::Exhaust) > r(&moving, HotPart::EngineDeck));
        assert!(r(&moving, HotPart::RunningGear) > r(&parked, HotPart::RunningGear) + 20.0);
        let burning = EntityHeat::steady(
            &EntityThermalInput {
                burning: true,
                destroyed: true,
                ..running(0.0)
            },
            AMBIENT,
        );
        assert!(burning.part_temperature_k(HotPart::BurningHull, AMBIENT) > 700.0);
        assert!((moving.part_temperature_k(HotPart::Crew, AMBIENT) - CREW_SKIN_K).abs() < 1e-9);
    }

    #[test]
    fn hot_spots_decay() {
        let c = HotSpot::crater(2.0);
        assert!(c.rise_k(0.0) > c.rise_k(600.0) * 2.5);
        assert_eq!(c.rise_k(-1.0), 0.0);
        assert!(HotSpot::impact().rise_k(30.0) < 1.0);
        for p in HotPart::ALL {
            assert_eq!(HotPart::from_name(p.name()), Some(p));
        }
    }
}
