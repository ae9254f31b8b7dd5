//! The atmosphere in the infrared: band transmittance and path radiance of a line of sight.
//!
//! Algorithm: a table generated offline from LOWTRAN 7 (the source's own attenuation model,
//! source 001, "Atmospheric Attenuation": LOWTRAN with the maritime aerosol) by
//! `tools/lowtran/generate_ir_table.py`, stored in `data/ir_atmosphere.txt` and compiled in.
//! It holds, for the 8-12 and 3-5 um bands and horizontal sea-level paths of 0.05-50 km:
//! - the gases' band-mean transmittance (water-vapour lines and continuum, CO2, O3 and the
//!   other uniformly mixed gases, at 1013.25 hPa) over air temperature -40..40 C and relative
//!   humidity 0-100 %, and the Planck-weighted transmittance at the air temperature;
//! - the aerosol's band-mean transmittance for LOWTRAN's rural (IHAZE 1), maritime (4) and
//!   urban (5) models over visibility 1-50 km and relative humidity 0-99 %.
//!
//! A path's transmittance is the product of the two, interpolated (trilinear in temperature,
//! humidity and log range). Raised and slant paths are reduced to sea-level-equivalent
//! amounts: the dry gases follow the standard atmosphere's density (lapse 6.5 K/km), water
//! vapour falls with a 2 km scale height and aerosol with a 1.2 km one. The path radiance of
//! the (nearly isothermal) path is `L_band(T) (1 - tau_planck)`, with aerosol extinction
//! counted as emitting. Visibilities outside 1-50 km scale the range (the aerosol's optical
//! depth goes as 1 / visibility, Koschmieder).
//!
//! Limits: the band-mean product of gas and aerosol is not the band mean of the spectral
//! product (the aerosol is nearly grey in each band, so the error is about 0.01); pressure
//! broadening on raised paths is not modelled (amounts only); one temperature per path for
//! the radiance; no multiple scattering of sunlight into the path in MWIR.

use crate::planck::{band_radiance_unchecked, Band};
use crate::weather::saturation_vapour_pressure_hpa;
use crate::ThermalError;
use std::sync::OnceLock;

/// The two sensor bands of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IrBand {
    /// 8-12 um.
    Lwir,
    /// 3-5 um.
    Mwir,
}

impl IrBand {
    /// The band's wavelengths.
    pub fn band(self) -> Band {
        match self {
            IrBand::Lwir => Band::LWIR,
            IrBand::Mwir => Band::MWIR,
        }
    }

    /// `8-12` or `3-5` (also `lwir`, `mwir`).
    pub fn parse(text: &str) -> Result<IrBand, ThermalError> {
        match text.trim() {
            "lwir" | "LWIR" => return Ok(IrBand::Lwir),
            "mwir" | "MWIR" => return Ok(IrBand::Mwir),
            _ => {}
        }
        let band = Band::parse(text)?;
        if band == Band::LWIR {
            Ok(IrBand::Lwir)
        } else if band == Band::MWIR {
            Ok(IrBand::Mwir)
        } else {
            Err(ThermalError::UnsupportedBand(text.to_string()))
        }
    }

    fn index(self) -> usize {
        match self {
            IrBand::Lwir => 0,
            IrBand::Mwir => 1,
        }
    }
}

/// Aerosol models (LOWTRAN 7's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aerosol {
    /// No aerosol: gases only.
    None,
    /// Continental rural (IHAZE 1).
    Rural,
    /// Maritime (IHAZE 4).
    Maritime,
    /// Urban (IHAZE 5).
    Urban,
}

impl Aerosol {
    /// Parses none, rural, maritime, urban.
    pub fn from_name(name: &str) -> Result<Aerosol, ThermalError> {
        match name {
            "none" => Ok(Aerosol::None),
            "rural" => Ok(Aerosol::Rural),
            "maritime" => Ok(Aerosol::Maritime),
            "urban" => Ok(Aerosol::Urban),
            _ => Err(ThermalError::UnknownName {
                what: "aerosol model",
                name: name.to_string(),
                expected: "none, rural, maritime, urban",
            }),
        }
    }

