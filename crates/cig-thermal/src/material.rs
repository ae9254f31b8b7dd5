//! The thermal materials: layered slabs with their surface optics, every property with its
//! source.
//!
//! Each material is a 1-D stack of layers (thickness, conductivity, density, specific heat),
//! a surface with a solar absorptivity and band emissivities, a wetness (the fraction of the
//! evaporation an open water surface would have at the same temperature, wind and humidity), an
//! optional melting cap, and an inner boundary: the deep ground for terrain, a constant
//! interior for hulls, vehicles and bodies, or the air again for leaves and track pads, which
//! have air on both faces. The source's ship model is one of them: eight nodes through a steel
//! plate with a constant interior (source 001, "Infrared Gray Level Prediction", Figure 4);
//! here every material has as many nodes as its layers need.
//!
//! Sources of the properties (cited per material in [`MATERIALS`]):
//! - [Oke] T. R. Oke, *Boundary Layer Climates*, 2nd ed., Routledge 1987: Table 2.1 (thermal
//!   properties of natural materials: density, specific heat, conductivity of soils, rock,
//!   snow, water, asphalt) and Table 1.1 (albedo and emissivity of natural surfaces).
//! - [Incropera] F. P. Incropera, D. P. DeWitt, *Fundamentals of Heat and Mass Transfer*, 6th
//!   ed., Wiley 2007: Table A.1 (plain carbon steel AISI 1010, chromium steel), Table A.3
//!   (glass, rubber, fabric), Table A.11 (total emissivities).
//! - [FLIR] FLIR Systems, *The Ultimate Infrared Handbook* emissivity table, 8-14 um (collected
//!   in `references/sensors.md`): oil paint 0.94, skin 0.98, asphalt 0.967, water 0.96-0.99,
//!   snow 0.8-0.9, concrete 0.92.
//! - [Jones] H. G. Jones, *Plants and Microclimate*, 3rd ed., Cambridge 2014: leaf thickness,
//!   water content and heat capacity; leaf absorptance of solar radiation about 0.5.
//! - [Fiala] D. Fiala et al., J. Appl. Physiol. 87:1957 (1999): skin and fat tissue
//!   conductivity, density, specific heat; core at 37 C.
//! - [Navy] MIL-PRF-24635 haze grey and CARC olive drab paint solar absorptance 0.7-0.9.
//!
//! Limits: properties are constant with temperature; soil moisture is fixed per class (the
//! wetness and the soil's properties do not change with rain); snow melts at its surface only
//! (the cap), with no meltwater; the wetness model uses the Lewis analogy and neglects canopy
//! resistance's daily cycle.

use crate::ThermalError;

/// One layer of a slab, from the surface down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    /// What the layer is.
    pub name: &'static str,
    /// Thickness, metres.
    pub thickness_m: f64,
    /// Thermal conductivity, W m-1 K-1.
    pub conductivity_w_m_k: f64,
    /// Density, kg m-3.
    pub density_kg_m3: f64,
    /// Specific heat, J kg-1 K-1.
    pub specific_heat_j_kg_k: f64,
    /// Cells the layer is divided into.
    pub cells: usize,
    /// Ratio of each cell's thickness to the one above it (1 for equal cells; above 1 puts
    /// fine cells near the surface, where the daily wave is).
    pub growth: f64,
}

/// What lies behind the last layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InnerBoundary {
    /// Held at the weather's deep-ground temperature (terrain).
    DeepGround,
    /// A film coefficient to an interior at a constant temperature (hulls, vehicles, bodies).
    Interior {
        /// Interior air or core temperature, kelvin.
        temperature_k: f64,
        /// Inner film (or perfusion) coefficient, W m-2 K-1.
        film_w_m2_k: f64,
    },
    /// Air on the back face too (leaves, track pads): convection and long-wave exchange with
    /// surroundings at air temperature.
    Air,
}

