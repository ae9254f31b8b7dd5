//! The command line's thermal sensor options (`cig render --sensor lwir ...`): parsing, and the
//! thermal state of a still frame (the surface table spun up for the place and time, the
//! entities' engines). The physics is `cig-thermal`'s.

use anyhow::{bail, Context};
use cig_scene::thermal::{DisplayColour, Polarity, SensorView, ThermalScene};
use cig_scene::EntityInstance;
use cig_thermal::{Aerosol, AirTemperature, EntityThermalInput, ThermalWeather};

/// What `--sensor` and its companions ask for.
pub struct SensorOptions<'a> {
    pub sensor: &'a str,
    pub polarity: &'a str,
    pub gain: Option<f64>,
    pub level: Option<f64>,
    pub noise_k: f64,
    pub display: &'a str,
    pub ac_coupling_us: f64,
    pub line_dropout: bool,
}

/// The night-vision goggle `--sensor nvg` asks for, with `--nvg-gain` and `--phosphor`
/// (`None` for any other sensor; the gain and phosphor are checked either way).
pub fn parse_nvg(
    sensor: &str,
    gain: f64,
    phosphor: &str,
) -> anyhow::Result<Option<cig_scene::nvg::NvgView>> {
    let phosphor = cig_scene::nvg::Phosphor::from_name(phosphor)
        .map_err(|e| anyhow::anyhow!("--phosphor: {e}"))?;
    let view = cig_scene::nvg::NvgView {
        gain: gain as f32,
        phosphor,
        ..Default::default()
    };
    view.validate()
        .map_err(|e| anyhow::anyhow!("--nvg-gain: {e}"))?;
    Ok((sensor == "nvg").then_some(view))
}

/// The view's sensor (`None` for the visible channel).
pub fn parse_sensor(o: &SensorOptions) -> anyhow::Result<Option<SensorView>> {
    let Some(mut view) = cig_scene::thermal::sensor_of_name(o.sensor).map_err(|()| {
        anyhow::anyhow!(
            "--sensor \"{}\" is not visible, lwir, mwir or nvg",
            o.sensor
        )
    })?
    else {
        return Ok(None);
    };
    view.polarity = Polarity::from_name(o.polarity).with_context(|| {
        format!(
            "--polarity \"{}\" is not white-hot or black-hot",
            o.polarity
        )
    })?;
    view.display = DisplayColour::from_name(o.display)
        .with_context(|| format!("--display \"{}\" is not white, green or black", o.display))?;
    view.manual_gain_level = match (o.gain, o.level) {
        (None, None) => None,
        (Some(g), Some(l)) => {
            for (name, v) in [("--gain", g), ("--level", l)] {
                if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                    bail!("{name} {v} must lie in 0..1");
                }
            }
            Some((g as f32, l as f32))
        }
        _ => bail!("--gain and --level go together (without both, the gain is automatic)"),
    };
    if !(o.noise_k.is_finite() && (0.0..=5.0).contains(&o.noise_k)) {
        bail!("--noise {} must lie in 0..5 kelvin", o.noise_k);
    }
    view.netd_k = o.noise_k as f32;
    if !(o.ac_coupling_us.is_finite() && (0.0..=1.0e6).contains(&o.ac_coupling_us)) {
        bail!(
            "--ac-coupling-us {} must lie in 0..1000000 microseconds",
            o.ac_coupling_us
        );
    }
    view.ac_coupling_us = o.ac_coupling_us as f32;
    view.line_dropout = o.line_dropout;
    Ok(Some(view))
}

/// The weather a still frame's surfaces were heated by.
pub struct FrameWeather {
    pub air_min_c: f64,
    pub air_max_c: f64,
    pub rh_pct: f64,
    pub wind_mps: f64,
    pub cloud_cover: f64,
    pub visibility_m: f64,
}

/// Parses `--air-c MIN,MAX`.
pub fn parse_air(text: &str) -> anyhow::Result<(f64, f64)> {
    let parts: Vec<&str> = text.split(',').collect();
    let [min, max] = parts[..] else {
        bail!("--air-c \"{text}\" is not MIN,MAX in Celsius");
    };
    let parse = |v: &str| -> anyhow::Result<f64> {
        v.trim()
            .parse::<f64>()
            .with_context(|| format!("--air-c \"{text}\": \"{v}\" is not a number"))
    };
    Ok((parse(min)?, parse(max)?))
}

/// The thermal state of a still frame at a place (the ground there `ground_alt_m` above the
/// ellipsoid) and time: every material spun up over the two days before, the entities'
/// engines running (steady) or off.
pub fn still_thermal_scene(
    lat_deg: f64,
    lon_deg: f64,
    ground_alt_m: f64,
    time: cig_environment::UtcTime,
    weather: &FrameWeather,
    entities: &[EntityInstance],
    engines_running: bool,
) -> anyhow::Result<ThermalScene> {
    let air = AirTemperature::diurnal_c(weather.air_min_c, weather.air_max_c).context("--air-c")?;
    let thermal_weather = ThermalWeather {
        air,
        relative_humidity_pct: weather.rh_pct,
        wind_mps: weather.wind_mps,
        cloud_cover: weather.cloud_cover,
        deep_ground_k: None,
    };
    thermal_weather.validate().context("--rh")?;
    let ids: Vec<u32> = entities.iter().map(|e| e.id).collect();
    cig_scene::thermal::still_scene(
        lat_deg,
        lon_deg,
        ground_alt_m,
        time,
        thermal_weather,
        (Aerosol::Rural, weather.visibility_m),
        &ids,
        &EntityThermalInput {
            engine_on: engines_running,
            speed_mps: 0.0,
            burning: false,
            destroyed: false,
        },
    )
    .context("the thermal model")
}