    /// LOWTRAN's default visibility of the model, metres (23 km, urban 5 km).
    pub fn default_visibility_m(self) -> f64 {
        match self {
            Aerosol::Urban => 5_000.0,
            _ => 23_000.0,
        }
    }

    fn table_index(self) -> Option<usize> {
        match self {
            Aerosol::None => None,
            Aerosol::Rural => Some(0),
            Aerosol::Maritime => Some(1),
            Aerosol::Urban => Some(2),
        }
    }
}

/// The six standard model atmospheres at sea level (AFGL, Anderson et al. 1986, as in
/// LOWTRAN 7): temperature and water-vapour density.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelAtmosphere {
    Tropical,
    MidLatitudeSummer,
    MidLatitudeWinter,
    SubarcticSummer,
    SubarcticWinter,
    UsStandard,
}

impl ModelAtmosphere {
    /// All six, in LOWTRAN's order (MODEL 1..6).
    pub const ALL: [ModelAtmosphere; 6] = [
        ModelAtmosphere::Tropical,
        ModelAtmosphere::MidLatitudeSummer,
        ModelAtmosphere::MidLatitudeWinter,
        ModelAtmosphere::SubarcticSummer,
        ModelAtmosphere::SubarcticWinter,
        ModelAtmosphere::UsStandard,
    ];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            ModelAtmosphere::Tropical => "tropical",
            ModelAtmosphere::MidLatitudeSummer => "mid-latitude-summer",
            ModelAtmosphere::MidLatitudeWinter => "mid-latitude-winter",
            ModelAtmosphere::SubarcticSummer => "subarctic-summer",
            ModelAtmosphere::SubarcticWinter => "subarctic-winter",
            ModelAtmosphere::UsStandard => "us-standard",
        }
    }

    /// Parses a name of [`ModelAtmosphere::name`].
    pub fn from_name(name: &str) -> Result<ModelAtmosphere, ThermalError> {
        ModelAtmosphere::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| ThermalError::UnknownName {
                what: "model atmosphere",
                name: name.to_string(),
                expected: "us-standard, tropical, mid-latitude-summer, mid-latitude-winter, \
                           subarctic-summer, subarctic-winter",
            })
    }

    /// Sea-level air temperature, kelvin, and water-vapour density, g/m3.
    pub fn sea_level(self) -> (f64, f64) {
        match self {
            ModelAtmosphere::Tropical => (299.7, 19.0),
            ModelAtmosphere::MidLatitudeSummer => (294.2, 14.0),
            ModelAtmosphere::MidLatitudeWinter => (272.2, 3.5),
            ModelAtmosphere::SubarcticSummer => (287.2, 9.1),
            ModelAtmosphere::SubarcticWinter => (257.2, 1.2),
            ModelAtmosphere::UsStandard => (288.2, 5.9),
        }
    }

    /// Sea-level relative humidity, percent (from the density and the saturation pressure).
    pub fn relative_humidity_pct(self) -> f64 {
        let (t, rho) = self.sea_level();
        relative_humidity_from_density(t, rho)
    }
}

/// Gas constant of water vapour, J kg-1 K-1.
const WATER_GAS_CONSTANT: f64 = 461.5;

/// Relative humidity (percent) of air at `temp_k` holding `density_g_m3` of water vapour.
pub fn relative_humidity_from_density(temp_k: f64, density_g_m3: f64) -> f64 {
    let e_hpa = density_g_m3 * 1e-3 * WATER_GAS_CONSTANT * temp_k / 100.0;
    100.0 * e_hpa / saturation_vapour_pressure_hpa(temp_k)
}

/// Water-vapour density (g/m3) of air at `temp_k` and relative humidity `rh_pct`.
pub fn water_density_g_m3(temp_k: f64, rh_pct: f64) -> f64 {
    let e_pa = saturation_vapour_pressure_hpa(temp_k) * 100.0 * rh_pct / 100.0;
    e_pa / (WATER_GAS_CONSTANT * temp_k) * 1e3
}