/// A thermal material: layers, surface optics and the inner boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialProperties {
    /// The material.
    pub id: ThermalMaterial,
    /// Layers from the surface down.
    pub layers: &'static [Layer],
    /// Fraction of the solar (0.3-3 um) irradiance absorbed at the surface.
    pub solar_absorptivity: f64,
    /// Emissivity in the long-wave infrared (8-12 um), also used for the broadband
    /// long-wave exchange of the energy balance.
    pub emissivity_lwir: f64,
    /// Emissivity in the mid-wave infrared (3-5 um).
    pub emissivity_mwir: f64,
    /// Fraction of open water's evaporation, 0 (dry) to 1 (open water).
    pub wetness: f64,
    /// The convective film coefficient relative to a large plate's (McAdams): above 1 for
    /// leaves and grass, whose small size gives thin boundary layers (Campbell and Norman,
    /// *An Introduction to Environmental Biophysics*, 1998, ch. 7).
    pub convection_factor: f64,
    /// A temperature the surface cannot rise above (snow melting at 0 C), kelvin.
    pub melts_at_k: Option<f64>,
    /// What lies behind the last layer.
    pub inner: InnerBoundary,
    /// Where the numbers come from.
    pub sources: &'static str,
}

/// Every material the thermal model knows: the terrain database's nine classes (in the
/// terrain's byte order) and the models' materials (the index is the code models carry in
/// their vertex colours' alpha, see `cig_scene::thermal`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ThermalMaterial {
    Water,
    Sand,
    DryClay,
    Grass,
    Forest,
    Rock,
    Snow,
    PavedRoad,
    DirtRoad,
    /// Painted steel ship hull.
    HullPaint,
    /// Painted steel ship superstructure (thinner plate, warmer interior).
    Superstructure,
    /// Painted rolled armour of a vehicle.
    VehicleArmour,
    /// Window glass.
    Glass,
    /// Rubber track pads, tyres and running gear covers.
    RubberTracks,
    /// Clothing over skin.
    Clothing,
    /// Bare skin.
    Skin,
    /// Tree canopy foliage (leaves).
    CanopyFoliage,
    /// Walls and roofs of buildings: concrete or brick over a heated interior.
    BuildingWall,
}

const CELSIUS_0: f64 = 273.15;

const STEEL_PLATE_10MM: [Layer; 1] = [Layer {
    name: "steel AISI 1010, 10 mm",
    thickness_m: 0.010,
    conductivity_w_m_k: 63.9,
    density_kg_m3: 7832.0,
    specific_heat_j_kg_k: 434.0,
    cells: 7,
    growth: 1.0,
}];

const STEEL_PLATE_6MM: [Layer; 1] = [Layer {
    name: "steel AISI 1010, 6 mm",
    thickness_m: 0.006,
    conductivity_w_m_k: 63.9,
    density_kg_m3: 7832.0,
    specific_heat_j_kg_k: 434.0,
    cells: 7,
    growth: 1.0,
}];

const ARMOUR_40MM: [Layer; 1] = [Layer {
    name: "chromium steel armour, 40 mm",
    thickness_m: 0.040,
    conductivity_w_m_k: 37.7,
    density_kg_m3: 7858.0,
    specific_heat_j_kg_k: 473.0,
    cells: 8,
    growth: 1.0,
}];

/// Moist loam under the vegetation and roads: between Oke's dry and saturated sandy and clay
/// soils (40 % pore space, about half saturated).
const MOIST_SOIL: Layer = Layer {
    name: "moist soil",
    thickness_m: 1.0,
    conductivity_w_m_k: 1.0,
    density_kg_m3: 1800.0,
    specific_heat_j_kg_k: 1180.0,
    cells: 12,
    growth: 1.35,
};

