//! Soil: Bekker–Wong sinkage, compaction resistance, thrust and go/no-go trafficability.
//!
//! # Algorithm
//!
//! Each running gear presses on the ground through rectangular contact patches of width `b`
//! (the smaller side) and length `l` ([`VehicleLoad`]), all carrying the same mean pressure
//! `p = m g / A`. Per patch (J. Y. Wong, *Theory of Ground Vehicles*, 4th ed., 2008, ch. 2,
//! after M. G. Bekker, *Introduction to Terrain-Vehicle Systems*, 1969):
//!
//! - Bekker's pressure–sinkage law `p = (k_c / b + k_phi) z^n`, so the static sinkage is
//!   `z0 = [p / (k_c / b + k_phi)]^(1/n)` ([`sinkage_m`]);
//! - the compaction (motion) resistance, the work of cutting a rut of depth `z0` per unit
//!   length: `R_c = b (k_c / b + k_phi) z0^(n+1) / (n+1)`, summed over the patches;
//! - the Mohr–Coulomb maximum thrust of the whole footprint `H_max = A c + W tan(phi)`, and the
//!   Janosi–Hanamoto shear stress `tau = (c + sigma tan phi)(1 - e^(-j/K))` that builds it up
//!   with the shear displacement `j` ([`shear_stress_pa`], [`thrust_at_slip_n`]).
//!
//! [`trafficability`] turns these into a go/no-go verdict (document 002, "Slippage – stuck in
//! mud" and "Trafficability": Bekker's model with empirical limits). The vehicle is **no-go**
//! when
//!
//! 1. the sinkage exceeds the gear's ground clearance ([`RunningGear::ground_clearance_m`]):
//!    the hull (or, on foot, the shin) rests on the soil and the vehicle is high-centred
//!    (the usual belly- or axle-contact immobilisation rule; the clearances are this crate's
//!    choices, see [`RunningGear`]); or
//! 2. the compaction resistance reaches the maximum thrust: Wong's drawbar pull, thrust minus
//!    motion resistance (`H_max - R_c` here), is no longer positive, so the vehicle cannot
//!    move itself. Bulldozing and internal resistances would only make this stricter.
//!
//! Otherwise it is **go**. Ruts ([`rut_depth_m`]) are the Bekker sinkage capped at the ground
//! clearance: past it the hull carries the load and the rut stops deepening.
//!
//! # Tables
//!
//! Bekker–Wong parameters are Wong's Table 2.3 (his units: `k_c` in kN/m^(n+1), `k_phi` in
//! kN/m^(n+2), `c` in kPa, `phi` in degrees); `K` is the shear deformation modulus. The rows
//! were checked against the same table as transcribed in a published Project Chrono SCM
//! terrain demo (`Soil_Params`, 23 rows "from Theory of Ground Vehicles, Wong et al., 2008");
//! the book itself was not available here.
//!
//! | constant | n | k_c | k_phi | c kPa | phi ° | K m |
//! |---|---|---|---|---|---|---|
//! | [`DRY_SAND`] (Land Locomotion Lab) | 1.1 | 0.99 | 1528.43 | 1.04 | 28 | 0.025 |
//! | [`SANDY_LOAM_15`] (LLL, 15 % moisture) | 0.7 | 5.27 | 1515.04 | 1.72 | 29 | 0.02 |
//! | [`SANDY_LOAM_26`] (Hanamoto, 26 %) | 0.3 | 2.79 | 141.11 | 13.79 | 22 | 0.02 |
//! | [`CLAYEY_SOIL_38`] (Thailand, 38 %) | 0.5 | 13.19 | 692.15 | 4.14 | 13 | 0.02 |
//! | [`CLAYEY_SOIL_55`] (Thailand, 55 %) | 0.7 | 16.03 | 1262.53 | 2.07 | 10 | 0.02 |
//! | [`HEAVY_CLAY_25`] (WES, 25 %) | 0.13 | 12.70 | 1555.95 | 68.95 | 34 | 0.006 |
//! | [`HEAVY_CLAY_40`] (WES, 40 %) | 0.11 | 1.84 | 103.27 | 20.69 | 6 | 0.03 |
//! | [`LEAN_CLAY_22`] (WES, 22 %) | 0.2 | 16.43 | 1724.69 | 68.95 | 20 | 0.006 |
//! | [`LEAN_CLAY_32`] (WES, 32 %) | 0.15 | 1.52 | 119.61 | 13.79 | 11 | 0.03 |
//! | [`LETE_SAND`] (Wong) | 0.793 | 102 | 5301 | 1.3 | 31.1 | 0.012 |
//! | [`SNOW_US`] (U.S., Harrison) | 1.6 | 4.37 | 196.72 | 1.03 | 19.7 | 0.025 |
//! | [`SNOW_SWEDEN`] | 1.44 | 10.55 | 66.08 | 6.0 | 20.7 | 0.025 |
//!
//! `K` is **not** part of Table 2.3. The values follow Wong's text (ch. 2: about 1 cm on firm
//! sandy terrain, 2.5 cm on loose sand and undisturbed fresh snow, 0.6 cm for clay at maximum
//! compaction — quoted from memory of the book, unverified here) and the Chrono demo's choices
//! (2 cm for loams, 3 cm for the wet clays, 1.2 cm for LETE sand). `K` only enters
//! [`shear_stress_pa`] and [`thrust_at_slip_n`], never the go/no-go verdict. LETE sand's `n`
//! is 0.793 as in the project's reference notes; the Chrono transcription rounds it to 0.79.
//!
//! Materials and moisture map to rows as follows ([`properties`]):
//!
//! | material | [`SoilMoisture::Dry`] | [`SoilMoisture::Wet`] |
//! |---|---|---|
//! | sand | dry sand | sandy loam, 15 % |
//! | dry clay | heavy clay, 25 % | heavy clay, 40 % |
//! | grass | sandy loam, 15 % | sandy loam (Hanamoto), 26 % |
//! | forest | clayey soil, 38 % | clayey soil, 55 % |
//! | dirt road | lean clay, 22 % | lean clay, 32 % |
//! | snow | snow (U.S.) | snow (Sweden) |
//! | rock, paved road | — (does not deform) | — |
//! | water | — (not trafficable) | — |
//!
//! Choices made here, not by a source: moist sand is *firmer* than dry loose sand (capillary
//! cohesion; the reason beaches are driven at the waterline), so wet sand takes the moist
//! sandy-loam row and ruts less than dry sand. Table 2.3 gives no wetness for its snow rows;
//! the softer Swedish snow stands for wet snow. Dirt roads are compacted, so they take the
//! firm WES lean clay when dry and the same clay at 32 % moisture when wet.
//!
//! # Limits
//!
//! - Static, uniform pressure on flat rectangular patches: no multi-pass compaction, no
//!   slip-sinkage, no bulldozing resistance, no rigid-wheel geometry (a rigid wheel sinks more
//!   than a flat patch of the same area), no layered soil or finite snow depth (the snow rows
//!   assume snow deeper than the clearance; shallower snow bottoms out on the ground below).
//! - Bekker's `k_c / b` term is a size effect: at equal pressure a wider patch sinks deeper
//!   (soils with `k_c` near zero, such as dry sand, hardly care).
//! - The power law is a fit over the plate tests' range. Outside it the results are
//!   extrapolations: the wet clays' small `n` (0.11–0.15) makes sinkage switch from
//!   millimetres to metres around `p ≈ k_c / b + k_phi` (a bearing-capacity failure), and at
//!   very light pressures (people on foot) a low-`n` wet soil can show *less* sinkage than the
//!   same soil dry. Sinkage and ruts are therefore reported capped at the ground clearance.
//! - Hard surfaces (rock, paved road) do not deform: sinkage and resistance are zero and the
//!   thrust is a friction coefficient times the weight (see [`HARD_SURFACE_TRACTION_DRY`]).