/// The air a line of sight crosses, at sea level (or the ground the heights count from).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrAtmosphere {
    /// Air temperature at the base, kelvin.
    pub air_k: f64,
    /// Relative humidity at the base, percent.
    pub relative_humidity_pct: f64,
    /// The aerosol model.
    pub aerosol: Aerosol,
    /// Meteorological range (visibility) for the aerosol, metres.
    pub visibility_m: f64,
}

/// What a path does to the radiance crossing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptics {
    /// Band-mean transmittance, 0..1.
    pub transmittance: f64,
    /// Radiance the path itself emits toward the sensor, W m-2 sr-1.
    pub path_radiance_w_m2_sr: f64,
}

/// Scale heights and lapse rate of the raised-path reduction.
const WATER_SCALE_HEIGHT_M: f64 = 2_000.0;
const AEROSOL_SCALE_HEIGHT_M: f64 = 1_200.0;
const LAPSE_K_PER_M: f64 = 0.0065;

impl IrAtmosphere {
    /// The sea-level state of a model atmosphere with an aerosol at its default visibility.
    pub fn model(model: ModelAtmosphere, aerosol: Aerosol) -> IrAtmosphere {
        IrAtmosphere {
            air_k: model.sea_level().0,
            relative_humidity_pct: model.relative_humidity_pct(),
            aerosol,
            visibility_m: aerosol.default_visibility_m(),
        }
    }

    /// Checks the ranges: temperature 200-330 K, humidity 0-100 %, visibility > 0.
    pub fn validate(&self) -> Result<(), ThermalError> {
        let checks: [(&'static str, f64, bool, &'static str); 3] = [
            (
                "air temperature (K)",
                self.air_k,
                (200.0..=330.0).contains(&self.air_k),
                "200..330 K (-73..57 C)",
            ),
            (
                "relative humidity",
                self.relative_humidity_pct,
                (0.0..=100.0).contains(&self.relative_humidity_pct),
                "0..100 %",
            ),
            (
                "visibility (m)",
                self.visibility_m,
                self.visibility_m > 0.0 && self.visibility_m.is_finite(),
                "above 0 m",
            ),
        ];
        for (name, value, ok, expected) in checks {
            if !ok || !value.is_finite() {
                return Err(ThermalError::OutOfRange {
                    name,
                    value,
                    expected,
                });
            }
        }
        Ok(())
    }

    /// A horizontal path of `range_m` at `altitude_m` above the base.
    pub fn horizontal(
        &self,
        band: IrBand,
        range_m: f64,
        altitude_m: f64,
    ) -> Result<PathOptics, ThermalError> {
        self.slant(band, altitude_m, altitude_m, range_m)
    }

    /// A straight path of `range_m` from `from_altitude_m` to `to_altitude_m` (heights above
    /// the base; the range is the slant length, at least the height difference).
    pub fn slant(
        &self,
        band: IrBand,
        from_altitude_m: f64,
        to_altitude_m: f64,
        range_m: f64,
    ) -> Result<PathOptics, ThermalError> {
        self.validate()?;
        if !(range_m.is_finite() && range_m >= 0.0) {
            return Err(ThermalError::OutOfRange {
                name: "range (m)",
                value: range_m,
                expected: "0 m or more",
            });
        }
        for h in [from_altitude_m, to_altitude_m] {
            if !(h.is_finite() && (-500.0..=30_000.0).contains(&h)) {
                return Err(ThermalError::OutOfRange {
                    name: "altitude (m)",
                    value: h,
                    expected: "-500..30000 m",
                });
            }
        }
        Ok(self.slant_unchecked(band, from_altitude_m, to_altitude_m, range_m))
    }

