//! A layered slab as an RC network, advanced by implicit Euler steps.
//!
//! Algorithm: the source's network of nodes through a plate (source 001, Figure 4: eight nodes
//! and "eight first-order linear difference equations"), generalised. Each layer is divided
//! into cells (equal, or growing geometrically with depth); nodes sit on the cell faces, so the
//! first node is the surface itself. A node's capacitance is half of each neighbouring cell's
//! `rho c dz`; the conductance between two nodes is the cell's `k / dz`. The inner boundary is
//! a fixed deep-ground temperature (the last face is not a node), or a film to a constant
//! interior, or air again (the back face of a leaf).
//!
//! The surface's energy balance (W m-2, positive into the surface):
//! `alpha S + eps L_down - eps sigma T^4 - h (T - T_air) - w h (L_v / c_p) (q_s(T) - q_air)`,
//! absorbed sunlight, absorbed long-wave, emission, convection and evaporation (the Lewis
//! analogy: the mass-transfer coefficient is `h / c_p`; `w` is the material's wetness). Each
//! step linearises emission and `q_s` about the current surface temperature and solves the
//! tridiagonal system by the Thomas algorithm: unconditionally stable, so a step may be a
//! frame (1/60 s) or a minute of the spin-up.
//!
//! Limits: 1-D conduction only (no lateral flow between orientations or materials); properties
//! do not change with temperature; a melting cap rather than a phase change with latent heat.

use crate::material::{InnerBoundary, MaterialProperties};
use crate::planck::STEFAN_BOLTZMANN;
use crate::weather::{saturation_specific_humidity, AIR_SPECIFIC_HEAT_J_KG_K, LATENT_HEAT_J_KG};

/// What the surroundings do to a surface during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceForcing {
    /// Sunlight (direct, diffuse and ground-reflected) arriving on the surface, W m-2.
    pub incident_shortwave_w_m2: f64,
    /// Long-wave irradiance arriving on the surface (sky and ground), W m-2.
    pub incident_longwave_w_m2: f64,
    /// Air temperature, kelvin.
    pub air_k: f64,
    /// Specific humidity of the air, kg/kg.
    pub air_specific_humidity: f64,
    /// Convective film coefficient, W m-2 K-1.
    pub convection_w_m2_k: f64,
    /// The deep-ground temperature at the base of terrain slabs, kelvin.
    pub deep_ground_k: f64,
}

/// A slab's nodes and their state.
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    /// Node temperatures, kelvin, surface first.
    temps_k: Vec<f64>,
    /// Node capacitances, J m-2 K-1.
    capacity: Vec<f64>,
    /// Conductance from node i to node i + 1 (for a deep-ground slab, the last one reaches the
    /// fixed base), W m-2 K-1.
    conductance: Vec<f64>,
    absorptivity: f64,
    emissivity: f64,
    wetness: f64,
    convection_factor: f64,
    melts_at_k: Option<f64>,
    inner: InnerBoundary,
    // Scratch for the solver.
    sub: Vec<f64>,
    diag: Vec<f64>,
    sup: Vec<f64>,
    rhs: Vec<f64>,
}

impl Slab {
    /// A slab of `material` with every node at `initial_k`.
    pub fn new(material: &MaterialProperties, initial_k: f64) -> Slab {
        let mut cells: Vec<(f64, f64, f64)> = Vec::new(); // (dz, k, rho c)
        for layer in material.layers {
            let n = layer.cells.max(1);
            let g = layer.growth.max(1.0);
            let total_weight: f64 = (0..n).map(|i| g.powi(i as i32)).sum();
            for i in 0..n {
                let dz = layer.thickness_m * g.powi(i as i32) / total_weight;
                cells.push((
                    dz,
                    layer.conductivity_w_m_k,
                    layer.density_kg_m3 * layer.specific_heat_j_kg_k,
                ));
            }
        }
        let fixed_base = matches!(material.inner, InnerBoundary::DeepGround);
        let nodes = if fixed_base {
            cells.len()
        } else {
            cells.len() + 1
        };
        let mut capacity = vec![0.0; nodes];
        let mut conductance = Vec::with_capacity(cells.len());
        for (i, &(dz, k, rho_c)) in cells.iter().enumerate() {
            capacity[i] += 0.5 * rho_c * dz;
            if i + 1 < nodes {
                capacity[i + 1] += 0.5 * rho_c * dz;
            }
            conductance.push(k / dz);
        }
        Slab {
            temps_k: vec![initial_k; nodes],
            capacity,
            conductance,
            absorptivity: material.solar_absorptivity,
            emissivity: material.emissivity_lwir,
            wetness: material.wetness,
            convection_factor: material.convection_factor,
            melts_at_k: material.melts_at_k,
            inner: material.inner,
            sub: vec![0.0; nodes],
            diag: vec![0.0; nodes],
            sup: vec![0.0; nodes],
            rhs: vec![0.0; nodes],
        }
    }

