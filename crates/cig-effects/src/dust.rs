//! Vehicle dust: how much dust a ground vehicle raises on a given surface at a given speed.
//!
//! Algorithm: the thesis's dust generator (source 000, chapter V.A and appendix D) takes the
//! soil as an index (0 no dust, 0.5 dry clay, 1 light sand) and the road as an index (0 paved,
//! 0.5 clay, 1 sand) from its Appendix Table 1, with the vehicle's speed. The thesis gives no
//! formula for the resulting cloud, so this module defines one that keeps its orderings: a
//! strength `soil_index * (0.25 + 0.75 road_index) * min(1, (speed - 1 m/s) / 19 m/s)` (zero
//! below walking pace, growing to full strength at 20 m/s, about 45 mph, the speed of the
//! thesis's Figure 11), which scales the initial puff radius (0.5 m to 3 m), the dust mass per
//! puff and the height the puffs are thrown to. Soil and road come from the terrain database's
//! material class under the vehicle (`cig_terrain::Material`, one byte per post), optionally with
//! the class beside a road, by [`DustSurface::from_materials`].
//!
//! Limits: no soil moisture, vegetation cover or track/wheel type; the material mapping assumes
//! dry-season ground (grass over dry clay raises dust; forest, rock, snow and water do not).

use crate::error::EffectsError;
use cig_terrain::Material;
use std::str::FromStr;

/// Soil type of the thesis's Appendix Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Soil {
    NoDust,
    DryClay,
    LightSand,
}

/// Road type of the thesis's Appendix Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Road {
    Paved,
    Clay,
    Sand,
}

impl Soil {
    /// The thesis's dust index: 0, 0.5, 1.
    pub fn index(self) -> f64 {
        match self {
            Soil::NoDust => 0.0,
            Soil::DryClay => 0.5,
            Soil::LightSand => 1.0,
        }
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Soil::NoDust => "none",
            Soil::DryClay => "dry_clay",
            Soil::LightSand => "light_sand",
        }
    }

    /// Colour hint of the raised dust (linear RGB, 0-1).
    pub fn colour_rgb(self) -> [f32; 3] {
        match self {
            Soil::NoDust => [0.55, 0.52, 0.48],
            Soil::DryClay => [0.58, 0.44, 0.32],
            Soil::LightSand => [0.78, 0.70, 0.52],
        }
    }
}

impl Road {
    /// The thesis's road index: 0, 0.5, 1.
    pub fn index(self) -> f64 {
        match self {
            Road::Paved => 0.0,
            Road::Clay => 0.5,
            Road::Sand => 1.0,
        }
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Road::Paved => "paved",
            Road::Clay => "clay",
            Road::Sand => "sand",
        }
    }
}

impl FromStr for Soil {
    type Err = EffectsError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "none" | "no_dust" => Ok(Soil::NoDust),
            "dry_clay" | "clay" => Ok(Soil::DryClay),
            "light_sand" | "sand" => Ok(Soil::LightSand),
            _ => Err(EffectsError::UnknownSoil(s.to_string())),
        }
    }
}

impl FromStr for Road {
    type Err = EffectsError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "paved" => Ok(Road::Paved),
            "clay" => Ok(Road::Clay),
            "sand" => Ok(Road::Sand),
            _ => Err(EffectsError::UnknownRoad(s.to_string())),
        }
    }
}

/// The surface under a vehicle as the dust model sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DustSurface {
    pub soil: Soil,
    pub road: Road,
}

impl DustSurface {
    /// Soil of an off-road material class (`None` for a road class).
    fn soil_of(material: Material) -> Option<Soil> {
        match material {
            Material::Sand => Some(Soil::LightSand),
            Material::DryClay | Material::Grass => Some(Soil::DryClay),
            Material::Water | Material::Forest | Material::Rock | Material::Snow => {
                Some(Soil::NoDust)
            }
            Material::PavedRoad | Material::DirtRoad => None,
        }
    }

    /// The surface for the material class under a vehicle. On a road class the soil is that of
    /// `roadside` (the class beside the road) when given, else the road's own (none for paved,
    /// dry clay for a dirt road). Off road, the road type is the soil's loose surface: sand on
    /// sand, clay elsewhere.
    pub fn from_materials(under: Material, roadside: Option<Material>) -> DustSurface {
        match under {
            Material::PavedRoad | Material::DirtRoad => {
                let (road, own_soil) = if under == Material::PavedRoad {
                    (Road::Paved, Soil::NoDust)
                } else {
                    (Road::Clay, Soil::DryClay)
                };
                let soil = roadside.and_then(Self::soil_of).unwrap_or(own_soil);
                DustSurface { soil, road }
            }
            off_road => {
                let soil = Self::soil_of(off_road).unwrap_or(Soil::NoDust);
                let road = if soil == Soil::LightSand {
                    Road::Sand
                } else {
                    Road::Clay
                };
                DustSurface { soil, road }
            }
        }
    }