    /// [`IrAtmosphere::slant`] for inputs the caller has checked (the renderer's rays).
    pub fn slant_unchecked(
        &self,
        band: IrBand,
        from_altitude_m: f64,
        to_altitude_m: f64,
        range_m: f64,
    ) -> PathOptics {
        let table = table();
        let rho_w0 = water_density_g_m3(self.air_k, self.relative_humidity_pct);
        // Sea-level-equivalent amounts by the midpoint rule over 16 segments.
        const SEGMENTS: usize = 16;
        let (mut dry_m, mut water_g_m2, mut aerosol_m, mut t_weighted) = (0.0, 0.0, 0.0, 0.0);
        for s in 0..SEGMENTS {
            let f = (s as f64 + 0.5) / SEGMENTS as f64;
            let h = from_altitude_m + (to_altitude_m - from_altitude_m) * f;
            let dl = range_m / SEGMENTS as f64;
            let t = (self.air_k - LAPSE_K_PER_M * h).max(180.0);
            let pressure_ratio = (t / self.air_k).powf(5.255_9);
            let density_ratio = pressure_ratio * self.air_k / t;
            dry_m += dl * density_ratio;
            water_g_m2 += dl * rho_w0 * (-h / WATER_SCALE_HEIGHT_M).exp();
            aerosol_m += dl * (-h / AEROSOL_SCALE_HEIGHT_M).exp();
            t_weighted += dl * density_ratio * t;
        }
        let t_path = if dry_m > 0.0 {
            t_weighted / dry_m
        } else {
            self.air_k
        };
        let rh_path = if dry_m > 0.0 {
            relative_humidity_from_density(t_path, water_g_m2 / dry_m).clamp(0.0, 100.0)
        } else {
            self.relative_humidity_pct
        };
        let b = band.index();
        let (gas_mean, gas_planck) = table.gas(b, t_path, rh_path, dry_m / 1000.0);
        let aerosol = match self.aerosol.table_index() {
            None => 1.0,
            Some(a) => table.aerosol(
                b,
                a,
                self.visibility_m / 1000.0,
                self.relative_humidity_pct,
                aerosol_m / 1000.0,
            ),
        };
        let transmittance = (gas_mean * aerosol).clamp(0.0, 1.0);
        let emitting = (gas_planck * aerosol).clamp(0.0, 1.0);
        PathOptics {
            transmittance,
            path_radiance_w_m2_sr: band_radiance_unchecked(band.band(), t_path) * (1.0 - emitting),
        }
    }
}

/// The parsed LOWTRAN table.
struct IrTable {
    temps_k: Vec<f64>,
    rh_gas: Vec<f64>,
    ln_ranges: Vec<f64>,
    ranges_km: Vec<f64>,
    vis_km: Vec<f64>,
    ln_vis: Vec<f64>,
    rh_aerosol: Vec<f64>,
    /// [band][t][rh] -> (mean along range, planck along range)
    gas: Vec<(Vec<f64>, Vec<f64>)>,
    /// [band][aerosol][vis][rh] -> along range
    aerosol: Vec<Vec<f64>>,
}

const TABLE_TEXT: &str = include_str!("../data/ir_atmosphere.txt");

fn table() -> &'static IrTable {
    static TABLE: OnceLock<IrTable> = OnceLock::new();
    TABLE.get_or_init(|| parse_table(TABLE_TEXT).expect("the compiled-in IR table parses"))
}

fn numbers(fields: &[&str]) -> Result<Vec<f64>, String> {
    fields
        .iter()
        .map(|f| f.parse::<f64>().map_err(|e| format!("{f:?}: {e}")))
        .collect()
}