const fn soil(
    name: &'static str,
    conductivity_w_m_k: f64,
    density_kg_m3: f64,
    specific_heat_j_kg_k: f64,
) -> Layer {
    Layer {
        name,
        thickness_m: 1.0,
        conductivity_w_m_k,
        density_kg_m3,
        specific_heat_j_kg_k,
        cells: 12,
        growth: 1.35,
    }
}

/// A wind-mixed water layer over wet sediment. The eddy conductivity (5000 W/m K, an
/// assumption) mixes 2 m of water within about an hour, as wind and convection do; the
/// sediment (Oke's saturated clay) keeps the water from being pinned to the deep ground.
const WATER_LAYERS: [Layer; 2] = [
    Layer {
        name: "well-mixed water, 2 m",
        thickness_m: 2.0,
        conductivity_w_m_k: 5000.0,
        density_kg_m3: 1000.0,
        specific_heat_j_kg_k: 4180.0,
        cells: 4,
        growth: 1.0,
    },
    Layer {
        name: "wet sediment",
        thickness_m: 1.0,
        conductivity_w_m_k: 1.58,
        density_kg_m3: 2000.0,
        specific_heat_j_kg_k: 1550.0,
        cells: 6,
        growth: 1.3,
    },
];
const SAND_LAYERS: [Layer; 1] = [soil("dry sand (40 % pores)", 0.30, 1600.0, 800.0)];
const CLAY_LAYERS: [Layer; 1] = [soil("dry clay (40 % pores)", 0.25, 1600.0, 890.0)];
const GRASS_LAYERS: [Layer; 2] = [
    Layer {
        name: "turf: grass blades and thatch",
        thickness_m: 0.02,
        conductivity_w_m_k: 0.12,
        density_kg_m3: 250.0,
        specific_heat_j_kg_k: 2500.0,
        cells: 2,
        growth: 1.0,
    },
    MOIST_SOIL,
];
const LEAF_LAYERS: [Layer; 1] = [Layer {
    name: "leaf, 0.3 mm (70 % water)",
    thickness_m: 0.000_3,
    conductivity_w_m_k: 0.5,
    density_kg_m3: 700.0,
    specific_heat_j_kg_k: 3760.0,
    cells: 1,
    growth: 1.0,
}];
const ROCK_LAYERS: [Layer; 1] = [soil("solid rock", 2.90, 2700.0, 750.0)];
const SNOW_LAYERS: [Layer; 2] = [
    Layer {
        name: "old snow, 0.4 m",
        thickness_m: 0.4,
        conductivity_w_m_k: 0.42,
        density_kg_m3: 480.0,
        specific_heat_j_kg_k: 2090.0,
        cells: 8,
        growth: 1.3,
    },
    Layer {
        name: "frozen soil",
        thickness_m: 0.6,
        conductivity_w_m_k: 1.6,
        density_kg_m3: 1800.0,
        specific_heat_j_kg_k: 1000.0,
        cells: 4,
        growth: 1.3,
    },
];
const PAVED_LAYERS: [Layer; 2] = [
    Layer {
        name: "asphalt, 0.1 m",
        thickness_m: 0.1,
        conductivity_w_m_k: 0.75,
        density_kg_m3: 2110.0,
        specific_heat_j_kg_k: 920.0,
        cells: 5,
        growth: 1.2,
    },
    Layer {
        name: "road base",
        thickness_m: 0.9,
        ..MOIST_SOIL
    },
];
const DIRT_ROAD_LAYERS: [Layer; 1] = [soil("compacted dry clay", 0.6, 1900.0, 900.0)];
const GLASS_LAYERS: [Layer; 1] = [Layer {
    name: "plate glass, 6 mm",
    thickness_m: 0.006,
    conductivity_w_m_k: 1.4,
    density_kg_m3: 2500.0,
    specific_heat_j_kg_k: 750.0,
    cells: 4,
    growth: 1.0,
}];
const RUBBER_LAYERS: [Layer; 1] = [Layer {
    name: "vulcanised rubber, 20 mm",
    thickness_m: 0.02,
    conductivity_w_m_k: 0.13,
    density_kg_m3: 1100.0,
    specific_heat_j_kg_k: 2010.0,
    cells: 6,
    growth: 1.0,
}];
const TISSUE: Layer = Layer {
    name: "skin and fat, 8 mm",
    thickness_m: 0.008,
    conductivity_w_m_k: 0.37,
    density_kg_m3: 1000.0,
    specific_heat_j_kg_k: 3600.0,
    cells: 4,
    growth: 1.0,
};
const CLOTHING_LAYERS: [Layer; 2] = [
    Layer {
        name: "uniform fabric and trapped air, 3 mm",
        thickness_m: 0.003,
        conductivity_w_m_k: 0.05,
        density_kg_m3: 300.0,
        specific_heat_j_kg_k: 1300.0,
        cells: 3,
        growth: 1.0,
    },
    TISSUE,
];
const SKIN_LAYERS: [Layer; 1] = [TISSUE];
const WALL_LAYERS: [Layer; 1] = [Layer {
    name: "concrete, 0.2 m",
    thickness_m: 0.2,
    conductivity_w_m_k: 1.4,
    density_kg_m3: 2300.0,
    specific_heat_j_kg_k: 880.0,
    cells: 8,
    growth: 1.15,
}];