    /// Sets the nodes on a straight line from `surface_k` to `base_k` (a start before spin-up).
    pub fn set_linear_profile(&mut self, surface_k: f64, base_k: f64) {
        let n = self.temps_k.len();
        for (i, t) in self.temps_k.iter_mut().enumerate() {
            let f = if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.0
            };
            *t = surface_k + (base_k - surface_k) * f;
        }
    }

    /// The surface temperature, kelvin.
    pub fn surface_k(&self) -> f64 {
        self.temps_k[0]
    }

    /// Every node's temperature, kelvin, surface first.
    pub fn temperatures_k(&self) -> &[f64] {
        &self.temps_k
    }

    /// Heat stored per unit area above `reference_k`, J m-2 (for energy checks).
    pub fn stored_energy_j_m2(&self, reference_k: f64) -> f64 {
        self.temps_k
            .iter()
            .zip(&self.capacity)
            .map(|(t, c)| c * (t - reference_k))
            .sum()
    }

    /// Advances the slab by `dt_s` seconds under `forcing` (one implicit Euler step).
    pub fn step(&mut self, dt_s: f64, forcing: &SurfaceForcing) {
        if dt_s <= 0.0 {
            return;
        }
        let n = self.temps_k.len();
        for i in 0..n {
            let c_dt = self.capacity[i] / dt_s;
            self.diag[i] = c_dt;
            self.rhs[i] = c_dt * self.temps_k[i];
            self.sub[i] = 0.0;
            self.sup[i] = 0.0;
        }
        // Conduction between nodes, and to the fixed base.
        for (i, &g) in self.conductance.iter().enumerate() {
            if i + 1 < n {
                self.diag[i] += g;
                self.diag[i + 1] += g;
                self.sup[i] = -g;
                self.sub[i + 1] = -g;
            } else {
                self.diag[i] += g;
                self.rhs[i] += g * forcing.deep_ground_k;
            }
        }
        // Surface energy balance, linearised about the current surface temperature.
        let t0 = self.temps_k[0];
        let eps = self.emissivity;
        let h = forcing.convection_w_m2_k * self.convection_factor;
        let radiative = 4.0 * eps * STEFAN_BOLTZMANN * t0 * t0 * t0;
        let (q_s, dq_s) = saturation_specific_humidity(t0);
        let evaporative = self.wetness * h * LATENT_HEAT_J_KG / AIR_SPECIFIC_HEAT_J_KG_K;
        self.diag[0] += radiative + h + evaporative * dq_s;
        self.rhs[0] += self.absorptivity * forcing.incident_shortwave_w_m2
            + eps * forcing.incident_longwave_w_m2
            + 3.0 * eps * STEFAN_BOLTZMANN * t0 * t0 * t0 * t0
            + h * forcing.air_k
            - evaporative * (q_s - dq_s * t0 - forcing.air_specific_humidity);
        // Inner boundary.
        let last = n - 1;
        match self.inner {
            InnerBoundary::DeepGround => {}
            InnerBoundary::Interior {
                temperature_k,
                film_w_m2_k,
            } => {
                self.diag[last] += film_w_m2_k;
                self.rhs[last] += film_w_m2_k * temperature_k;
            }
            InnerBoundary::Air => {
                let ta = forcing.air_k;
                let back = h + 4.0 * eps * STEFAN_BOLTZMANN * ta * ta * ta;
                self.diag[last] += back;
                self.rhs[last] += back * ta;
            }
        }
        solve_tridiagonal(
            &self.sub,
            &mut self.diag,
            &self.sup,
            &mut self.rhs,
            &mut self.temps_k,
        );
        if let Some(cap) = self.melts_at_k {
            for t in &mut self.temps_k {
                *t = t.min(cap);
            }
        }
    }
}