fn parse_table(text: &str) -> Result<IrTable, String> {
    let mut axes: std::collections::HashMap<&str, Vec<f64>> = Default::default();
    let mut gas_lines = Vec::new();
    let mut aerosol_lines = Vec::new();
    for line in text.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.first().copied() {
            None | Some("#") | Some("bands") | Some("aerosols") => {}
            Some("gas") => gas_lines.push(fields),
            Some("aerosol") => aerosol_lines.push(fields),
            Some(axis) => {
                axes.insert(axis, numbers(&fields[1..])?);
            }
        }
    }
    let axis = |name: &str| axes.get(name).cloned().ok_or(format!("no {name} axis"));
    let temps_k = axis("temps_k")?;
    let rh_gas = axis("rh_gas")?;
    let ranges_km = axis("ranges_km")?;
    let vis_km = axis("vis_km")?;
    let rh_aerosol = axis("rh_aerosol")?;
    let n_range = ranges_km.len();
    let mut gas = Vec::new();
    for pair in gas_lines.chunks(2) {
        let [mean, planck] = pair else {
            return Err("odd number of gas lines".into());
        };
        let m = numbers(&mean[5..])?;
        let p = numbers(&planck[5..])?;
        if m.len() != n_range || p.len() != n_range {
            return Err("gas line of the wrong length".into());
        }
        gas.push((m, p));
    }
    if gas.len() != 2 * temps_k.len() * rh_gas.len() {
        return Err(format!("{} gas rows", gas.len()));
    }
    let mut aerosol = Vec::new();
    for line in aerosol_lines {
        let v = numbers(&line[5..])?;
        if v.len() != n_range {
            return Err("aerosol line of the wrong length".into());
        }
        aerosol.push(v);
    }
    if aerosol.len() != 2 * 3 * vis_km.len() * rh_aerosol.len() {
        return Err(format!("{} aerosol rows", aerosol.len()));
    }
    Ok(IrTable {
        temps_k,
        rh_gas,
        ln_ranges: ranges_km.iter().map(|r| r.ln()).collect(),
        ranges_km,
        ln_vis: vis_km.iter().map(|v| v.ln()).collect(),
        vis_km,
        rh_aerosol,
        gas,
        aerosol,
    })
}

/// Index and weight of `x` between the grid's points (clamped to the ends).
fn bracket(grid: &[f64], x: f64) -> (usize, f64) {
    if x.is_nan() || x <= grid[0] {
        return (0, 0.0);
    }
    let last = grid.len() - 1;
    if x >= grid[last] {
        return (last - 1, 1.0);
    }
    let i = grid.partition_point(|g| *g <= x) - 1;
    (i, (x - grid[i]) / (grid[i + 1] - grid[i]))
}

impl IrTable {
    /// Transmittance along range from one row: 1 at 0 km, linear to the first point,
    /// linear in log range between points, grey (a power) beyond the last.
    fn along_range(&self, row: &[f64], range_km: f64) -> f64 {
        if range_km.is_nan() || range_km <= 0.0 {
            return 1.0;
        }
        let first = self.ranges_km[0];
        if range_km < first {
            return 1.0 + (row[0] - 1.0) * range_km / first;
        }
        let last = self.ranges_km.len() - 1;
        if range_km > self.ranges_km[last] {
            return row[last].max(0.0).powf(range_km / self.ranges_km[last]);
        }
        let (i, w) = bracket(&self.ln_ranges, range_km.ln());
        row[i] * (1.0 - w) + row[i + 1] * w
    }

    fn gas(&self, band: usize, t_k: f64, rh: f64, range_km: f64) -> (f64, f64) {
        let (ti, tw) = bracket(&self.temps_k, t_k);
        let (ri, rw) = bracket(&self.rh_gas, rh);
        let n_rh = self.rh_gas.len();
        let base = band * self.temps_k.len() * n_rh;
        let (mut mean, mut planck) = (0.0, 0.0);
        for (dt, wt) in [(0, 1.0 - tw), (1, tw)] {
            for (dr, wr) in [(0, 1.0 - rw), (1, rw)] {
                let w = wt * wr;
                if w == 0.0 {
                    continue;
                }
                let (m, p) = &self.gas[base + (ti + dt) * n_rh + ri + dr];
                mean += w * self.along_range(m, range_km);
                planck += w * self.along_range(p, range_km);
            }
        }
        (mean, planck)
    }