/// Blood perfusion and core coupling behind the skin tissue, W m-2 K-1 (Fiala 1999: the
/// perfusion term of resting skin is of the order of 10-40).
const PERFUSION_W_M2_K: f64 = 20.0;
const CORE_K: f64 = CELSIUS_0 + 37.0;

/// Every material's properties.
pub const MATERIALS: [MaterialProperties; 18] = [
    MaterialProperties {
        id: ThermalMaterial::Water,
        layers: &WATER_LAYERS,
        solar_absorptivity: 0.94,
        emissivity_lwir: 0.98,
        emissivity_mwir: 0.97,
        wetness: 1.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 water rho, c and saturated clay (sediment); eddy conductivity 5000 W/m \
                  K for a wind-mixed layer (an assumption: it mixes 2 m within an hour); Oke T1.1 albedo 0.03-0.10 at \
                  high sun; FLIR 0.96-0.99",
    },
    MaterialProperties {
        id: ThermalMaterial::Sand,
        layers: &SAND_LAYERS,
        solar_absorptivity: 0.65,
        emissivity_lwir: 0.90,
        emissivity_mwir: 0.82,
        wetness: 0.02,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 sandy soil dry; Oke T1.1 desert sand albedo 0.20-0.45, emissivity \
                  0.84-0.90",
    },
    MaterialProperties {
        id: ThermalMaterial::DryClay,
        layers: &CLAY_LAYERS,
        solar_absorptivity: 0.72,
        emissivity_lwir: 0.92,
        emissivity_mwir: 0.88,
        wetness: 0.05,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 clay soil dry; Oke T1.1 soils albedo 0.05-0.40, emissivity \
                  0.90-0.98",
    },
    MaterialProperties {
        id: ThermalMaterial::Grass,
        layers: &GRASS_LAYERS,
        solar_absorptivity: 0.77,
        emissivity_lwir: 0.96,
        emissivity_mwir: 0.95,
        wetness: 0.35,
        convection_factor: 1.5,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T1.1 grass albedo 0.16-0.26, emissivity 0.90-0.95; turf and moist soil \
                  between Oke T2.1's dry and saturated soils; wetness from a canopy resistance \
                  of about twice the aerodynamic resistance (Jones ch. 5); convection 1.5x \
                  (Campbell and Norman ch. 7)",
    },
    MaterialProperties {
        id: ThermalMaterial::Forest,
        layers: &LEAF_LAYERS,
        solar_absorptivity: 0.88,
        emissivity_lwir: 0.98,
        emissivity_mwir: 0.97,
        wetness: 0.5,
        convection_factor: 2.0,
        melts_at_k: None,
        inner: InnerBoundary::Air,
        sources: "the canopy seen from above: Oke T1.1 coniferous/deciduous forest albedo \
                  0.05-0.20, emissivity 0.97-0.99; leaves as CanopyFoliage (Jones); \
                  wetness 0.5 (a Bowen ratio near 0.5 of well-watered forest, Oke ch. 5); \
                  convection 2x for leaves (Campbell and Norman ch. 7)",
    },
    MaterialProperties {
        id: ThermalMaterial::Rock,
        layers: &ROCK_LAYERS,
        solar_absorptivity: 0.70,
        emissivity_lwir: 0.93,
        emissivity_mwir: 0.85,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 rock (solid); albedo 0.3 and emissivity 0.93 of granite (Incropera \
                  A.11: 0.90-0.93 for stone)",
    },
    MaterialProperties {
        id: ThermalMaterial::Snow,
        layers: &SNOW_LAYERS,
        solar_absorptivity: 0.25,
        emissivity_lwir: 0.90,
        emissivity_mwir: 0.85,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: Some(CELSIUS_0),
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 snow (old); Oke T1.1 old snow albedo 0.40-0.80 (0.75 taken); FLIR \
                  0.8-0.9; surface capped at 0 C (melting)",
    },
    MaterialProperties {
        id: ThermalMaterial::PavedRoad,
        layers: &PAVED_LAYERS,
        solar_absorptivity: 0.90,
        emissivity_lwir: 0.967,
        emissivity_mwir: 0.93,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 asphalt; Oke T1.1 asphalt albedo 0.05-0.20 (0.10 taken); FLIR \
                  asphalt 0.967; base as moist soil",
    },
    MaterialProperties {
        id: ThermalMaterial::DirtRoad,
        layers: &DIRT_ROAD_LAYERS,
        solar_absorptivity: 0.75,
        emissivity_lwir: 0.92,
        emissivity_mwir: 0.88,
        wetness: 0.03,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::DeepGround,
        sources: "Oke T2.1 clay soil between dry and saturated (compacted); Oke T1.1 soils \
                  albedo 0.05-0.40 (0.25 taken)",
    },
    MaterialProperties {
        id: ThermalMaterial::HullPaint,
        layers: &STEEL_PLATE_10MM,
        solar_absorptivity: 0.75,
        emissivity_lwir: 0.94,
        emissivity_mwir: 0.90,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CELSIUS_0 + 20.0,
            film_w_m2_k: 3.0,
        },
        sources: "Incropera A.1 AISI 1010; FLIR oil paint 0.94; Navy haze grey absorptance \
                  0.7-0.8; interior 20 C behind a still-air film of 3 W/m2 K",
    },
    MaterialProperties {
        id: ThermalMaterial::Superstructure,
        layers: &STEEL_PLATE_6MM,
        solar_absorptivity: 0.75,
        emissivity_lwir: 0.94,
        emissivity_mwir: 0.90,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CELSIUS_0 + 22.0,
            film_w_m2_k: 4.0,
        },
        sources: "Incropera A.1 AISI 1010; FLIR oil paint 0.94; Navy haze grey absorptance \
                  0.7-0.8; air-conditioned interior 22 C",
    },
    MaterialProperties {
        id: ThermalMaterial::VehicleArmour,
        layers: &ARMOUR_40MM,
        solar_absorptivity: 0.85,
        emissivity_lwir: 0.94,
        emissivity_mwir: 0.90,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CELSIUS_0 + 20.0,
            film_w_m2_k: 3.0,
        },
        sources: "Incropera A.1 chromium steel; FLIR oil paint 0.94; CARC olive drab \
                  absorptance 0.85; crew compartment 20 C",
    },
    MaterialProperties {
        id: ThermalMaterial::Glass,
        layers: &GLASS_LAYERS,
        solar_absorptivity: 0.15,
        emissivity_lwir: 0.92,
        emissivity_mwir: 0.85,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CELSIUS_0 + 21.0,
            film_w_m2_k: 8.0,
        },
        sources: "Incropera A.3 plate glass; Incropera A.11 glass 0.90-0.95; clear glass \
                  absorbs about 0.1-0.2 of sunlight (the rest is transmitted or reflected); \
                  inner film 8 W/m2 K (ASHRAE still air)",
    },
    MaterialProperties {
        id: ThermalMaterial::RubberTracks,
        layers: &RUBBER_LAYERS,
        solar_absorptivity: 0.90,
        emissivity_lwir: 0.94,
        emissivity_mwir: 0.92,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Air,
        sources: "Incropera A.3 vulcanised rubber (soft); Incropera A.11 rubber 0.94; black \
                  rubber absorptance 0.9",
    },
    MaterialProperties {
        id: ThermalMaterial::Clothing,
        layers: &CLOTHING_LAYERS,
        solar_absorptivity: 0.80,
        emissivity_lwir: 0.95,
        emissivity_mwir: 0.90,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CORE_K,
            film_w_m2_k: PERFUSION_W_M2_K,
        },
        sources: "Incropera A.3 fabric and cotton batting (0.04-0.06 W/m K with trapped air); \
                  Fiala 1999 tissue and core 37 C; cotton emissivity 0.95 (Incropera A.11); \
                  camouflage absorptance 0.8",
    },
    MaterialProperties {
        id: ThermalMaterial::Skin,
        layers: &SKIN_LAYERS,
        solar_absorptivity: 0.60,
        emissivity_lwir: 0.98,
        emissivity_mwir: 0.95,
        wetness: 0.06,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CORE_K,
            film_w_m2_k: PERFUSION_W_M2_K,
        },
        sources: "Fiala 1999 skin and fat tissue, core 37 C; FLIR human skin 0.98; insensible \
                  sweating about 6 % of a wet surface",
    },
    MaterialProperties {
        id: ThermalMaterial::CanopyFoliage,
        layers: &LEAF_LAYERS,
        solar_absorptivity: 0.50,
        emissivity_lwir: 0.97,
        emissivity_mwir: 0.96,
        wetness: 0.5,
        convection_factor: 2.0,
        melts_at_k: None,
        inner: InnerBoundary::Air,
        sources: "Jones: leaf 0.3 mm, 70 % water (c about 3760 J/kg K), solar absorptance \
                  about 0.5, emissivity 0.95-0.98; wetness and convection as for forest",
    },
    MaterialProperties {
        id: ThermalMaterial::BuildingWall,
        layers: &WALL_LAYERS,
        solar_absorptivity: 0.6,
        emissivity_lwir: 0.92,
        emissivity_mwir: 0.88,
        wetness: 0.0,
        convection_factor: 1.0,
        melts_at_k: None,
        inner: InnerBoundary::Interior {
            temperature_k: CELSIUS_0 + 20.0,
            film_w_m2_k: 8.0,
        },
        sources: "Oke T2.1 concrete (dense); FLIR concrete 0.92; Oke T1.1 concrete albedo \
                  0.10-0.35 and brick 0.20-0.40 (0.4 taken); heated interior 20 C behind \
                  ASHRAE's still-air film",
    },
];