/// Thomas algorithm: solves `sub[i] x[i-1] + diag[i] x[i] + sup[i] x[i+1] = rhs[i]`.
/// `diag` and `rhs` are overwritten. The systems here are diagonally dominant, so no pivoting.
fn solve_tridiagonal(sub: &[f64], diag: &mut [f64], sup: &[f64], rhs: &mut [f64], x: &mut [f64]) {
    let n = diag.len();
    for i in 1..n {
        let m = sub[i] / diag[i - 1];
        diag[i] -= m * sup[i - 1];
        rhs[i] -= m * rhs[i - 1];
    }
    x[n - 1] = rhs[n - 1] / diag[n - 1];
    for i in (0..n - 1).rev() {
        x[i] = (rhs[i] - sup[i] * x[i + 1]) / diag[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Layer, ThermalMaterial};

    const BARBER_LAYER: [Layer; 1] = [Layer {
        name: "Barber's semi-infinite body",
        thickness_m: 2.0,
        conductivity_w_m_k: 1.2,
        density_kg_m3: 2300.0,
        specific_heat_j_kg_k: 920.0,
        cells: 40,
        growth: 1.12,
    }];

    fn convective_only(layers: &'static [Layer], inner: InnerBoundary) -> MaterialProperties {
        MaterialProperties {
            id: ThermalMaterial::Rock,
            layers,
            solar_absorptivity: 0.0,
            emissivity_lwir: 0.0,
            emissivity_mwir: 0.0,
            wetness: 0.0,
            convection_factor: 1.0,
            melts_at_k: None,
            inner,
            sources: "test",
        }
    }

    fn forcing(air_k: f64, h: f64, deep_k: f64) -> SurfaceForcing {
        SurfaceForcing {
            incident_shortwave_w_m2: 0.0,
            incident_longwave_w_m2: 0.0,
            air_k,
            air_specific_humidity: 0.0,
            convection_w_m2_k: h,
            deep_ground_k: deep_k,
        }
    }

    /// Barber (1957): a semi-infinite body under sinusoidal air, convection only. The surface
    /// swings with amplitude ratio `H / sqrt((H + C)^2 + C^2)` and lags by
    /// `atan(C / (H + C)) / omega`, `H = h / k`, `C = sqrt(omega / 2 a)`.
    fn barber(h: f64) -> (f64, f64, f64, f64) {
        let (k, rho, cp) = (1.2, 2300.0, 920.0);
        let omega = 2.0 * std::f64::consts::PI / 86_400.0;
        let c = (omega / (2.0 * k / (rho * cp))).sqrt();
        let hh = h / k;
        let ratio = hh / ((hh + c).powi(2) + c * c).sqrt();
        let lag_h = (c / (hh + c)).atan() / omega / 3600.0;

        let (mean, swing) = (290.0, 10.0);
        let material = convective_only(&BARBER_LAYER, InnerBoundary::DeepGround);
        let mut slab = Slab::new(&material, mean);
        let dt = 30.0;
        let steps_per_day = (86_400.0 / dt) as usize;
        let mut last_day = Vec::new();
        for step in 0..steps_per_day * 12 {
            let t = (step + 1) as f64 * dt;
            let air = mean + swing * (omega * t).sin();
            slab.step(dt, &forcing(air, h, mean));
            if step >= steps_per_day * 11 {
                last_day.push((t, slab.surface_k()));
            }
        }
        // Fit the first harmonic of the last day.
        let (mut a, mut b) = (0.0, 0.0);
        for &(t, v) in &last_day {
            a += (v - mean) * (omega * t).sin();
            b += (v - mean) * (omega * t).cos();
        }
        let n = last_day.len() as f64;
        let (a, b) = (2.0 * a / n, 2.0 * b / n);
        let amplitude = (a * a + b * b).sqrt() / swing;
        let phase_lag_h = (-b).atan2(a) / omega / 3600.0;
        (amplitude, ratio, phase_lag_h, lag_h)
    }

    #[test]
    fn matches_barbers_periodic_solution() {
        for (h, ratio_ref, lag_ref) in [(10.0, 0.458, 1.74), (20.0, 0.642, 1.20)] {
            let (amplitude, ratio, lag, lag_closed) = barber(h);
            assert!((ratio - ratio_ref).abs() < 0.001 && (lag_closed - lag_ref).abs() < 0.01);
            assert!(
                (amplitude - ratio).abs() < 0.01,
                "h {h}: amplitude ratio {amplitude} vs {ratio}"
            );
            assert!(
                (lag - lag_closed).abs() < 0.05,
                "h {h}: lag {lag} h vs {lag_closed} h"
            );
        }
    }

    #[test]
    fn a_slab_in_constant_air_converges_to_it() {
        for inner in [
            InnerBoundary::Air,
            InnerBoundary::Interior {
                temperature_k: 300.0,
                film_w_m2_k: 0.0,
            },
        ] {
            let material = convective_only(&BARBER_LAYER[..], inner);
            let mut slab = Slab::new(&material, 250.0);
            slab.set_linear_profile(320.0, 260.0);
            for _ in 0..2_000 {
                slab.step(86_400.0, &forcing(285.0, 12.0, 0.0));
            }
            for t in slab.temperatures_k() {
                assert!((t - 285.0).abs() < 1e-3, "{inner:?}: {t}");
            }
        }
    }

    #[test]
    fn conserves_energy_when_insulated() {
        // A plate with no film inside and no convection outside keeps its heat as it evens out.
        let material = convective_only(
            &BARBER_LAYER[..],
            InnerBoundary::Interior {
                temperature_k: 0.0,
                film_w_m2_k: 0.0,
            },
        );
        let mut slab = Slab::new(&material, 280.0);
        slab.set_linear_profile(320.0, 280.0);
        let before = slab.stored_energy_j_m2(0.0);
        for _ in 0..1000 {
            slab.step(60.0, &forcing(280.0, 0.0, 0.0));
        }
        let after = slab.stored_energy_j_m2(0.0);
        assert!(
            (after - before).abs() / before < 1e-9,
            "{before} vs {after}"
        );
    }
}