    fn aerosol(&self, band: usize, model: usize, vis_km: f64, rh: f64, range_km: f64) -> f64 {
        // Outside the visibility grid, the optical depth scales as 1 / visibility: the range
        // is scaled instead.
        let lo = self.vis_km[0];
        let hi = self.vis_km[self.vis_km.len() - 1];
        let (vis, range_km) = if vis_km < lo {
            (lo, range_km * lo / vis_km)
        } else if vis_km > hi {
            (hi, range_km * hi / vis_km)
        } else {
            (vis_km, range_km)
        };
        let (vi, vw) = bracket(&self.ln_vis, vis.ln());
        let (ri, rw) = bracket(&self.rh_aerosol, rh);
        let n_rh = self.rh_aerosol.len();
        let base = (band * 3 + model) * self.vis_km.len() * n_rh;
        let mut t = 0.0;
        for (dv, wv) in [(0, 1.0 - vw), (1, vw)] {
            for (dr, wr) in [(0, 1.0 - rw), (1, rw)] {
                let w = wv * wr;
                if w == 0.0 {
                    continue;
                }
                t += w * self
                    .along_range(&self.aerosol[base + (vi + dv) * n_rh + ri + dr], range_km);
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_compiled_table_parses() {
        let t = table();
        assert_eq!(t.temps_k.len(), 9);
        assert_eq!(t.gas.len(), 2 * 9 * 9);
    }

    #[test]
    fn transmittance_falls_with_range_humidity_and_aerosol() {
        let us = IrAtmosphere::model(ModelAtmosphere::UsStandard, Aerosol::None);
        let mut last = 1.0;
        for r in [0.0, 10.0, 100.0, 1000.0, 5000.0, 20_000.0, 80_000.0] {
            let p = us.horizontal(IrBand::Lwir, r, 0.0).expect("valid");
            assert!(p.transmittance <= last + 1e-12, "{r}: {p:?}");
            last = p.transmittance;
        }
        let at_5_km = |a: IrAtmosphere| {
            a.horizontal(IrBand::Lwir, 5000.0, 0.0)
                .expect("valid")
                .transmittance
        };
        let td = at_5_km(IrAtmosphere::model(
            ModelAtmosphere::SubarcticWinter,
            Aerosol::None,
        ));
        let tw = at_5_km(IrAtmosphere::model(
            ModelAtmosphere::Tropical,
            Aerosol::None,
        ));
        assert!(td > tw + 0.3, "{td} vs {tw}");
        let th = at_5_km(IrAtmosphere {
            visibility_m: 2000.0,
            ..IrAtmosphere::model(ModelAtmosphere::UsStandard, Aerosol::Urban)
        });
        let tc = at_5_km(us);
        assert!(th < tc - 0.05, "{th} vs {tc}");
    }

    #[test]
    fn raised_paths_are_clearer_and_path_radiance_is_bounded_by_the_air() {
        let a = IrAtmosphere::model(ModelAtmosphere::MidLatitudeSummer, Aerosol::Rural);
        let low = a.horizontal(IrBand::Lwir, 10_000.0, 0.0).expect("v");
        let high = a.horizontal(IrBand::Lwir, 10_000.0, 3000.0).expect("v");
        let slant = a.slant(IrBand::Lwir, 0.0, 3000.0, 10_000.0).expect("v");
        assert!(high.transmittance > slant.transmittance);
        assert!(slant.transmittance > low.transmittance);
        let air = band_radiance_unchecked(Band::LWIR, a.air_k);
        assert!(low.path_radiance_w_m2_sr > 0.0 && low.path_radiance_w_m2_sr < air);
        // Long paths emit nearly as a black body at the air's temperature.
        let long = a.horizontal(IrBand::Lwir, 200_000.0, 0.0).expect("v");
        assert!(
            (long.path_radiance_w_m2_sr - air).abs() / air < 0.05,
            "{long:?} {air}"
        );
    }

    #[test]
    fn bad_values_are_refused() {
        let a = IrAtmosphere::model(ModelAtmosphere::UsStandard, Aerosol::None);
        assert!(a.horizontal(IrBand::Lwir, -1.0, 0.0).is_err());
        let wet = IrAtmosphere {
            relative_humidity_pct: 101.0,
            ..a
        };
        assert!(wet.horizontal(IrBand::Lwir, 1.0, 0.0).is_err());
        assert!(IrBand::parse("8-14").is_err());
        assert!(Aerosol::from_name("volcanic").is_err());
        assert!(ModelAtmosphere::from_name("martian").is_err());
        assert_eq!(IrBand::parse("3-5").expect("b"), IrBand::Mwir);
    }
}