use cig_terrain::Material;

use crate::G_MPS2;

/// Ground moisture: the dry and the wet (after rain or thaw) state of each soil.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SoilMoisture {
    /// Dry, or at its usual field moisture.
    Dry,
    /// Wet: near saturation after rain, flooding or thaw.
    Wet,
}

/// Bekker–Wong and Janosi–Hanamoto parameters of one soil (units as Wong's Table 2.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoilProperties {
    /// The soil as the source names it.
    pub name: &'static str,
    /// Sinkage exponent `n`, dimensionless.
    pub n: f64,
    /// Cohesive modulus of deformation `k_c`, kN/m^(n+1).
    pub k_c_kn: f64,
    /// Frictional modulus of deformation `k_phi`, kN/m^(n+2).
    pub k_phi_kn: f64,
    /// Cohesion `c`, kPa.
    pub cohesion_kpa: f64,
    /// Angle of internal shearing resistance `phi`, degrees.
    pub friction_angle_deg: f64,
    /// Shear deformation modulus `K` of the Janosi–Hanamoto equation, m.
    pub shear_deformation_modulus_m: f64,
}

impl SoilProperties {
    /// `k_c / b + k_phi` for a contact of width `b`, kN/m^(n+2).
    fn modulus_kn(&self, contact_width_m: f64) -> f64 {
        self.k_c_kn / contact_width_m + self.k_phi_kn
    }

    /// Whether the parameters can be used: `n`, `k_phi`, `K` positive and finite, `k_c`,
    /// `c` non-negative and finite, `phi` in 0..90 degrees.
    pub fn is_usable(&self) -> bool {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        positive(self.n)
            && non_negative(self.k_c_kn)
            && positive(self.k_phi_kn)
            && non_negative(self.cohesion_kpa)
            && (0.0..90.0).contains(&self.friction_angle_deg)
            && positive(self.shear_deformation_modulus_m)
    }
}

/// Dry sand, Land Locomotion Laboratory (Wong, Table 2.3).
pub const DRY_SAND: SoilProperties = SoilProperties {
    name: "dry sand (LLL)",
    n: 1.1,
    k_c_kn: 0.99,
    k_phi_kn: 1528.43,
    cohesion_kpa: 1.04,
    friction_angle_deg: 28.0,
    shear_deformation_modulus_m: 0.025,
};

/// Sandy loam at 15 % moisture, Land Locomotion Laboratory (Wong, Table 2.3).
pub const SANDY_LOAM_15: SoilProperties = SoilProperties {
    name: "sandy loam, 15 % moisture (LLL)",
    n: 0.7,
    k_c_kn: 5.27,
    k_phi_kn: 1515.04,
    cohesion_kpa: 1.72,
    friction_angle_deg: 29.0,
    shear_deformation_modulus_m: 0.02,
};

/// Sandy loam at 26 % moisture, Hanamoto (Wong, Table 2.3).
pub const SANDY_LOAM_26: SoilProperties = SoilProperties {
    name: "sandy loam, 26 % moisture (Hanamoto)",
    n: 0.3,
    k_c_kn: 2.79,
    k_phi_kn: 141.11,
    cohesion_kpa: 13.79,
    friction_angle_deg: 22.0,
    shear_deformation_modulus_m: 0.02,
};

/// Clayey soil at 38 % moisture, Thailand (Wong, Table 2.3).
pub const CLAYEY_SOIL_38: SoilProperties = SoilProperties {
    name: "clayey soil, 38 % moisture (Thailand)",
    n: 0.5,
    k_c_kn: 13.19,
    k_phi_kn: 692.15,
    cohesion_kpa: 4.14,
    friction_angle_deg: 13.0,
    shear_deformation_modulus_m: 0.02,
};

