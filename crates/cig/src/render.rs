//! `cig render`: one frame off-screen, to PNG, with optional statistics.

use crate::cli::RenderArgs;
use crate::config::Config;
use anyhow::{bail, Context};
use cig_geo::Geodetic;
use cig_ig::scenes::{fire_puffs, lightning_bolt, FireSpec, MAX_BURN_S, MAX_HEAT_MW};
use cig_ig::sea::WorldSea;
use cig_render::{FrameStats, Gpu, Image, Renderer};
use cig_scene::lighting::{Fog, FogMode};
use cig_scene::snapshot::{place_entity, Clamp, EntitySpec};
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::database::GeoidLookup;
use cig_terrain::{QuerySession, TileCache};
use std::path::Path;
use std::sync::Arc;

/// Parses `N` comma-separated numbers named `what`.
pub fn parse_numbers(text: &str, what: &str, counts: &[usize]) -> anyhow::Result<Vec<f64>> {
    let values: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("{what} \"{text}\" is not a list of numbers"))?;
    if !counts.contains(&values.len()) || values.iter().any(|v| !v.is_finite()) {
        bail!("{what} \"{text}\" needs {counts:?} finite numbers");
    }
    Ok(values)
}

/// Parses "WxH".
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .with_context(|| format!("--size \"{text}\" is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size \"{text}\": bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size \"{text}\": bad height"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--size \"{text}\" must be between 1x1 and 16384x16384");
    }
    Ok((w, h))
}

/// Parses an ISO 8601 time (see `cig ephem`) into seconds since 1970 UTC.
pub fn parse_time(text: &str) -> anyhow::Result<f64> {
    Ok(crate::ephem::parse_time(text)?.unix_seconds())
}

/// Builds a view from the command line's strings.
pub fn parse_view(eye: &str, hpr: &str, fov: &str, size: &str) -> anyhow::Result<View> {
    let e = parse_numbers(eye, "--eye", &[3])?;
    let o = parse_numbers(hpr, "--hpr", &[3])?;
    let (width_px, height_px) = parse_size(size)?;
    let f = parse_numbers(fov, "--fov", &[1, 2, 4])?;
    let fov = match f.as_slice() {
        [h] => FovDeg::from_horizontal(*h, width_px, height_px),
        [h, v] => FovDeg::symmetric(*h, *v),
        [l, r, d, u] => FovDeg {
            left_deg: *l,
            right_deg: *r,
            down_deg: *d,
            up_deg: *u,
        },
        _ => bail!("--fov \"{fov}\" needs 1, 2 or 4 numbers"),
    };
    let view = View {
        eye: Geodetic::new(e[0], e[1], e[2]),
        orientation: Hpr {
            heading_deg: o[0],
            pitch_deg: o[1],
            roll_deg: o[2],
        },
        fov,
        width_px,
        height_px,
    };
    view.validate().context("the view cannot be drawn")?;
    Ok(view)
}

/// Parses "MODEL,LAT,LON,ALT[,HEADING[,clamp]]".
pub fn parse_entity(text: &str, id: u32) -> anyhow::Result<(EntitySpec, EntityMotion)> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() < 4 || parts.len() > 8 {
        bail!(
            "--entity \"{text}\" is not MODEL,LAT,LON,ALT[,HEADING[,clamp][,speed=MPS][,turn=DEG_S]]"
        );
    }
    let nums = parse_numbers(
        &parts[1..4.max(parts.len().min(5))].join(","),
        "--entity",
        &[3, 4],
    )?;
    let mut clamp = Clamp::None;
    let mut motion = EntityMotion::default();
    for option in parts.iter().skip(5) {
        let number = |value: &str, what: &str, range: std::ops::RangeInclusive<f64>| {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && range.contains(v))
                .with_context(|| {
                    format!(
                        "--entity \"{text}\": {what} \"{value}\" must lie in {}..{}",
                        range.start(),
                        range.end()
                    )
                })
        };
        match option.split_once('=') {
            None if *option == "clamp" => clamp = Clamp::HeightAndAttitude,
            Some(("speed", value)) => motion.speed_mps = number(value, "speed (m/s)", 0.0..=40.0)?,
            Some(("turn", value)) => {
                motion.turn_deg_s = number(value, "turn (degrees a second)", -10.0..=10.0)?;
            }
            _ => bail!(
                "--entity \"{text}\": unknown option \"{option}\" (clamp, speed=MPS or turn=DEG_S)"
            ),
        }
    }
    let spec = EntitySpec {
        id,
        model: parts[0].to_string(),
        position: Geodetic::new(nums[0], nums[1], nums[2]),
        orientation: Hpr {
            heading_deg: nums.get(3).copied().unwrap_or(0.0),
            ..Default::default()
        },
        clamp,
    };
    Ok((spec, motion))
}

