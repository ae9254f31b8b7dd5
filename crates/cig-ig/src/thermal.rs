//! The world's thermal state for the sensor views: the surface table (`cig_thermal`) spun up
//! for the served area when a sensor first needs it and advanced with the simulation clock
//! every step, the host's and the scenario's weather driving it, and each drawn entity's hot
//! parts warming and cooling with its engine.
//!
//! Engine state, by entity: the scenario's `engine`, else its DIS appearance's power-plant bit
//! (bit 22 of a platform's appearance, SISO-REF-010 land, air and surface platforms); a
//! remote DIS entity's appearance; a host's CIGI entity runs its engine while active (CIGI has
//! no engine field). Damage "destroyed" (appearance bits 3-4 = 3) and the flaming bit (15) make
//! it destroyed and burning. Speed is the entity's displacement between steps.
//!
//! Limits: one table for the whole served area, at the first eye's place when it is made (the
//! sun's angles and the local solar time of a 100 km database differ by under a degree);
//! entities' hot parts only for the vehicles drawn; the hot spots of impacts are the DIS
//! exercise's detonations on the ground (the last 32), as Gaussian warm patches, not shaped
//! craters.

use crate::scenario::{value_error, ThermalSection};
use crate::ScenarioError;
use cig_geo::Geodetic;
use cig_scene::thermal::{SensorView, ThermalScene};
use cig_thermal::{
    Aerosol, AirTemperature, EntityHeat, EntityThermalInput, IrBand, Orientations, SurfaceTable,
    ThermalMaterial, ThermalWeather, CELSIUS_0_K,
};
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;

/// DIS platform appearance bits (SISO-REF-010).
const BIT_POWER_PLANT_ON: u32 = 1 << 22;
const BIT_FLAMING: u32 = 1 << 15;
const SHIFT_DAMAGE: u32 = 3;
const DAMAGE_DESTROYED: u32 = 3;

/// What a DIS appearance says about an entity's heat: (engine on, burning, destroyed).
pub fn appearance_heat(appearance: u32) -> (bool, bool, bool) {
    (
        appearance & BIT_POWER_PLANT_ON != 0,
        appearance & BIT_FLAMING != 0,
        (appearance >> SHIFT_DAMAGE) & 3 == DAMAGE_DESTROYED,
    )
}

impl ThermalSection {
    /// The weather the section describes, and its aerosol model, checked.
    pub fn weather(&self) -> Result<(ThermalWeather, Aerosol), ScenarioError> {
        let air = match (&self.air_hourly_c, self.air_min_c, self.air_max_c) {
            (Some(hours), None, None) => AirTemperature::hourly_c(hours)
                .map_err(|e| value_error("thermal.air_hourly_c", e.to_string()))?,
            (None, min, max) => AirTemperature::diurnal_c(min.unwrap_or(10.0), max.unwrap_or(24.0))
                .map_err(|e| value_error("thermal.air_min_c", e.to_string()))?,
            _ => {
                return Err(value_error(
                    "thermal.air_hourly_c",
                    "give either air_hourly_c or air_min_c and air_max_c",
                ))
            }
        };
        let defaults = ThermalWeather::default();
        let weather = ThermalWeather {
            air,
            relative_humidity_pct: self.humidity_pct.unwrap_or(defaults.relative_humidity_pct),
            wind_mps: self.wind_mps.unwrap_or(defaults.wind_mps),
            cloud_cover: 0.0,
            deep_ground_k: self.deep_ground_c.map(|c| c + CELSIUS_0_K),
        };
        weather
            .validate()
            .map_err(|e| value_error("thermal", e.to_string()))?;
        let aerosol = Aerosol::from_name(self.aerosol.as_deref().unwrap_or("rural"))
            .map_err(|e| value_error("thermal.aerosol", e.to_string()))?;
        Ok((weather, aerosol))
    }
}