/// Clayey soil at 55 % moisture, Thailand (Wong, Table 2.3).
pub const CLAYEY_SOIL_55: SoilProperties = SoilProperties {
    name: "clayey soil, 55 % moisture (Thailand)",
    n: 0.7,
    k_c_kn: 16.03,
    k_phi_kn: 1262.53,
    cohesion_kpa: 2.07,
    friction_angle_deg: 10.0,
    shear_deformation_modulus_m: 0.02,
};

/// Heavy clay at 25 % moisture, Waterways Experiment Station (Wong, Table 2.3).
pub const HEAVY_CLAY_25: SoilProperties = SoilProperties {
    name: "heavy clay, 25 % moisture (WES)",
    n: 0.13,
    k_c_kn: 12.70,
    k_phi_kn: 1555.95,
    cohesion_kpa: 68.95,
    friction_angle_deg: 34.0,
    shear_deformation_modulus_m: 0.006,
};

/// Heavy clay at 40 % moisture, Waterways Experiment Station (Wong, Table 2.3).
pub const HEAVY_CLAY_40: SoilProperties = SoilProperties {
    name: "heavy clay, 40 % moisture (WES)",
    n: 0.11,
    k_c_kn: 1.84,
    k_phi_kn: 103.27,
    cohesion_kpa: 20.69,
    friction_angle_deg: 6.0,
    shear_deformation_modulus_m: 0.03,
};

/// Lean clay at 22 % moisture, Waterways Experiment Station (Wong, Table 2.3).
pub const LEAN_CLAY_22: SoilProperties = SoilProperties {
    name: "lean clay, 22 % moisture (WES)",
    n: 0.2,
    k_c_kn: 16.43,
    k_phi_kn: 1724.69,
    cohesion_kpa: 68.95,
    friction_angle_deg: 20.0,
    shear_deformation_modulus_m: 0.006,
};

/// Lean clay at 32 % moisture, Waterways Experiment Station (Wong, Table 2.3).
pub const LEAN_CLAY_32: SoilProperties = SoilProperties {
    name: "lean clay, 32 % moisture (WES)",
    n: 0.15,
    k_c_kn: 1.52,
    k_phi_kn: 119.61,
    cohesion_kpa: 13.79,
    friction_angle_deg: 11.0,
    shear_deformation_modulus_m: 0.03,
};

/// LETE sand, Wong's own measurements (Wong, Table 2.3). Not mapped to a material; kept for
/// callers that want a firm, compacted sand.
pub const LETE_SAND: SoilProperties = SoilProperties {
    name: "LETE sand (Wong)",
    n: 0.793,
    k_c_kn: 102.0,
    k_phi_kn: 5301.0,
    cohesion_kpa: 1.3,
    friction_angle_deg: 31.1,
    shear_deformation_modulus_m: 0.012,
};

/// Snow, U.S. (Harrison) (Wong, Table 2.3).
pub const SNOW_US: SoilProperties = SoilProperties {
    name: "snow (U.S., Harrison)",
    n: 1.6,
    k_c_kn: 4.37,
    k_phi_kn: 196.72,
    cohesion_kpa: 1.03,
    friction_angle_deg: 19.7,
    shear_deformation_modulus_m: 0.025,
};

/// Snow, Sweden (Wong, Table 2.3).
pub const SNOW_SWEDEN: SoilProperties = SoilProperties {
    name: "snow (Sweden)",
    n: 1.44,
    k_c_kn: 10.55,
    k_phi_kn: 66.08,
    cohesion_kpa: 6.0,
    friction_angle_deg: 20.7,
    shear_deformation_modulus_m: 0.025,
};

/// Traction coefficient on dry hard surfaces (rock, paved road): the sliding value of tyres on
/// dry asphalt and concrete (peak 0.8–0.9, sliding 0.75) in Wong's Table 1.1 of road adhesion,
/// quoted from memory of the book, unverified here. Rubber-padded tracks are similar.
pub const HARD_SURFACE_TRACTION_DRY: f64 = 0.75;

/// Traction coefficient on wet hard surfaces: wet asphalt's sliding range 0.45–0.6 in the same
/// table (unverified here), taken at 0.5.
pub const HARD_SURFACE_TRACTION_WET: f64 = 0.5;

/// Heaviest load accepted, kg (well above any land vehicle; heavier is an input error).
pub const MAX_MASS_KG: f64 = 1.0e6;

/// Smallest contact area accepted, m² (a heel); smaller would be an infinite pressure.
pub const MIN_CONTACT_AREA_M2: f64 = 1.0e-4;

/// Largest contact area accepted, m².
pub const MAX_CONTACT_AREA_M2: f64 = 1.0e3;

/// Bekker–Wong parameters of `material` in the given moisture (module table); `None` where the
/// ground does not deform (rock, paved road) or is water.
pub fn properties(material: Material, moisture: SoilMoisture) -> Option<SoilProperties> {
    use SoilMoisture::{Dry, Wet};
    match (material, moisture) {
        (Material::Water | Material::Rock | Material::PavedRoad, _) => None,
        (Material::Sand, Dry) => Some(DRY_SAND),
        (Material::Sand, Wet) | (Material::Grass, Dry) => Some(SANDY_LOAM_15),
        (Material::Grass, Wet) => Some(SANDY_LOAM_26),
        (Material::DryClay, Dry) => Some(HEAVY_CLAY_25),
        (Material::DryClay, Wet) => Some(HEAVY_CLAY_40),
        (Material::Forest, Dry) => Some(CLAYEY_SOIL_38),
        (Material::Forest, Wet) => Some(CLAYEY_SOIL_55),
        (Material::DirtRoad, Dry) => Some(LEAN_CLAY_22),
        (Material::DirtRoad, Wet) => Some(LEAN_CLAY_32),
        (Material::Snow, Dry) => Some(SNOW_US),
        (Material::Snow, Wet) => Some(SNOW_SWEDEN),
    }
}