/// How an `--entity` moves at the picture's instant: its speed, and the rate it has been
/// turning at (a ship's wake is drawn along that circle).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EntityMotion {
    pub speed_mps: f64,
    /// Degrees a second, positive to starboard.
    pub turn_deg_s: f64,
}

/// Parses `--light "LAT,LON,ALT_M,CANDELA[,COLOUR]"` into an all-round lamp.
pub fn parse_light(text: &str) -> anyhow::Result<cig_scene::lights::LightPoint> {
    let (numbers, colour) = match text.rsplit_once(',') {
        Some((head, tail)) if tail.trim().parse::<f64>().is_err() => (head, tail.trim()),
        _ => (text, "warm"),
    };
    let v = parse_numbers(numbers, "--light", &[4])
        .map_err(|e| anyhow::anyhow!("{e:#} (LAT,LON,ALT_M,CANDELA[,COLOUR])"))?;
    let (lat_deg, lon_deg, alt_m, candela) = (v[0], v[1], v[2], v[3]);
    if !(-90.0..=90.0).contains(&lat_deg) || !(-180.0..=180.0).contains(&lon_deg) {
        bail!("--light \"{text}\": latitude must lie in -90..90 and longitude in -180..180");
    }
    if !(alt_m.is_finite() && (-500.0..=100_000.0).contains(&alt_m)) {
        bail!("--light \"{text}\": altitude {alt_m} m must lie in -500..100000");
    }
    if !(candela.is_finite() && candela > 0.0 && candela <= 1e9) {
        bail!("--light \"{text}\": intensity {candela} cd must be above 0 and at most 1e9");
    }
    let lamp = cig_scene::lights::named_lamp(colour).with_context(|| {
        format!(
            "--light \"{text}\": unknown colour \"{colour}\" ({})",
            cig_scene::lights::LAMP_NAMES
        )
    })?;
    cig_scene::lights::omni_lamp(Geodetic::new(lat_deg, lon_deg, alt_m), candela as f32, lamp)
        .map_err(|e| anyhow::anyhow!("--light \"{text}\": {e}"))
}

/// Parses `--flare "LAT,LON,ALT_M"`: a 155 mm illumination flare lit at `unix_time_s`.
pub fn parse_flare(text: &str, unix_time_s: f64) -> anyhow::Result<cig_scene::lights::Flare> {
    let v = parse_numbers(text, "--flare", &[3])
        .map_err(|e| anyhow::anyhow!("{e:#} (LAT,LON,ALT_M)"))?;
    let (lat_deg, lon_deg, alt_m) = (v[0], v[1], v[2]);
    if !(-90.0..=90.0).contains(&lat_deg) || !(-180.0..=180.0).contains(&lon_deg) {
        bail!("--flare \"{text}\": latitude must lie in -90..90 and longitude in -180..180");
    }
    if !(alt_m.is_finite() && (-500.0..=20_000.0).contains(&alt_m)) {
        bail!("--flare \"{text}\": altitude {alt_m} m must lie in -500..20000");
    }
    Ok(cig_scene::lights::Flare::artillery_155mm(
        Geodetic::new(lat_deg, lon_deg, alt_m),
        unix_time_s,
    ))
}