/// One entity as the thermal state sees it this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalEntity {
    pub id: u32,
    pub position_ecef_m: DVec3,
    /// Engine on, burning, destroyed.
    pub engine_on: bool,
    pub burning: bool,
    pub destroyed: bool,
}

/// The host's air (CIGI Atmosphere Control), when it set one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostAir {
    pub air_temperature_c: f64,
    pub humidity_pct: f64,
    pub wind_mps: f64,
}

/// The thermal state of the world.
pub struct ThermalWorld {
    weather: ThermalWeather,
    aerosol: Aerosol,
    table: Option<SurfaceTable>,
    /// Per entity: its heat and its last (time, position) for its speed.
    heat: BTreeMap<u32, (EntityHeat, f64, DVec3)>,
    /// The frame's scene (rebuilt each step while the table exists).
    scene: Option<Arc<ThermalScene>>,
    /// Where the table was made: the place and the ground's height there (above the
    /// ellipsoid, the infrared paths' base).
    place: Option<Geodetic>,
    /// Fresh craters and impact points: (effect time of the event, ECEF point, the spot).
    spots: Vec<(f64, DVec3, cig_thermal::HotSpot)>,
    /// The terrain's crater edits younger than [`CRATER_HEAT_S`]: (UTC time made, ECEF point
    /// of the bowl's bottom, radius).
    craters: Vec<(f64, DVec3, f64)>,
    /// The edits read so far (their count, and the layer's revision then).
    craters_seen: (usize, u64),
    visibility_m: f64,
}

/// How long a crater's ground stays warmer than the ground around it, s (the disturbed
/// soil's hour, `cig_thermal::HotSpot::disturbed_soil`, to a tenth of a kelvin).
pub const CRATER_HEAT_S: f64 = 6.0 * 3600.0;

/// Warm craters kept (the newest); the renderer draws the nearest of their spots.
pub const MAX_WARM_CRATERS: usize = 1024;

impl ThermalWorld {
    /// The state for a scenario's `[thermal]` section (or the defaults).
    pub fn new(section: Option<&ThermalSection>) -> ThermalWorld {
        let (weather, aerosol) = section
            .and_then(|s| s.weather().ok())
            .unwrap_or((ThermalWeather::default(), Aerosol::Rural));
        ThermalWorld {
            weather,
            aerosol,
            table: None,
            heat: BTreeMap::new(),
            scene: None,
            spots: Vec::new(),
            craters: Vec::new(),
            craters_seen: (0, 0),
            place: None,
            visibility_m: 23_000.0,
        }
    }

    /// Whether the table has been spun up.
    pub fn is_running(&self) -> bool {
        self.table.is_some()
    }