/// Why a soil call refused its input: one line naming the value and the reason.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SoilError {
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

/// How a vehicle meets the ground; fixes the number and shape of its contact patches.
///
/// | gear | patches | patch shape | ground clearance |
/// |---|---|---|---|
/// | tracked | 2 (one per track) | length = 5 × width | 0.45 m |
/// | wheeled | 4 up to 10 t, 6 up to 20 t, 8 above | square | 0.30 m |
/// | foot | 2 (soles) | length = 3 × width (0.3 × 0.1 m at 0.06 m²) | 0.30 m |
///
/// Length-to-width 5 is the lower end of tanks' track contact (about 5–7); the wheel counts
/// are typical axle counts for the mass class; the clearances are typical of main battle
/// tanks (0.43–0.5 m), of military wheeled vehicles (0.3–0.4 m, taken low) and, on foot, a
/// sinkage to mid-shin. All are this crate's choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RunningGear {
    /// Two tracks.
    Tracked,
    /// Wheels (tyres), four or more.
    Wheeled,
    /// A person on two feet.
    Foot,
}

impl RunningGear {
    /// Ground clearance, m: the sinkage at which the vehicle is high-centred (module docs).
    pub fn ground_clearance_m(self) -> f64 {
        match self {
            RunningGear::Tracked => 0.45,
            RunningGear::Wheeled | RunningGear::Foot => 0.30,
        }
    }

    /// Patch length over patch width.
    fn aspect(self) -> f64 {
        match self {
            RunningGear::Tracked => 5.0,
            RunningGear::Wheeled => 1.0,
            RunningGear::Foot => 3.0,
        }
    }
}

/// A vehicle (or person) standing on the ground: its mass, its total contact area and how it
/// meets the ground. Built by [`VehicleLoad::new`], which checks the values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleLoad {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Total contact area of all patches, m².
    pub contact_area_m2: f64,
    /// How it meets the ground.
    pub running_gear: RunningGear,
}

impl VehicleLoad {
    /// A load of `mass_kg` (finite, above 0, at most [`MAX_MASS_KG`]) on `contact_area_m2` (finite,
    /// from [`MIN_CONTACT_AREA_M2`] to [`MAX_CONTACT_AREA_M2`]).
    pub fn new(
        mass_kg: f64,
        contact_area_m2: f64,
        running_gear: RunningGear,
    ) -> Result<VehicleLoad, SoilError> {
        if !(mass_kg.is_finite() && mass_kg > 0.0 && mass_kg <= MAX_MASS_KG) {
            return Err(SoilError::OutOfRange {
                name: "mass_kg",
                range: "finite, above 0 and at most 1e6 kg",
                value: mass_kg,
            });
        }
        if !(contact_area_m2.is_finite()
            && (MIN_CONTACT_AREA_M2..=MAX_CONTACT_AREA_M2).contains(&contact_area_m2))
        {
            return Err(SoilError::OutOfRange {
                name: "contact_area_m2",
                range: "finite, from 1e-4 to 1e3 m²",
                value: contact_area_m2,
            });
        }
        Ok(VehicleLoad {
            mass_kg,
            contact_area_m2,
            running_gear,
        })
    }

    /// Weight, N.
    pub fn weight_n(&self) -> f64 {
        self.mass_kg * G_MPS2
    }

    /// Mean ground pressure `m g / A`, Pa.
    pub fn ground_pressure_pa(&self) -> f64 {
        self.weight_n() / self.contact_area_m2
    }

    /// Number of contact patches (table on [`RunningGear`]).
    pub fn patches(&self) -> u32 {
        match self.running_gear {
            RunningGear::Tracked | RunningGear::Foot => 2,
            RunningGear::Wheeled if self.mass_kg <= 10_000.0 => 4,
            RunningGear::Wheeled if self.mass_kg <= 20_000.0 => 6,
            RunningGear::Wheeled => 8,
        }
    }

    /// Width `b` of one patch (its smaller side), m.
    pub fn contact_width_m(&self) -> f64 {
        let patch_m2 = self.contact_area_m2 / f64::from(self.patches());
        (patch_m2 / self.running_gear.aspect()).sqrt()
    }

    /// Length of one patch, m.
    pub fn contact_length_m(&self) -> f64 {
        self.contact_width_m() * self.running_gear.aspect()
    }
}

/// The go/no-go verdict for one load on one ground, with the numbers behind it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trafficability {
    /// The ground.
    pub material: Material,
    /// Static Bekker sinkage, m, capped at the gear's ground clearance (0 on hard ground and
    /// water).
    pub sinkage_m: f64,
    /// Total compaction resistance of all patches at that sinkage, N.
    pub resistance_n: f64,
    /// Maximum thrust `A c + W tan(phi)` (friction times weight on hard ground, 0 on water), N.
    pub max_thrust_n: f64,
    /// Whether the load can move over this ground.
    pub trafficable: bool,
    /// Why: [`REASON_GO`], [`REASON_HARD`], [`REASON_WATER`], [`REASON_HIGH_CENTRED`] or
    /// [`REASON_NO_THRUST`].
    pub reason: &'static str,
}

/// Reason of a go on deformable ground.
pub const REASON_GO: &str = "go";
/// Reason on rock and paved road.
pub const REASON_HARD: &str = "hard surface, no sinkage";
/// Reason on water.
pub const REASON_WATER: &str = "water";
/// Reason when the sinkage exceeds the ground clearance.
pub const REASON_HIGH_CENTRED: &str = "sinkage exceeds ground clearance (high-centred)";
/// Reason when the compaction resistance reaches the maximum thrust.
pub const REASON_NO_THRUST: &str = "compaction resistance exceeds maximum thrust";