    /// Dust strength 0-1 at `speed_mps` (any finite value; negative speeds count as their size).
    pub fn strength(self, speed_mps: f64) -> f64 {
        let speed = speed_mps.abs();
        if !speed.is_finite() {
            return 0.0;
        }
        let speed_factor = ((speed - 1.0) / 19.0).clamp(0.0, 1.0);
        self.soil.index() * (0.25 + 0.75 * self.road.index()) * speed_factor
    }

    /// Initial radius of a dust puff, m (0 when the surface raises no dust at this speed).
    pub fn puff_radius_m(self, speed_mps: f64) -> f64 {
        let s = self.strength(speed_mps);
        if s <= 0.0 {
            0.0
        } else {
            0.5 + 2.5 * s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const SOILS: [Soil; 3] = [Soil::NoDust, Soil::DryClay, Soil::LightSand];
    const ROADS: [Road; 3] = [Road::Paved, Road::Clay, Road::Sand];

    #[test]
    fn dust_size_orders_by_soil_road_and_speed() {
        for road in ROADS {
            let sizes: Vec<f64> = SOILS
                .iter()
                .map(|&soil| DustSurface { soil, road }.puff_radius_m(15.0))
                .collect();
            assert_eq!(sizes[0], 0.0, "no-dust soil raises nothing on {road:?}");
            assert!(
                sizes[0] < sizes[1] && sizes[1] < sizes[2],
                "{road:?}: {sizes:?}"
            );
        }
        for soil in [Soil::DryClay, Soil::LightSand] {
            let sizes: Vec<f64> = ROADS
                .iter()
                .map(|&road| DustSurface { soil, road }.puff_radius_m(15.0))
                .collect();
            assert!(
                sizes[0] < sizes[1] && sizes[1] < sizes[2],
                "{soil:?}: {sizes:?}"
            );
        }
        let sand = DustSurface {
            soil: Soil::LightSand,
            road: Road::Sand,
        };
        assert_eq!(
            sand.puff_radius_m(0.5),
            0.0,
            "a vehicle at walking pace raises nothing"
        );
        assert!(sand.puff_radius_m(5.0) < sand.puff_radius_m(10.0));
        assert!(sand.puff_radius_m(10.0) < sand.puff_radius_m(20.0));
        assert_eq!(sand.puff_radius_m(f64::NAN), 0.0);
    }

    #[test]
    fn materials_map_to_the_thesis_table() {
        let s = |m, r| DustSurface::from_materials(m, r);
        assert_eq!(
            s(Material::Sand, None),
            DustSurface {
                soil: Soil::LightSand,
                road: Road::Sand
            }
        );
        assert_eq!(
            s(Material::DryClay, None),
            DustSurface {
                soil: Soil::DryClay,
                road: Road::Clay
            }
        );
        assert_eq!(
            s(Material::PavedRoad, None),
            DustSurface {
                soil: Soil::NoDust,
                road: Road::Paved
            }
        );
        assert_eq!(
            s(Material::PavedRoad, Some(Material::Sand)),
            DustSurface {
                soil: Soil::LightSand,
                road: Road::Paved
            }
        );
        assert_eq!(
            s(Material::DirtRoad, None),
            DustSurface {
                soil: Soil::DryClay,
                road: Road::Clay
            }
        );
        for m in [
            Material::Water,
            Material::Forest,
            Material::Rock,
            Material::Snow,
        ] {
            assert_eq!(s(m, None).strength(20.0), 0.0, "{m}");
        }
        // A paved road through sand raises less than the sand beside it.
        assert!(
            s(Material::PavedRoad, Some(Material::Sand)).strength(15.0)
                < s(Material::Sand, None).strength(15.0)
        );
        assert_eq!("light_sand".parse::<Soil>().unwrap(), Soil::LightSand);
        assert!("mud".parse::<Soil>().is_err());
        assert!("gravel".parse::<Road>().is_err());
    }

    proptest! {
        #[test]
        fn dust_grows_with_speed(v in 0.0f64..60.0, dv in 0.0f64..10.0, soil in 0usize..3, road in 0usize..3) {
            let surface = DustSurface { soil: SOILS[soil], road: ROADS[road] };
            prop_assert!(surface.strength(v + dv) >= surface.strength(v));
            prop_assert!((0.0..=1.0).contains(&surface.strength(v)));
        }
    }
}