/// Parses "LAT,LON[,HEAT_MW[,SECONDS]]".
pub fn parse_smoke(text: &str) -> anyhow::Result<FireSpec> {
    let v = parse_numbers(text, "--smoke", &[2, 3, 4])
        .map_err(|e| anyhow::anyhow!("{e:#} (LAT,LON[,HEAT_MW[,SECONDS]])"))?;
    let get = |i: usize, default: f64| v.get(i).copied().unwrap_or(default);
    let (lat_deg, lon_deg, heat_mw, burning_s) =
        (get(0, 0.0), get(1, 0.0), get(2, 5.0), get(3, 120.0));
    if !(-90.0..=90.0).contains(&lat_deg) || !(-180.0..=180.0).contains(&lon_deg) {
        bail!("--smoke \"{text}\": latitude must lie in -90..90 and longitude in -180..180");
    }
    if !(heat_mw > 0.0 && heat_mw <= MAX_HEAT_MW) {
        bail!("--smoke \"{text}\": heat release {heat_mw} MW must be above 0 and at most {MAX_HEAT_MW}");
    }
    if !(burning_s > 0.0 && burning_s <= MAX_BURN_S) {
        bail!("--smoke \"{text}\": {burning_s} seconds of burning must be above 0 and at most {MAX_BURN_S}");
    }
    Ok(FireSpec {
        lat_deg,
        lon_deg,
        heat_w: heat_mw * 1e6,
        burning_s,
    })
}

/// Parses a `--cloud` layer "BASE_M,THICKNESS_M,COVERAGE[,KIND[,WIND_MPS,FROM_DEG]]" (the
/// `seed` of the layer's pattern given).
pub fn parse_cloud(text: &str, seed: u64) -> anyhow::Result<cig_environment::clouds::CloudLayer> {
    use cig_environment::clouds::{CloudKind, CloudLayer};
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let form = "BASE_M,THICKNESS_M,COVERAGE[,KIND[,WIND_MPS,FROM_DEG]]";
    if ![3, 4, 6].contains(&parts.len()) {
        bail!("--cloud \"{text}\" is not {form}");
    }
    let number = |i: usize, name: &str| -> anyhow::Result<f64> {
        let part = parts.get(i).copied().unwrap_or_default();
        part.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("--cloud \"{text}\": {name} \"{part}\" is not a number"))
    };
    let kind = match parts.get(3) {
        Some(name) => CloudKind::from_name(name).with_context(|| {
            let names: Vec<&str> = CloudKind::ALL.iter().map(|k| k.name()).collect();
            format!(
                "--cloud \"{text}\": \"{name}\" is not a cloud type ({})",
                names.join(", ")
            )
        })?,
        None => CloudKind::Cumulus,
    };
    let (wind_speed_mps, wind_from_deg) = if parts.len() == 6 {
        (number(4, "wind speed")?, number(5, "wind direction")?)
    } else {
        (0.0, 0.0)
    };
    let layer = CloudLayer {
        base_m: number(0, "base")?,
        thickness_m: number(1, "thickness")?,
        coverage: number(2, "coverage")?,
        kind,
        wind_speed_mps,
        wind_from_deg,
        seed,
        drift: cig_environment::CloudDrift::default(),
    };
    layer
        .validate()
        .with_context(|| format!("--cloud \"{text}\""))?;
    Ok(layer)
}

/// Parses "SPEED,FROM_DEG".
pub fn parse_wind(text: &str) -> anyhow::Result<cig_effects::Wind> {
    let v = parse_numbers(text, "--wind", &[2])
        .map_err(|e| anyhow::anyhow!("{e:#} (SPEED,FROM_DEG)"))?;
    let (speed_mps, from_deg) = (v[0], v[1]);
    if !(0.0..=60.0).contains(&speed_mps) {
        bail!("--wind \"{text}\": speed {speed_mps} m/s must lie in 0..60");
    }
    Ok(cig_effects::Wind {
        speed_mps,
        from_deg: from_deg.rem_euclid(360.0),
    })
}

/// Parses a `--rain` or `--snow` rate.
pub fn parse_precipitation(
    text: &str,
    kind: cig_environment::PrecipitationKind,
) -> anyhow::Result<cig_environment::Precipitation> {
    let flag = format!("--{}", kind.name());
    let v = parse_numbers(text, &flag, &[1])?;
    cig_environment::Precipitation::new(kind, v[0])
        .map_err(|e| anyhow::anyhow!("{flag} \"{text}\": {e}"))
}