    /// Advances the state to `time` (spinning the table up at `place` the first time, or when
    /// the place moved more than 100 km), with the host's air, the cloud cover, the visibility
    /// and the drawn entities. `place`'s altitude is the ground's there.
    #[allow(
        clippy::too_many_arguments,
        reason = "the step's inputs, each from a different part of the world"
    )]
    pub fn step(
        &mut self,
        time: cig_environment::UtcTime,
        place: Geodetic,
        host_air: Option<HostAir>,
        cloud_cover: f64,
        visibility_m: f64,
        entities: &[ThermalEntity],
    ) -> Result<(), cig_thermal::ThermalError> {
        let mut weather = self.weather.clone();
        weather.cloud_cover = cloud_cover.clamp(0.0, 1.0);
        if let Some(h) = host_air {
            // Values that are not numbers are the host's mistake: the previous ones stay.
            if h.humidity_pct.is_finite() {
                weather.relative_humidity_pct = h.humidity_pct.clamp(0.0, 100.0);
            }
            if h.wind_mps.is_finite() {
                weather.wind_mps = h.wind_mps.clamp(0.0, 100.0);
            }
            if h.air_temperature_c.is_finite() {
                weather.air = weather.air.with_current(
                    time,
                    place.lat_deg,
                    place.lon_deg,
                    (h.air_temperature_c + CELSIUS_0_K).clamp(183.0, 333.0),
                );
            }
        }
        self.visibility_m = if visibility_m.is_finite() && visibility_m > 0.0 {
            visibility_m
        } else {
            23_000.0
        };
        // A table made for a place more than 100 km away is made again here (the sun's hours).
        let far = self.place.is_some_and(|p| {
            (p.to_ecef() - Geodetic::new(place.lat_deg, place.lon_deg, p.alt_m).to_ecef()).length()
                > 100_000.0
        });
        if far {
            self.table = None;
        }
        self.place = Some(place);
        match &mut self.table {
            Some(table) => {
                table.set_weather(weather)?;
                table.advance_to(time);
            }
            None => {
                self.table = Some(SurfaceTable::spin_up(
                    place.lat_deg,
                    place.lon_deg,
                    time,
                    weather,
                    &ThermalMaterial::ALL,
                    Orientations::Standard,
                )?);
            }
        }
        let Some(table) = &self.table else {
            return Ok(());
        };
        let air_k = table.air_k();
        let now = time.unix_seconds();
        let mut kept = BTreeMap::new();
        for e in entities {
            let (mut heat, last_s, last_p) = self.heat.remove(&e.id).unwrap_or((
                EntityHeat::default(),
                f64::NAN,
                e.position_ecef_m,
            ));
            let dt = now - last_s;
            let speed = if dt.is_finite() && dt > 1e-3 {
                (e.position_ecef_m - last_p).length() / dt
            } else {
                0.0
            };
            let input = EntityThermalInput {
                engine_on: e.engine_on,
                speed_mps: speed.min(100.0),
                burning: e.burning,
                destroyed: e.destroyed,
            };
            if last_s.is_nan() {
                // First seen: as if it had been doing this for a while.
                heat = EntityHeat::steady(&input, air_k);
            } else if dt > 0.0 {
                heat.step(dt, &input, air_k);
            }
            kept.insert(e.id, (heat, now, e.position_ecef_m));
        }
        self.heat = kept;
        let atmosphere =
            cig_scene::thermal::atmosphere_over(table, self.aerosol, self.visibility_m);
        let mut scene = ThermalScene::from_table(
            table,
            atmosphere,
            self.heat
                .iter()
                .map(|(id, (h, _, _))| (*id, h.rise_k.map(|r| r as f32)))
                .collect(),
        );
        scene.base_alt_m = place.alt_m;
        let effect_now = cig_effects::effect_time_s(now);
        // A crater's heat: its hot core for minutes, its disturbed soil for hours; an impact
        // that made a crater is the crater's (its own spot would count the heat twice).
        let crater_spots = self.craters.iter().flat_map(|&(t, p, radius_m)| {
            [
                cig_thermal::HotSpot::crater(radius_m),
                cig_thermal::HotSpot::disturbed_soil(radius_m),
            ]
            .map(|spot| (p, spot.radius_m, spot.rise_k(now - t)))
        });
        let near_crater = |p: &DVec3| {
            self.craters
                .iter()
                .any(|(_, c, r)| c.distance_squared(*p) < (r + 1.0) * (r + 1.0))
        };
        let impact_spots = self
            .spots
            .iter()
            .filter(|(_, p, spot)| spot.radius_m < 1.0 || !near_crater(p))
            .map(|(t, p, spot)| (*p, spot.radius_m, spot.rise_k(effect_now - t)));
        scene.hot_spots = impact_spots
            .chain(crater_spots)
            .filter(|(_, _, rise)| *rise > 0.2)
            .map(|(p, radius_m, rise)| (p.to_array(), radius_m as f32, rise as f32))
            .collect();
        self.scene = Some(Arc::new(scene));
        Ok(())
    }

    /// Sets the hot spots of the ground's recent impacts: (effect time, ECEF point, size); a
    /// large or medium round leaves a crater, a small one an impact point.
    pub fn set_impacts(&mut self, impacts: &[(f64, DVec3, cig_dis::ImpactSize)]) {
        self.spots = impacts
            .iter()
            .map(|(t, p, size)| {
                let spot = match size {
                    cig_dis::ImpactSize::Small => cig_thermal::HotSpot::impact(),
                    cig_dis::ImpactSize::Medium => cig_thermal::HotSpot::crater(2.0),
                    cig_dis::ImpactSize::Large => cig_thermal::HotSpot::crater(4.0),
                };
                (*t, *p, spot)
            })
            .collect();
    }

    /// Follows the terrain's crater edits (any author: detonations, the host's, the
    /// operator's): the ones made within [`CRATER_HEAT_S`] of `now_unix_s` are warm. Reads
    /// only the edits added since the last call (all of them again after a removal or a new
    /// layer); each new crater's bottom is found by `query`.
    pub fn follow_craters(
        &mut self,
        layer: &cig_terrain::edits::EditLayer,
        query: &mut cig_terrain::QuerySession,
        now_unix_s: f64,
    ) {
        let (seen, revision) = self.craters_seen;
        if layer.revision() != revision || layer.len() != seen {
            let start = if layer.len() >= seen && layer.revision() >= revision {
                seen
            } else {
                self.craters.clear();
                0
            };
            for edit in layer.edits_from(start) {
                let cig_terrain::edits::EditShape::Crater {
                    centre, radius_m, ..
                } = &edit.shape
                else {
                    continue;
                };
                if now_unix_s - edit.time_utc_s > CRATER_HEAT_S {
                    continue;
                }
                if let Ok(ground) = query.hot(centre.lat_deg, centre.lon_deg) {
                    let bottom = Geodetic::new(
                        centre.lat_deg,
                        centre.lon_deg,
                        ground.height_msl_m + ground.geoid_undulation_m,
                    );
                    self.craters
                        .push((edit.time_utc_s, bottom.to_ecef(), *radius_m));
                }
            }
            self.craters_seen = (layer.len(), layer.revision());
        }
        self.craters
            .retain(|(t, _, _)| now_unix_s - t <= CRATER_HEAT_S);
        // The newest first, at most the shader's spots.
        if self.craters.len() > MAX_WARM_CRATERS {
            self.craters.sort_by(|a, b| b.0.total_cmp(&a.0));
            self.craters.truncate(MAX_WARM_CRATERS);
        }
    }

    /// The frame's thermal scene, once the table runs.
    pub fn scene(&self) -> Option<Arc<ThermalScene>> {
        self.scene.clone()
    }
}