impl ThermalMaterial {
    /// Every material, in table order.
    pub const ALL: [ThermalMaterial; 18] = [
        ThermalMaterial::Water,
        ThermalMaterial::Sand,
        ThermalMaterial::DryClay,
        ThermalMaterial::Grass,
        ThermalMaterial::Forest,
        ThermalMaterial::Rock,
        ThermalMaterial::Snow,
        ThermalMaterial::PavedRoad,
        ThermalMaterial::DirtRoad,
        ThermalMaterial::HullPaint,
        ThermalMaterial::Superstructure,
        ThermalMaterial::VehicleArmour,
        ThermalMaterial::Glass,
        ThermalMaterial::RubberTracks,
        ThermalMaterial::Clothing,
        ThermalMaterial::Skin,
        ThermalMaterial::CanopyFoliage,
        ThermalMaterial::BuildingWall,
    ];

    /// The material's index in [`ThermalMaterial::ALL`] and [`MATERIALS`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The terrain database's material byte (0..=8, the same order) as a thermal material.
    pub fn from_terrain_byte(byte: u8) -> Option<ThermalMaterial> {
        ThermalMaterial::ALL[..9].get(usize::from(byte)).copied()
    }

    /// The snake_case name used on the command line and in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            ThermalMaterial::Water => "water",
            ThermalMaterial::Sand => "sand",
            ThermalMaterial::DryClay => "dry_clay",
            ThermalMaterial::Grass => "grass",
            ThermalMaterial::Forest => "forest",
            ThermalMaterial::Rock => "rock",
            ThermalMaterial::Snow => "snow",
            ThermalMaterial::PavedRoad => "paved_road",
            ThermalMaterial::DirtRoad => "dirt_road",
            ThermalMaterial::HullPaint => "hull_paint",
            ThermalMaterial::Superstructure => "superstructure",
            ThermalMaterial::VehicleArmour => "vehicle_armour",
            ThermalMaterial::Glass => "glass",
            ThermalMaterial::RubberTracks => "rubber_tracks",
            ThermalMaterial::Clothing => "clothing",
            ThermalMaterial::Skin => "skin",
            ThermalMaterial::CanopyFoliage => "canopy_foliage",
            ThermalMaterial::BuildingWall => "building_wall",
        }
    }

    /// Parses a name of [`ThermalMaterial::name`].
    pub fn from_name(name: &str) -> Result<ThermalMaterial, ThermalError> {
        ThermalMaterial::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| ThermalError::UnknownMaterial(name.to_string()))
    }

    /// The material's properties.
    pub fn properties(self) -> &'static MaterialProperties {
        &MATERIALS[self.index()]
    }
}