/// Parses `--lightning SEED[,DIST_M]`.
pub fn parse_lightning(text: &str) -> anyhow::Result<(u64, f64)> {
    let (seed_text, distance) = match text.split_once(',') {
        Some((s, d)) => (s.trim(), Some(d.trim())),
        None => (text.trim(), None),
    };
    let seed = seed_text.parse::<u64>().map_err(|_| {
        anyhow::anyhow!("--lightning \"{text}\": the seed \"{seed_text}\" is not a whole number 0..2^64 (SEED[,DIST_M])")
    })?;
    let distance_m = match distance {
        None => 3000.0,
        Some(d) => parse_numbers(d, "--lightning distance", &[1])?[0],
    };
    if !(100.0..=50_000.0).contains(&distance_m) {
        bail!("--lightning \"{text}\": the distance {distance_m} m must lie in 100..50000");
    }
    Ok((seed, distance_m))
}

/// The frame statistics as JSON.
pub fn stats_json(stats: &FrameStats, gpu: &Gpu, view: &View) -> serde_json::Value {
    serde_json::json!({
        "triangles": stats.triangles,
        "terrain_triangles": stats.terrain_triangles,
        "model_triangles": stats.model_triangles,
        "culture_triangles": stats.culture_triangles,
        "culture_drawn": stats.culture_drawn,
        "culture_blocks_occluded": stats.culture_blocks_occluded,
        "culture_cpu_ms": stats.culture_cpu_ms,
        "tiles_resident": stats.tiles_resident,
        "draw_calls": stats.draw_calls,
        "cpu_ms": stats.cpu_frame_ms,
        "cpu_select_ms": stats.cpu_select_ms,
        "gpu_ms": stats.gpu_ms,
        "gpu_timed_by": stats.gpu_timed_by,
        "terrain_nodes": stats.terrain_nodes,
        "nodes_visited": stats.nodes_visited,
        "meshes_built": stats.meshes_built,
        "nodes_dropped": stats.nodes_dropped,
        "entities_drawn": stats.entities_drawn,
        "puffs_drawn": stats.puffs_drawn,
        "puff_gpu_ms": stats.puff_gpu_ms,
        "illuminance_lux": stats.illuminance_lux,
        "exposure_ev": stats.exposure_ev,
        "view_adaptation_ev": stats.view_adaptation_ev,
        "cloud_layers_drawn": stats.cloud_layers_drawn,
        "cloud_gpu_ms": stats.cloud_gpu_ms,
        "bolt_lines_drawn": stats.bolt_lines_drawn,
        "light_points": stats.light_points,
        "precipitation_particles": stats.precipitation_particles,
        "klod": stats.klod,
        "klod_nominal": stats.klod_nominal,
        "overload": stats.overload,
        "adapter": gpu.describe(),
        "size": [view.width_px, view.height_px],
        "fov_deg": [view.fov.left_deg + view.fov.right_deg, view.fov.down_deg + view.fov.up_deg],
        "eye": [view.eye.lat_deg, view.eye.lon_deg, view.eye.alt_m],
    })
}