/// CIGI View Definition view types cig gives a meaning to (the field is IG-defined;
/// docs/cigi-conformance.md): 0 the visible channel, 1 LWIR, 2 MWIR, 3 night-vision goggles.
pub const VIEW_TYPE_LWIR: u8 = 1;
pub const VIEW_TYPE_MWIR: u8 = 2;
pub const VIEW_TYPE_NVG: u8 = 3;

/// The night-vision goggle a host's view shows: an NVG view type's goggle at its defaults,
/// with the gain of a Sensor Control on the view (CIGI's 0..1 gain, already clamped by the
/// session, maps to the goggle's 0.1..10 as `10^(2 g - 1)`: 0.5 is the nominal 1); a Sensor
/// Control turned off over an NVG view makes it visible. Any other view type has none.
pub fn host_nvg(
    view_type: u8,
    control: Option<&crate::session::SensorMode>,
) -> Option<cig_scene::nvg::NvgView> {
    if view_type != VIEW_TYPE_NVG {
        return None;
    }
    let mut nvg = cig_scene::nvg::NvgView::default();
    if let Some(c) = control {
        if !c.on {
            return None;
        }
        let gain = 10f64.powf(2.0 * c.gain.clamp(0.0, 1.0) - 1.0);
        nvg.gain = (gain as f32).clamp(0.1, 10.0);
    }
    Some(nvg)
}