/// All material names, comma-separated (for error messages and help).
pub fn material_names() -> String {
    ThermalMaterial::ALL.map(|m| m.name()).join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_order_matches_the_enum_and_properties_are_physical() {
        for (i, m) in ThermalMaterial::ALL.into_iter().enumerate() {
            let p = m.properties();
            assert_eq!(p.id, m);
            assert_eq!(m.index(), i);
            assert_eq!(ThermalMaterial::from_name(m.name()), Ok(m));
            assert!((0.0..=1.0).contains(&p.solar_absorptivity));
            assert!((0.5..=1.0).contains(&p.emissivity_lwir), "{m:?}");
            assert!((0.5..=1.0).contains(&p.emissivity_mwir), "{m:?}");
            assert!((0.0..=1.0).contains(&p.wetness));
            assert!((1.0..=3.0).contains(&p.convection_factor));
            assert!(!p.sources.is_empty());
            for l in p.layers {
                assert!(l.thickness_m > 0.0 && l.conductivity_w_m_k > 0.0);
                assert!(l.density_kg_m3 > 0.0 && l.specific_heat_j_kg_k > 0.0);
                assert!(l.cells >= 1 && l.growth >= 1.0);
            }
        }
    }

    #[test]
    fn terrain_bytes_map_in_order_and_unknown_names_are_refused() {
        assert_eq!(
            ThermalMaterial::from_terrain_byte(0),
            Some(ThermalMaterial::Water)
        );
        assert_eq!(
            ThermalMaterial::from_terrain_byte(8),
            Some(ThermalMaterial::DirtRoad)
        );
        assert_eq!(ThermalMaterial::from_terrain_byte(9), None);
        let e = ThermalMaterial::from_name("lava").expect_err("unknown");
        assert!(e.to_string().contains("lava"), "{e}");
    }
}