/// Static Bekker sinkage `z0 = [p / (k_c / b + k_phi)]^(1/n)`, m, of a plate of width
/// `contact_width_m` under `pressure_pa`.
///
/// Uncapped (see [`rut_depth_m`] for the capped rut). Returns 0 when nothing presses or the
/// inputs are unusable: a pressure or width that is not above zero (or NaN), or soil
/// parameters that fail [`SoilProperties::is_usable`], or an infinite pressure on a plate so
/// narrow that `k_c / b` is infinite too (undefined). Otherwise an infinite pressure sinks
/// infinitely.
pub fn sinkage_m(props: &SoilProperties, pressure_pa: f64, contact_width_m: f64) -> f64 {
    let pressing = pressure_pa > 0.0 && contact_width_m > 0.0 && props.is_usable();
    let modulus_kn = props.modulus_kn(contact_width_m);
    let ratio = pressure_pa / 1000.0 / modulus_kn;
    if pressing && modulus_kn > 0.0 && !ratio.is_nan() {
        ratio.powf(1.0 / props.n)
    } else {
        0.0
    }
}

/// Compaction resistance of one patch of width `contact_width_m` sunk `sinkage_m`,
/// `R_c = b (k_c / b + k_phi) z^(n+1) / (n+1)`, N. Zero for unusable inputs.
pub fn compaction_resistance_n(
    props: &SoilProperties,
    contact_width_m: f64,
    sinkage_m: f64,
) -> f64 {
    if contact_width_m > 0.0 && sinkage_m > 0.0 && props.is_usable() {
        let n1 = props.n + 1.0;
        let kn = contact_width_m * props.modulus_kn(contact_width_m) * sinkage_m.powf(n1) / n1;
        kn * 1000.0
    } else {
        0.0
    }
}

/// Maximum thrust of the whole footprint, `H_max = A c + W tan(phi)`, N.
pub fn max_thrust_n(props: &SoilProperties, load: &VehicleLoad) -> f64 {
    let cohesion_n = load.contact_area_m2 * props.cohesion_kpa * 1000.0;
    cohesion_n + load.weight_n() * props.friction_angle_deg.to_radians().tan()
}

/// Janosi–Hanamoto shear stress `tau = (c + sigma tan phi)(1 - e^(-j/K))`, Pa, under normal
/// pressure `normal_pressure_pa` after a shear displacement `shear_displacement_m`.
/// Negative or NaN pressure or displacement count as zero.
pub fn shear_stress_pa(
    props: &SoilProperties,
    normal_pressure_pa: f64,
    shear_displacement_m: f64,
) -> f64 {
    let sigma_pa = normal_pressure_pa.max(0.0);
    let j_m = shear_displacement_m.max(0.0);
    let strength_pa =
        props.cohesion_kpa * 1000.0 + sigma_pa * props.friction_angle_deg.to_radians().tan();
    strength_pa * (1.0 - (-j_m / props.shear_deformation_modulus_m).exp())
}

/// Thrust of the footprint at slip `slip` (0 = rolling, 1 = spinning in place), N: the
/// Janosi–Hanamoto stress integrated along a patch whose shear displacement grows linearly
/// from 0 at its front to `slip × l` at its rear (Wong, ch. 2, uniform pressure):
/// `F = H_max [1 - K / (i l) (1 - e^(-i l / K))]`. The slip is clamped to 0..=1 (NaN is 0).
pub fn thrust_at_slip_n(props: &SoilProperties, load: &VehicleLoad, slip: f64) -> f64 {
    let slip = if slip.is_nan() {
        0.0
    } else {
        slip.clamp(0.0, 1.0)
    };
    let sheared_m = slip * load.contact_length_m();
    if sheared_m <= 0.0 {
        return 0.0;
    }
    let k_m = props.shear_deformation_modulus_m;
    let fraction = 1.0 - k_m / sheared_m * (1.0 - (-sheared_m / k_m).exp());
    max_thrust_n(props, load) * fraction
}

/// The go/no-go verdict of `load` on `material` (rules in the module docs).
///
/// Water: not trafficable, reason [`REASON_WATER`], all numbers zero. Rock and paved road:
/// trafficable, no sinkage or resistance, thrust = [`HARD_SURFACE_TRACTION_DRY`] (or
/// [`HARD_SURFACE_TRACTION_WET`]) times the weight.
pub fn trafficability(
    material: Material,
    moisture: SoilMoisture,
    load: &VehicleLoad,
) -> Trafficability {
    match properties(material, moisture) {
        Some(props) => assess(material, &props, load),
        None if material == Material::Water => Trafficability {
            material,
            sinkage_m: 0.0,
            resistance_n: 0.0,
            max_thrust_n: 0.0,
            trafficable: false,
            reason: REASON_WATER,
        },
        None => {
            let traction = match moisture {
                SoilMoisture::Dry => HARD_SURFACE_TRACTION_DRY,
                SoilMoisture::Wet => HARD_SURFACE_TRACTION_WET,
            };
            Trafficability {
                material,
                sinkage_m: 0.0,
                resistance_n: 0.0,
                max_thrust_n: traction * load.weight_n(),
                trafficable: true,
                reason: REASON_HARD,
            }
        }
    }
}