/// The sensor a host's view shows: its view type's band, with the Sensor Control the host set
/// on it (gain and level unless automatic, polarity, noise as a NETD of up to 0.5 K, line
/// dropout, AC coupling); a Sensor Control turned on over a visible view type makes it LWIR.
pub fn host_sensor(
    view_type: u8,
    control: Option<&crate::session::SensorMode>,
) -> Option<SensorView> {
    let band = match view_type {
        VIEW_TYPE_LWIR => Some(IrBand::Lwir),
        VIEW_TYPE_MWIR => Some(IrBand::Mwir),
        // A Sensor Control on a goggle's view sets the goggle, not a thermal band.
        VIEW_TYPE_NVG => return None,
        _ => None,
    };
    let control = control.filter(|c| c.on);
    let band = band.or(control.map(|_| IrBand::Lwir))?;
    let mut view = SensorView::new(band);
    if let Some(c) = control {
        view.polarity = if c.black_hot {
            cig_scene::thermal::Polarity::BlackHot
        } else {
            cig_scene::thermal::Polarity::WhiteHot
        };
        view.manual_gain_level = (!c.automatic_gain).then_some((c.gain as f32, c.level as f32));
        view.netd_k = (0.5 * c.noise) as f32;
        view.line_dropout = c.line_dropout;
        view.ac_coupling_us = c.ac_coupling_us as f32;
    }
    Some(view)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn appearance_bits_give_engine_fire_and_damage() {
        assert_eq!(appearance_heat(0), (false, false, false));
        assert_eq!(appearance_heat(1 << 22), (true, false, false));
        assert_eq!(appearance_heat((3 << 3) | (1 << 15)), (false, true, true));
        assert_eq!(appearance_heat(1 << 3), (false, false, false));
    }

    #[test]
    fn the_table_spins_up_once_and_entities_warm_after_start() {
        let mut w = ThermalWorld::new(None);
        let t0 = cig_environment::UtcTime::parse_iso8601("2026-06-21T06:00:00Z").expect("t");
        let place = Geodetic::new(36.0, -121.0, 0.0);
        let mut tank = ThermalEntity {
            id: 7,
            position_ecef_m: place.to_ecef(),
            engine_on: false,
            burning: false,
            destroyed: false,
        };
        w.step(t0, place, None, 0.0, 20_000.0, &[tank])
            .expect("step");
        let cold = w.scene().expect("scene").entity_heat[0].1[0];
        assert!(cold.abs() < 1e-3, "{cold}");
        tank.engine_on = true;
        w.step(t0.plus_seconds(600.0), place, None, 0.0, 20_000.0, &[tank])
            .expect("step");
        let warm = w.scene().expect("scene").entity_heat[0].1[0];
        assert!(warm > 20.0, "the engine deck warms in ten minutes: {warm}");
        // The host's air temperature shifts the curve.
        w.step(
            t0.plus_seconds(601.0),
            place,
            Some(HostAir {
                air_temperature_c: 35.0,
                humidity_pct: 30.0,
                wind_mps: 2.0,
            }),
            0.0,
            20_000.0,
            &[tank],
        )
        .expect("step");
        let air = w.scene().expect("scene").air_k - CELSIUS_0_K;
        assert!((air - 35.0).abs() < 0.01, "{air}");
    }

    /// A flat 65 x 65 post database, 30 m apart, of grass.
    fn flat_query() -> cig_terrain::QuerySession {
        use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
        use cig_terrain::raster::{GeoGrid, Raster};
        let (n, e) = cig_geo::metres_per_degree(36.0);
        let grid = GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 30.0 / n,
            dlon_deg: 30.0 / e,
            rows: 65,
            cols: 65,
        };
        let raster = Raster {
            grid,
            elevation_m: vec![100.0; grid.len()],
            material: Some(vec![cig_terrain::Material::Grass; grid.len()]),
        };
        let store = Arc::new(MemoryTileStore::new());
        let summary = cig_terrain::build::build_pyramid::<cig_terrain::build::BuildError>(
            &raster,
            64,
            &mut |t| {
                store.insert(t.key, t.encode());
                Ok(())
            },
        )
        .expect("build");
        let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]);
        let db =
            TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
        let cache = cig_terrain::TileCache::new(Arc::new(db), cig_terrain::PagingConfig::default())
            .expect("cache");
        cig_terrain::QuerySession::new(Arc::new(cache))
    }

    #[test]
    fn crater_edits_are_hot_and_cool_and_an_impact_there_is_not_counted_twice() {
        use cig_terrain::edits::{EditAuthor, EditShape, GeoPoint, TerrainEdit};
        let mut q = flat_query();
        let t0 = cig_environment::UtcTime::parse_iso8601("2026-06-21T06:00:00Z").expect("t");
        let (lat, lon) = (36.0 + 0.004, -121.0 + 0.005);
        let crater = |sequence: u32, time_utc_s: f64, lat_deg: f64| TerrainEdit {
            author: EditAuthor::default(),
            sequence,
            time_utc_s,
            shape: EditShape::Crater {
                centre: GeoPoint {
                    lat_deg,
                    lon_deg: lon,
                },
                radius_m: 2.0,
                depth_m: 0.8,
                lip_radius_m: 2.5,
                lip_height_m: 0.2,
            },
        };
        // A fresh crater, and one made a day before (cold).
        q.cache()
            .update_edits(|l| {
                l.apply(crater(1, t0.unix_seconds(), lat))?;
                l.apply(crater(2, t0.unix_seconds() - 86_400.0, lat + 0.001))
            })
            .expect("craters");
        let place = Geodetic::new(36.0, -121.0, 0.0);
        let mut w = ThermalWorld::new(None);
        // The Detonation that made it, as an impact: its spot is the crater's.
        let at = cig_effects::effect_time_s(t0.unix_seconds());
        let bottom = Geodetic::new(lat, lon, 99.2).to_ecef();
        w.set_impacts(&[(at, bottom, cig_dis::ImpactSize::Large)]);
        let spots_at = |w: &mut ThermalWorld,
                        q: &mut cig_terrain::QuerySession,
                        t: cig_environment::UtcTime| {
            let edits = q.cache().edits();
            w.follow_craters(&edits, q, t.unix_seconds());
            w.step(t, place, None, 0.0, 20_000.0, &[]).expect("step");
            w.scene().expect("scene").hot_spots.clone()
        };
        let fresh = spots_at(&mut w, &mut q, t0);
        // The crater's core and its disturbed soil; the impact's own spot left out.
        assert_eq!(fresh.len(), 2, "{fresh:?}");
        let core = fresh.iter().map(|s| s.2).fold(0.0f32, f32::max);
        assert!(core > 250.0, "{fresh:?}");
        let centre = DVec3::from_array(fresh[0].0);
        assert!(centre.distance(bottom) < 0.5, "at the bowl's bottom");
        // Ten minutes on: the core has cooled to about a third, the soil hardly.
        let later = spots_at(&mut w, &mut q, t0.plus_seconds(600.0));
        let core_later = later.iter().map(|s| s.2).fold(0.0f32, f32::max);
        assert!(core_later < core / 2.5, "{later:?}");
        // Two hours on: only the disturbed soil, a kelvin or so.
        let hours = spots_at(&mut w, &mut q, t0.plus_seconds(7200.0));
        assert_eq!(hours.len(), 1, "{hours:?}");
        assert!((0.5..3.0).contains(&hours[0].2), "{hours:?}");
        // Healed: no crater, no heat; the impact's spot is its own again.
        q.cache()
            .update_edits(|l| {
                l.remove(cig_terrain::edits::EditId {
                    author: EditAuthor::default(),
                    sequence: 1,
                })
            })
            .expect("healed");
        let healed = spots_at(&mut w, &mut q, t0.plus_seconds(60.0));
        assert!(healed.iter().all(|s| s.1 == 4.0), "{healed:?}");
    }

    #[test]
    fn impacts_leave_hot_spots_that_cool() {
        let mut w = ThermalWorld::new(None);
        let t0 = cig_environment::UtcTime::parse_iso8601("2026-06-21T06:00:00Z").expect("t");
        let place = Geodetic::new(36.0, -121.0, 0.0);
        let at = cig_effects::effect_time_s(t0.unix_seconds());
        w.set_impacts(&[
            (at, place.to_ecef(), cig_dis::ImpactSize::Large),
            (at, place.to_ecef(), cig_dis::ImpactSize::Small),
        ]);
        w.step(t0, place, None, 0.0, 20_000.0, &[]).expect("step");
        let fresh = w.scene().expect("scene").hot_spots.clone();
        assert_eq!(fresh.len(), 2);
        assert!(fresh[0].2 > 250.0 && fresh[0].1 == 4.0, "{fresh:?}");
        w.step(t0.plus_seconds(600.0), place, None, 0.0, 20_000.0, &[])
            .expect("step");
        let later = w.scene().expect("scene").hot_spots.clone();
        // The crater has cooled to about a third; the small impact is gone.
        assert_eq!(later.len(), 1);
        assert!(later[0].2 < fresh[0].2 / 2.5, "{later:?}");
    }

    #[test]
    fn host_sensors_follow_view_type_and_control() {
        assert_eq!(host_sensor(0, None), None);
        assert_eq!(host_sensor(2, None).map(|s| s.band), Some(IrBand::Mwir));
        let control = crate::session::SensorMode {
            view_id: 0,
            sensor_id: 0,
            on: true,
            black_hot: true,
            gain: 0.4,
            level: 0.6,
            noise: 0.2,
            track_mode: 0,
            extended_response: false,
            automatic_gain: false,
            line_dropout: true,
            ac_coupling_us: 20.0,
            track_black: false,
        };
        let s = host_sensor(0, Some(&control)).expect("a sensor");
        assert_eq!(s.band, IrBand::Lwir);
        assert_eq!(s.polarity, cig_scene::thermal::Polarity::BlackHot);
        assert_eq!(s.manual_gain_level, Some((0.4, 0.6)));
        assert!((s.netd_k - 0.1).abs() < 1e-6 && s.line_dropout);
        // On an NVG view the control is the goggle's, not a thermal sensor's.
        assert_eq!(host_sensor(VIEW_TYPE_NVG, Some(&control)), None);
    }

    #[test]
    fn host_nvg_gain_maps_zero_one_to_a_tenth_to_ten() {
        assert_eq!(host_nvg(0, None), None);
        assert_eq!(host_nvg(VIEW_TYPE_LWIR, None), None);
        assert_eq!(host_nvg(VIEW_TYPE_NVG, None).map(|n| n.gain), Some(1.0));
        let mut control = crate::session::SensorMode {
            view_id: 0,
            sensor_id: 0,
            on: true,
            black_hot: false,
            gain: 0.5,
            level: 0.5,
            noise: 0.0,
            track_mode: 0,
            extended_response: false,
            automatic_gain: true,
            line_dropout: false,
            ac_coupling_us: 0.0,
            track_black: false,
        };
        let gain =
            |c: &crate::session::SensorMode| host_nvg(VIEW_TYPE_NVG, Some(c)).map(|n| n.gain);
        assert!((gain(&control).expect("nvg") - 1.0).abs() < 1e-6);
        control.gain = 0.0;
        assert!((gain(&control).expect("nvg") - 0.1).abs() < 1e-6);
        control.gain = 1.0;
        assert!((gain(&control).expect("nvg") - 10.0).abs() < 1e-5);
        control.gain = 0.75;
        assert!((gain(&control).expect("nvg") - 10f32.sqrt()).abs() < 1e-4);
        control.on = false;
        assert_eq!(gain(&control), None);
    }
}