/// Writes an image as PNG, through a temporary file renamed into place.
pub fn write_png(image: &Image, path: &Path) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let tmp = tempfile::NamedTempFile::new_in(dir)
        .with_context(|| format!("cannot write into {}", dir.display()))?;
    {
        let mut encoder = png::Encoder::new(
            std::io::BufWriter::new(tmp.as_file()),
            image.width,
            image.height,
        );
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder
            .write_header()
            .with_context(|| format!("cannot write {}", path.display()))?;
        writer
            .write_image_data(&image.rgba)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// Opens a database with its cache, the GPU and a renderer.
pub fn open(db: &Path, config: &Config) -> anyhow::Result<(Arc<TileCache>, Renderer)> {
    let cache = crate::dynterrain::open_cache(db, &config.paging)?;
    let gpu = Gpu::headless()?;
    let mut renderer = Renderer::new(gpu, &cache, cig_render::FRAME_FORMAT);
    config.configure_renderer(&mut renderer)?;
    Ok((cache, renderer))
}

pub fn run(args: &RenderArgs, config: &Config) -> anyhow::Result<()> {
    let mut view = parse_view(&args.eye, &args.hpr, &args.fov, &args.size)?;
    let unix_time_s = parse_time(&args.time)?;
    let periscope = args
        .periscope
        .as_deref()
        .map(crate::sea::parse_periscope)
        .transpose()?;
    let refraction_k = crate::sea::parse_refraction(&args.refraction)?;
    let sea_conditions =
        crate::sea::conditions_from_args(args.sea_state, args.sea_wind.as_deref())?;
    let mut sea_waves = Vec::new();
    let mut regional_waves = Vec::new();
    for text in &args.sea_waves {
        match crate::sea::parse_wave(text)? {
            (wave, None) => sea_waves.push(wave),
            (wave, Some(region)) => regional_waves.push((wave, region)),
        }
    }
    if !args.sea_waves.is_empty() && sea_conditions.is_none() {
        bail!("--sea-wave needs a sea: give --sea-state or --sea-wind (0 for a swell alone)");
    }
    if !(args.max_pixel_error.is_finite() && args.max_pixel_error >= 0.0) {
        bail!(
            "--max-pixel-error {} must be 0 or more",
            args.max_pixel_error
        );
    }
    if !(args.visibility.is_finite() && args.visibility > 0.0) {
        bail!(
            "--visibility {} must be more than 0 metres",
            args.visibility
        );
    }
    let ground_fog = args
        .ground_fog
        .as_deref()
        .map(|text| -> anyhow::Result<cig_scene::FogLayer> {
            let v = parse_numbers(text, "--ground-fog", &[2])?;
            if !(v[1] > 0.0 && (-1000.0..=20_000.0).contains(&v[0])) {
                bail!("--ground-fog \"{text}\": the top must lie in -1000..20000 m and the visibility be more than 0 m");
            }
            Ok(cig_scene::FogLayer {
                top_m: v[0],
                visibility_m: v[1],
            })
        })
        .transpose()?;
    let fog_mode = FogMode::parse(&args.fog)
        .with_context(|| format!("--fog \"{}\" is not off, linear, exp or exp2", args.fog))?;
    let sky_model = match args.sky.to_ascii_lowercase().as_str() {
        "physical" => cig_scene::lighting::SkyModel::Physical,
        "flat" => cig_scene::lighting::SkyModel::Flat,
        other => bail!("--sky \"{other}\" is not physical or flat"),
    };
    if !(args.exposure_ev.is_finite() && (-10.0..=10.0).contains(&args.exposure_ev)) {
        bail!("--exposure-ev {} must lie in -10..10", args.exposure_ev);
    }
    if let Some(ev) = args.fixed_exposure_ev {
        if !(ev.is_finite() && (-20.0..=20.0).contains(&ev)) {
            bail!("--fixed-exposure-ev {ev} must lie in -20..20");
        }
    }
    let (specs, motions): (Vec<EntitySpec>, Vec<EntityMotion>) = args
        .entities
        .iter()
        .enumerate()
        .map(|(i, text)| parse_entity(text, i as u32 + 1))
        .collect::<anyhow::Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    let fires: Vec<(String, FireSpec)> = args
        .smoke
        .iter()
        .map(|text| Ok((text.clone(), parse_smoke(text)?)))
        .collect::<anyhow::Result<_>>()?;
    let wind = parse_wind(&args.wind)?;
    if args.clouds.len() > cig_environment::clouds::MAX_CLOUD_LAYERS {
        bail!(
            "--cloud is given {} times; at most {} layers",
            args.clouds.len(),
            cig_environment::clouds::MAX_CLOUD_LAYERS
        );
    }
    let clouds: Vec<cig_environment::clouds::CloudLayer> = args
        .clouds
        .iter()
        .enumerate()
        .map(|(i, text)| parse_cloud(text, i as u64 + 1))
        .collect::<anyhow::Result<_>>()?;
    let precipitation = match (&args.rain, &args.snow) {
        (Some(text), _) => Some(parse_precipitation(
            text,
            cig_environment::PrecipitationKind::Rain,
        )?),
        (None, Some(text)) => Some(parse_precipitation(
            text,
            cig_environment::PrecipitationKind::Snow,
        )?),
        (None, None) => None,
    };
    let lightning = args.lightning.as_deref().map(parse_lightning).transpose()?;
    let klod = args
        .klod
        .map(|k| cig_scene::detail::validate_klod(k).map_err(|e| anyhow::anyhow!("--klod: {e}")))
        .transpose()?;
    let culture = on_or_off("--culture", &args.culture)?;
    let culture_occlusion = args
        .culture_occlusion
        .as_deref()
        .map(|v| on_or_off("--culture-occlusion", v))
        .transpose()?;
    let correction =
        crate::display::read_display_correction(args.warp.as_deref(), args.blend.as_deref())?;
    let nvg = crate::thermal_view::parse_nvg(&args.sensor, args.nvg_gain, &args.phosphor)?;
    let sensor = crate::thermal_view::parse_sensor(&crate::thermal_view::SensorOptions {
        sensor: if nvg.is_some() {
            "visible"
        } else {
            &args.sensor
        },
        polarity: &args.polarity,
        gain: args.gain,
        level: args.level,
        noise_k: args.noise,
        display: &args.display,
        ac_coupling_us: args.ac_coupling_us,
        line_dropout: args.line_dropout,
    })?;
    let (air_min_c, air_max_c) = crate::thermal_view::parse_air(&args.air_c)?;
    let engines_running = match args.engines.as_str() {
        "running" => true,
        "off" => false,
        other => bail!("--engines \"{other}\" is not running or off"),
    };
    let (cache, mut renderer) = open(&args.db, config)?;
    renderer.set_display_correction(Some(correction));
    renderer.detail.klod = klod;
    if let Some(occlusion) = culture_occlusion {
        renderer.culture_occlusion = occlusion;
    }
    let geoid = GeoidLookup::new(&cache.database().manifest().geoid);
    if let Some((height_m, magnification)) = periscope {
        // The head above mean sea level; the field 48 degrees over the magnification.
        view.eye.alt_m = geoid.undulation_m(view.eye.lat_deg, view.eye.lon_deg) + height_m;
        view.fov = FovDeg::from_horizontal(
            magnification.field_of_view_deg(),
            view.width_px,
            view.height_px,
        );
    }
    let mut session = QuerySession::new(Arc::clone(&cache));
    // An eye inside the terrain is drawn from its surface, with a word.
    let mut views = [view];
    for lifted in cig_scene::lift_eyes_above_terrain(&mut session, &mut views) {
        tracing::warn!("{lifted}");
    }
    let [view] = views;
    let mut entities = Vec::new();
    let mut loaded = Vec::new();
    for spec in &specs {
        let lower = spec.model.to_ascii_lowercase();
        if (lower.ends_with(".gltf") || lower.ends_with(".glb")) && !loaded.contains(&spec.model) {
            let model = cig_render::load_gltf_model(Path::new(&spec.model), &spec.model)?;
            renderer.set_models(vec![model]);
            loaded.push(spec.model.clone());
        }
    }
    for spec in &specs {
        if !renderer.model_names().contains(&spec.model) {
            bail!(
                "--entity: no model \"{}\" (built-in: {})",
                spec.model,
                renderer.model_names().join(", ")
            );
        }
        entities.push(
            place_entity(&mut session, spec)
                .with_context(|| format!("cannot clamp entity {} to the terrain", spec.model))?,
        );
    }
    let lights = args
        .lights
        .iter()
        .map(|text| parse_light(text))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let flares = args
        .flares
        .iter()
        .map(|text| parse_flare(text, unix_time_s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut snapshot = FrameSnapshot::new(unix_time_s, vec![view]);
    // Lights and flares must stand over the database (their ground is asked for).
    for (text, light) in args.lights.iter().zip(&lights) {
        let at = Geodetic::from_ecef(light.position_ecef_m);
        session
            .hot(at.lat_deg, at.lon_deg)
            .with_context(|| format!("--light \"{text}\" is outside the database"))?;
    }
    snapshot.lights = lights;
    for (text, flare) in args.flares.iter().zip(&flares) {
        let ground = session
            .hot(flare.start.lat_deg, flare.start.lon_deg)
            .with_context(|| format!("--flare \"{text}\" is outside the database"))?
            .height_ellipsoid_m();
        if flare.start.alt_m <= ground {
            bail!("--flare \"{text}\": the flare is below the ground ({ground:.0} m there)");
        }
        snapshot
            .lights
            .extend(flare.light_at(unix_time_s, Some(ground)));
    }
    snapshot.culture = culture;
    snapshot.fog = Fog::from_visibility(fog_mode, args.visibility);
    if let Some(p) = precipitation {
        // The rain's or snow's extinction adds to the air's.
        snapshot.fog = Fog::from_visibility(fog_mode, p.combined_visibility_m(args.visibility));
        let to = (wind.from_deg + 180.0).to_radians();
        snapshot.precipitation = Some(cig_scene::PrecipitationDraw {
            precipitation: p,
            wind_en_mps: [wind.speed_mps * to.sin(), wind.speed_mps * to.cos()],
            seed: 1,
        });
    }
    let mut bolt_note = String::new();
    if let Some((seed, distance_m)) = lightning {
        let (bolt, flash_lux, made) = lightning_bolt(&mut session, &view, seed, distance_m);
        bolt_note = format!(
            ", a bolt of {} segments generated in {:.0} us, flash {flash_lux:.2} lux",
            made.segments, made.generation_us
        );
        snapshot.bolts = vec![bolt];
        snapshot.flash_lux = flash_lux;
    }
    snapshot.ground_fog = ground_fog;
    snapshot.sky = cig_scene::lighting::SkySettings {
        model: sky_model,
        exposure_compensation_ev: args.exposure_ev,
        fixed_exposure_ev: args.fixed_exposure_ev,
    };
    snapshot.max_pixel_error = args.max_pixel_error;
    snapshot.refraction_k = refraction_k;
    snapshot.wireframe = args.wireframe;
    // The share of a periscope's window under water.
    let mut wash = 0.0;
    if let Some(conditions) = sea_conditions {
        // The sea `cig serve` draws and answers on this database at this time (seed 1).
        let (lat_deg, lon_deg) = cache.database().layout().grid.centre_deg();
        let mut world_sea =
            WorldSea::of_conditions(Some(conditions), cig_ig::sea::Water::of_scenario(None), 1)
                .with_waves(sea_waves)
                .and_then(|sea| sea.with_regional_waves(regional_waves))
                .context("--sea-wave")?;
        world_sea
            .update(
                &cig_ig::session::EnvironmentState::default(),
                None,
                cig_scene::sea::sea_origin(lat_deg, lon_deg),
                unix_time_s,
                &std::collections::BTreeMap::new(),
            )
            .context("the sea")?;
        let sea = world_sea.now().context("the sea")?;
        if let Some((height_m, _)) = periscope {
            wash = crate::sea::wash_over(sea.surface(), sea.draw(), view.eye, height_m)?;
        }
        // Ships float: on the sea under them, pitched and rolled by its waves.
        for (entity, EntityMotion { speed_mps, .. }) in entities.iter_mut().zip(&motions) {
            if cig_scene::sea::builtin_hull(&entity.model).is_some() {
                let p = entity.position;
                let course = entity.orientation.heading_deg.to_radians();
                let pose = sea.float(
                    &session,
                    &entity.model,
                    entity.orientation,
                    Clamp::HeightAndAttitude,
                    [p.lat_deg, p.lon_deg, 0.0],
                    [speed_mps * course.sin(), speed_mps * course.cos()],
                    sea.draw().level_m,
                    None,
                );
                entity.position = pose.position;
                entity.orientation = pose.orientation;
            }
        }
        // Ships under way leave their wakes, along the circles they turn on.
        snapshot.wakes = entities
            .iter()
            .zip(&motions)
            .filter_map(|(e, motion)| {
                cig_scene::sea::WakeDraw::of_ship(
                    &e.model,
                    e.position,
                    e.orientation.heading_deg,
                    motion.speed_mps,
                )
                .map(|wake| wake.turning(motion.turn_deg_s))
            })
            .collect();
        snapshot.sea = Some(Arc::clone(sea.draw()));
    }
    snapshot.entities = entities;
    snapshot.cloud_cover_fraction = cig_environment::cloud_cover_fraction(&clouds);
    snapshot.cloud_layers = clouds;
    // The pattern's origin: the eye's whole degrees (the same clouds for nearby eyes).
    snapshot.cloud_origin = cig_environment::CloudOrigin {
        lat_deg: view.eye.lat_deg.round(),
        lon_deg: view.eye.lon_deg.round(),
    };
    snapshot.puff_origin_ecef_m = view.eye.to_ecef();
    snapshot.puffs = fire_puffs(
        &mut session,
        &fires,
        wind,
        unix_time_s,
        snapshot.puff_origin_ecef_m,
    )?;
    if let Some(sensor) = sensor {
        let time = cig_environment::UtcTime::from_unix_seconds(unix_time_s)
            .map_err(|e| anyhow::anyhow!("--time: {e}"))?;
        let ground_alt_m = session
            .hot(view.eye.lat_deg, view.eye.lon_deg)
            .map_or(0.0, |h| h.height_ellipsoid_m());
        let scene = crate::thermal_view::still_thermal_scene(
            view.eye.lat_deg,
            view.eye.lon_deg,
            ground_alt_m,
            time,
            &crate::thermal_view::FrameWeather {
                air_min_c,
                air_max_c,
                rh_pct: args.rh,
                wind_mps: wind.speed_mps,
                cloud_cover: snapshot.cloud_cover_fraction,
                visibility_m: args.visibility,
            },
            &snapshot.entities,
            engines_running,
        )?;
        snapshot.sensors = vec![Some(sensor)];
        snapshot.thermal = Some(Arc::new(scene));
    }
    snapshot.nvg = vec![nvg];
    cache.update(&[view.eye]);
    cache.wait_idle();
    cig_render::load_for_view(&mut renderer, &cache, &snapshot, 0, 64)?;
    let (mut image, stats) = cig_render::render_image(&mut renderer, &cache, &snapshot, 0)?;
    // A picture the GPU rejected part of is not written over what is on disk.
    if let Some((count, first)) = renderer.gpu().take_errors() {
        anyhow::bail!(
            "the GPU rejected this frame's work ({count} errors; the first: {first}), nothing written to {}",
            args.out.display()
        );
    }
    if periscope.is_some() {
        crate::sea::draw_wash(&mut image.rgba, image.width, image.height, wash);
        crate::sea::draw_reticle(&mut image, &view);
    }
    write_png(&image, &args.out)?;
    if let Some(path) = &args.stats {
        let json = stats_json(&stats, renderer.gpu(), &view);
        let text = serde_json::to_string_pretty(&json)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    eprintln!(
        "rendered {}x{} to {}: {} triangles, {} nodes, {} puffs, {} draw calls, cpu {:.1} ms, gpu {:.1} ms ({}){bolt_note}",
        view.width_px,
        view.height_px,
        args.out.display(),
        stats.triangles,
        stats.terrain_nodes,
        stats.puffs_drawn,
        stats.draw_calls,
        stats.cpu_frame_ms,
        stats.gpu_ms,
        renderer.gpu().describe()
    );
    Ok(())
}

/// `true` for "on", `false` for "off" (any case); otherwise a one-line error naming `option`.
fn on_or_off(option: &str, value: &str) -> anyhow::Result<bool> {
    match value.to_ascii_lowercase().as_str() {
        "on" => Ok(true),
        "off" => Ok(false),
        other => bail!("{option} \"{other}\" is not on or off"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_entity_takes_its_speed_and_turn_and_refuses_them_out_of_range() {
        let (spec, motion) =
            parse_entity("destroyer,36,-121,0,90,speed=10,turn=-2.5", 1).expect("parsed");
        assert_eq!(spec.orientation.heading_deg, 90.0);
        assert_eq!(
            motion,
            EntityMotion {
                speed_mps: 10.0,
                turn_deg_s: -2.5
            }
        );
        let (_, motion) = parse_entity("tank,36,-121,0", 2).expect("parsed");
        assert_eq!(motion, EntityMotion::default());
        for (bad, needle) in [
            ("destroyer,36,-121,0,0,speed=50", "speed"),
            ("destroyer,36,-121,0,0,turn=11", "turn"),
            ("destroyer,36,-121,0,0,turn=NaN", "turn"),
            ("destroyer,36,-121,0,0,yaw=3", "unknown option"),
            (
                "destroyer,36,-121,0,0,clamp,speed=1,turn=1,x",
                "is not MODEL",
            ),
        ] {
            let e = format!("{:#}", parse_entity(bad, 1).expect_err(bad));
            assert!(e.contains(needle) && !e.contains('\n'), "{bad}: {e}");
        }
    }
}