/// The verdict on deformable soil `props` (the ground is named `material` in the result).
fn assess(material: Material, props: &SoilProperties, load: &VehicleLoad) -> Trafficability {
    let width_m = load.contact_width_m();
    let clearance_m = load.running_gear.ground_clearance_m();
    let sinkage_m = sinkage_m(props, load.ground_pressure_pa(), width_m);
    let rut_m = sinkage_m.min(clearance_m);
    let resistance_n = f64::from(load.patches()) * compaction_resistance_n(props, width_m, rut_m);
    let max_thrust_n = max_thrust_n(props, load);
    let (trafficable, reason) = if sinkage_m > clearance_m {
        (false, REASON_HIGH_CENTRED)
    } else if resistance_n >= max_thrust_n {
        (false, REASON_NO_THRUST)
    } else {
        (true, REASON_GO)
    };
    Trafficability {
        material,
        sinkage_m: rut_m,
        resistance_n,
        max_thrust_n,
        trafficable,
        reason,
    }
}

/// Depth of the rut `load` leaves in `material`, m: the static Bekker sinkage capped at the
/// gear's ground clearance (past it the hull carries the load); 0 on rock, paved road and
/// water.
pub fn rut_depth_m(material: Material, moisture: SoilMoisture, load: &VehicleLoad) -> f64 {
    trafficability(material, moisture, load).sinkage_m
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A 60 t main battle tank on 4.6 m² of track.
    fn tank() -> VehicleLoad {
        VehicleLoad::new(60_000.0, 4.6, RunningGear::Tracked).unwrap()
    }

    /// A 2.5 t light utility vehicle on four 0.1 m² tyre patches.
    fn utility() -> VehicleLoad {
        VehicleLoad::new(2_500.0, 0.4, RunningGear::Wheeled).unwrap()
    }

    /// An 80 kg soldier standing on two 0.3 × 0.1 m soles.
    fn soldier() -> VehicleLoad {
        VehicleLoad::new(80.0, 0.06, RunningGear::Foot).unwrap()
    }

    fn close(actual: f64, expected: f64, rel: f64) -> bool {
        (actual - expected).abs() <= rel * expected.abs()
    }

    #[test]
    fn sinkage_matches_a_hand_computation() {
        // Dry sand, 50 kPa on a 0.5 m plate:
        // k = 0.99 / 0.5 + 1528.43 = 1530.41 kN/m^3.1;
        // z = (50 / 1530.41)^(1 / 1.1) = 0.032671^0.90909 = 0.0445901 m.
        let z = sinkage_m(&DRY_SAND, 50_000.0, 0.5);
        assert!(close(z, 0.044_590_09, 1e-6), "{z}");
        // R_c = 0.5 * 1530.41 * z^2.1 / 2.1 kN = 530.834 N.
        let r = compaction_resistance_n(&DRY_SAND, 0.5, z);
        assert!(close(r, 530.834_4, 1e-5), "{r}");
        // The law inverts: the pressure that sinks the plate z deep is (k_c/b + k_phi) z^n.
        let p_kpa = (0.99 / 0.5 + 1528.43) * z.powf(1.1);
        assert!(close(p_kpa, 50.0, 1e-9));
    }

    #[test]
    fn wider_plates_and_higher_pressures_sink_deeper() {
        // Bekker's size effect: at equal pressure k_c / b stiffens a narrow plate, so the wide
        // one sinks deeper: (80 / (13.19 + 692.15))^2 = 0.0129 m against
        // (80 / (131.9 + 692.15))^2 = 0.0094 m.
        let wide = sinkage_m(&CLAYEY_SOIL_38, 80_000.0, 1.0);
        let narrow = sinkage_m(&CLAYEY_SOIL_38, 80_000.0, 0.1);
        assert!(close(wide, (80.0_f64 / 705.34).powi(2), 1e-12), "{wide}");
        assert!(
            close(narrow, (80.0_f64 / 824.05).powi(2), 1e-12),
            "{narrow}"
        );
        assert!(wide > narrow);
        // Without a cohesive modulus the width does not matter.
        let frictional = SoilProperties {
            k_c_kn: 0.0,
            ..CLAYEY_SOIL_38
        };
        assert_eq!(
            sinkage_m(&frictional, 80_000.0, 1.0),
            sinkage_m(&frictional, 80_000.0, 0.1)
        );
        assert!(sinkage_m(&CLAYEY_SOIL_38, 90_000.0, 1.0) > wide);
        assert_eq!(sinkage_m(&CLAYEY_SOIL_38, 0.0, 1.0), 0.0);
        assert_eq!(sinkage_m(&CLAYEY_SOIL_38, -5.0, 1.0), 0.0);
        assert_eq!(sinkage_m(&CLAYEY_SOIL_38, f64::NAN, 1.0), 0.0);
        assert_eq!(sinkage_m(&CLAYEY_SOIL_38, 80_000.0, 0.0), 0.0);
    }

    #[test]
    fn contact_geometry_follows_the_gear_table() {
        let t = tank();
        assert_eq!(t.patches(), 2);
        // 2.3 m² per track at 5:1: b = sqrt(0.46) = 0.678 m, l = 3.39 m.
        assert!(close(t.contact_width_m(), 0.46_f64.sqrt(), 1e-12));
        assert!(close(t.contact_length_m(), 5.0 * 0.46_f64.sqrt(), 1e-12));
        assert!(close(
            t.contact_width_m() * t.contact_length_m() * 2.0,
            4.6,
            1e-12
        ));
        // 60 t on 4.6 m²: 127.9 kPa.
        assert!(close(
            t.ground_pressure_pa(),
            60_000.0 * G_MPS2 / 4.6,
            1e-12
        ));
        let s = soldier();
        assert!(close(s.contact_width_m(), 0.1, 1e-12));
        assert!(close(s.contact_length_m(), 0.3, 1e-12));
        assert_eq!(utility().patches(), 4);
        assert!(close(utility().contact_width_m(), 0.1_f64.sqrt(), 1e-12));
        let truck = VehicleLoad::new(15_000.0, 1.2, RunningGear::Wheeled).unwrap();
        assert_eq!(truck.patches(), 6);
        let heavy = VehicleLoad::new(30_000.0, 2.0, RunningGear::Wheeled).unwrap();
        assert_eq!(heavy.patches(), 8);
    }

    #[test]
    fn bad_loads_are_refused_with_a_message_naming_the_value() {
        for mass in [-1.0, 0.0, f64::NAN, f64::INFINITY, 2.0e6] {
            let err = VehicleLoad::new(mass, 1.0, RunningGear::Tracked).unwrap_err();
            assert!(err.to_string().starts_with("mass_kg must be"), "{err}");
            assert!(!err.to_string().contains('\n'));
        }
        for area in [-1.0, 0.0, 1e-9, f64::NAN, f64::NEG_INFINITY, 5.0e3] {
            let err = VehicleLoad::new(1_000.0, area, RunningGear::Wheeled).unwrap_err();
            assert!(
                err.to_string().starts_with("contact_area_m2 must be"),
                "{err}"
            );
        }
        assert_eq!(
            VehicleLoad::new(f64::NAN, 1.0, RunningGear::Foot)
                .unwrap_err()
                .to_string(),
            "mass_kg must be finite, above 0 and at most 1e6 kg, not NaN"
        );
    }

    #[test]
    fn a_tank_ruts_sand_deeper_than_dry_clay_and_not_paved_road() {
        let t = tank();
        let sand = rut_depth_m(Material::Sand, SoilMoisture::Dry, &t);
        let clay = rut_depth_m(Material::DryClay, SoilMoisture::Dry, &t);
        // Dry sand: k = 0.99 / 0.678 + 1528.43 = 1529.9; z = (127.9 / 1529.9)^(1/1.1) = 0.105 m.
        assert!(close(sand, 0.1048, 0.01), "{sand}");
        // Heavy clay at 25 %: n = 0.13 makes 127.9 kPa against k = 1574.7 sink nothing visible.
        assert!(clay < 1e-6, "{clay}");
        assert!(sand > clay);
        for hard in [Material::PavedRoad, Material::Rock, Material::Water] {
            assert_eq!(rut_depth_m(hard, SoilMoisture::Dry, &t), 0.0);
            assert_eq!(rut_depth_m(hard, SoilMoisture::Wet, &t), 0.0);
        }
    }

    #[test]
    fn wet_clays_loams_and_snow_rut_deeper_than_dry() {
        for load in [tank(), utility()] {
            for material in [
                Material::DryClay,
                Material::Grass,
                Material::Forest,
                Material::DirtRoad,
                Material::Snow,
            ] {
                let props_dry = properties(material, SoilMoisture::Dry).unwrap();
                let props_wet = properties(material, SoilMoisture::Wet).unwrap();
                let p = load.ground_pressure_pa();
                let b = load.contact_width_m();
                let dry = sinkage_m(&props_dry, p, b);
                let wet = sinkage_m(&props_wet, p, b);
                assert!(wet > dry, "{material}: wet {wet} dry {dry} for {load:?}");
                assert!(
                    rut_depth_m(material, SoilMoisture::Wet, &load)
                        >= rut_depth_m(material, SoilMoisture::Dry, &load)
                );
            }
        }
        // The tank in wet heavy clay sinks to its belly: the rut is capped at its clearance.
        assert_eq!(
            rut_depth_m(Material::DryClay, SoilMoisture::Wet, &tank()),
            RunningGear::Tracked.ground_clearance_m()
        );
    }

    #[test]
    fn moist_sand_is_firmer_than_dry_sand() {
        // The documented choice: wet sand takes the moist sandy-loam row.
        let t = tank();
        assert!(
            rut_depth_m(Material::Sand, SoilMoisture::Wet, &t)
                < rut_depth_m(Material::Sand, SoilMoisture::Dry, &t)
        );
    }

    #[test]
    fn a_light_vehicle_goes_on_dry_clay_and_a_tank_bogs_in_wet_clay() {
        let light = trafficability(Material::DryClay, SoilMoisture::Dry, &utility());
        assert!(light.trafficable, "{light:?}");
        assert_eq!(light.reason, REASON_GO);
        assert!(light.resistance_n < light.max_thrust_n);
        // Wet heavy clay (WES, 40 %): k = 1.84 / 0.678 + 103.27 = 105.98 kN/m^2.11 against
        // 127.9 kPa gives z = 1.207^(1/0.11) = 5.5 m: the tank is high-centred.
        let bogged = trafficability(Material::DryClay, SoilMoisture::Wet, &tank());
        assert!(!bogged.trafficable, "{bogged:?}");
        assert_eq!(bogged.reason, REASON_HIGH_CENTRED);
        let raw = sinkage_m(
            &HEAVY_CLAY_40,
            tank().ground_pressure_pa(),
            tank().contact_width_m(),
        );
        assert!(close(raw, 5.53, 0.02), "{raw}");
        // The same wet clay carries the light vehicle (61 kPa on 0.32 m patches sinks 5 mm).
        let light_wet = trafficability(Material::DryClay, SoilMoisture::Wet, &utility());
        assert!(light_wet.trafficable, "{light_wet:?}");
        assert!(light_wet.sinkage_m < 0.01);
        // And the tank crosses dry sand (0.1 m) and dry clay.
        assert!(trafficability(Material::Sand, SoilMoisture::Dry, &tank()).trafficable);
        assert!(trafficability(Material::DryClay, SoilMoisture::Dry, &tank()).trafficable);
    }

    #[test]
    fn water_and_hard_ground() {
        let w = trafficability(Material::Water, SoilMoisture::Dry, &tank());
        assert!(!w.trafficable);
        assert_eq!(w.reason, "water");
        let road = trafficability(Material::PavedRoad, SoilMoisture::Wet, &tank());
        assert!(road.trafficable);
        assert_eq!(road.sinkage_m, 0.0);
        assert_eq!(road.resistance_n, 0.0);
        assert!(close(road.max_thrust_n, 0.5 * 60_000.0 * G_MPS2, 1e-12));
        let rock = trafficability(Material::Rock, SoilMoisture::Dry, &soldier());
        assert!(rock.trafficable);
        assert!(close(rock.max_thrust_n, 0.75 * 80.0 * G_MPS2, 1e-12));
        assert_eq!(properties(Material::Water, SoilMoisture::Wet), None);
        assert_eq!(properties(Material::Rock, SoilMoisture::Wet), None);
        assert_eq!(properties(Material::PavedRoad, SoilMoisture::Dry), None);
    }

    #[test]
    fn thrust_and_resistance_match_their_formulas() {
        let t = tank();
        // Dry sand: H = 4.6 m² * 1.04 kPa + 588.4 kN * tan 28° = 4.784 + 312.85 kN.
        let h = max_thrust_n(&DRY_SAND, &t);
        let expected = 4.6 * 1040.0 + 60_000.0 * G_MPS2 * 28.0_f64.to_radians().tan();
        assert!(close(h, expected, 1e-12));
        assert!(close(h, 317_640.0, 1e-3), "{h}");
        let v = trafficability(Material::Sand, SoilMoisture::Dry, &t);
        let per_track = compaction_resistance_n(&DRY_SAND, t.contact_width_m(), v.sinkage_m);
        assert!(close(v.resistance_n, 2.0 * per_track, 1e-12));
        assert!(
            v.resistance_n > 1_000.0 && v.resistance_n < 20_000.0,
            "{v:?}"
        );
    }

    #[test]
    fn no_thrust_rule_stops_a_vehicle_on_frictionless_soft_soil() {
        // A soil with no cohesion and almost no friction: nothing to push against.
        let slick = SoilProperties {
            name: "test slurry",
            cohesion_kpa: 0.0,
            friction_angle_deg: 0.5,
            ..CLAYEY_SOIL_38
        };
        let v = assess(Material::Forest, &slick, &utility());
        assert!(v.sinkage_m < RunningGear::Wheeled.ground_clearance_m());
        assert!(v.resistance_n >= v.max_thrust_n, "{v:?}");
        assert!(!v.trafficable);
        assert_eq!(v.reason, REASON_NO_THRUST);
    }

    #[test]
    fn janosi_shear_builds_up_to_mohr_coulomb() {
        let sigma_pa = 100_000.0;
        let full = DRY_SAND.cohesion_kpa * 1000.0 + sigma_pa * 28.0_f64.to_radians().tan();
        assert_eq!(shear_stress_pa(&DRY_SAND, sigma_pa, 0.0), 0.0);
        // At j = K the stress is 1 - 1/e of its maximum.
        let at_k = shear_stress_pa(&DRY_SAND, sigma_pa, 0.025);
        assert!(close(at_k, full * (1.0 - (-1.0_f64).exp()), 1e-12));
        assert!(close(
            shear_stress_pa(&DRY_SAND, sigma_pa, 10.0),
            full,
            1e-9
        ));
        let t = tank();
        assert_eq!(thrust_at_slip_n(&DRY_SAND, &t, 0.0), 0.0);
        let low = thrust_at_slip_n(&DRY_SAND, &t, 0.05);
        let high = thrust_at_slip_n(&DRY_SAND, &t, 1.0);
        assert!(0.0 < low && low < high && high < max_thrust_n(&DRY_SAND, &t));
        assert!(high > 0.99 * max_thrust_n(&DRY_SAND, &t));
    }

    #[test]
    fn every_table_row_is_usable() {
        for row in [
            DRY_SAND,
            SANDY_LOAM_15,
            SANDY_LOAM_26,
            CLAYEY_SOIL_38,
            CLAYEY_SOIL_55,
            HEAVY_CLAY_25,
            HEAVY_CLAY_40,
            LEAN_CLAY_22,
            LEAN_CLAY_32,
            LETE_SAND,
            SNOW_US,
            SNOW_SWEDEN,
        ] {
            assert!(row.is_usable(), "{}", row.name);
        }
        let broken = SoilProperties { n: 0.0, ..DRY_SAND };
        assert!(!broken.is_usable());
        assert_eq!(sinkage_m(&broken, 50_000.0, 0.5), 0.0);
    }

    proptest! {
        #[test]
        fn loads_never_panic_and_valid_ones_give_finite_verdicts(
            mass in proptest::num::f64::ANY,
            area in proptest::num::f64::ANY,
            gear in prop_oneof![
                Just(RunningGear::Tracked),
                Just(RunningGear::Wheeled),
                Just(RunningGear::Foot)
            ],
        ) {
            if let Ok(load) = VehicleLoad::new(mass, area, gear) {
                for material in Material::ALL {
                    for moisture in [SoilMoisture::Dry, SoilMoisture::Wet] {
                        let v = trafficability(material, moisture, &load);
                        prop_assert!(v.sinkage_m.is_finite() && v.sinkage_m >= 0.0);
                        prop_assert!(v.sinkage_m <= gear.ground_clearance_m());
                        prop_assert!(v.resistance_n.is_finite() && v.resistance_n >= 0.0);
                        prop_assert!(v.max_thrust_n.is_finite() && v.max_thrust_n >= 0.0);
                    }
                }
            }
        }

        #[test]
        fn sinkage_is_never_nan(
            pressure in proptest::num::f64::ANY,
            width in proptest::num::f64::ANY,
        ) {
            for row in [DRY_SAND, HEAVY_CLAY_40, SNOW_US] {
                let z = sinkage_m(&row, pressure, width);
                prop_assert!(!z.is_nan() && z >= 0.0);
            }
        }
    }
}
