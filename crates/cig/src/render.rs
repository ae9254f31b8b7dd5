//! `cig render`: one frame off-screen, to PNG, with optional statistics.

use crate::cli::RenderArgs;
use crate::config::Config;
use anyhow::{bail, Context};
use cig_geo::Geodetic;
use cig_render::{FrameStats, Gpu, Image, Renderer};
use cig_scene::lighting::{Fog, FogMode};
use cig_scene::snapshot::{place_entity, Clamp, EntitySpec};
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::{QuerySession, TileCache};
use cig_terrain_io::store::open_database;
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
pub fn parse_entity(text: &str, id: u32) -> anyhow::Result<EntitySpec> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() < 4 || parts.len() > 6 {
        bail!("--entity \"{text}\" is not MODEL,LAT,LON,ALT[,HEADING[,clamp]]");
    }
    let nums = parse_numbers(
        &parts[1..4.max(parts.len().min(5))].join(","),
        "--entity",
        &[3, 4],
    )?;
    let clamp = match parts.get(5) {
        None => Clamp::None,
        Some(&"clamp") => Clamp::HeightAndAttitude,
        Some(other) => bail!("--entity \"{text}\": unknown option \"{other}\" (only \"clamp\")"),
    };
    Ok(EntitySpec {
        id,
        model: parts[0].to_string(),
        position: Geodetic::new(nums[0], nums[1], nums[2]),
        orientation: Hpr {
            heading_deg: nums.get(3).copied().unwrap_or(0.0),
            ..Default::default()
        },
        clamp,
    })
}

/// The frame statistics as JSON.
pub fn stats_json(stats: &FrameStats, gpu: &Gpu, view: &View) -> serde_json::Value {
    serde_json::json!({
        "triangles": stats.triangles,
        "terrain_triangles": stats.terrain_triangles,
        "model_triangles": stats.model_triangles,
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
        "adapter": gpu.describe(),
        "size": [view.width_px, view.height_px],
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
    let database = Arc::new(open_database(db)?);
    let cache = Arc::new(TileCache::new(database, config.paging.clone())?);
    let gpu = Gpu::headless()?;
    let renderer = Renderer::new(gpu, &cache, cig_render::FRAME_FORMAT);
    Ok((cache, renderer))
}

pub fn run(args: &RenderArgs, config: &Config) -> anyhow::Result<()> {
    let view = parse_view(&args.eye, &args.hpr, &args.fov, &args.size)?;
    let unix_time_s = parse_time(&args.time)?;
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
    let fog_mode = FogMode::parse(&args.fog)
        .with_context(|| format!("--fog \"{}\" is not off, linear, exp or exp2", args.fog))?;
    let specs: Vec<EntitySpec> = args
        .entities
        .iter()
        .enumerate()
        .map(|(i, text)| parse_entity(text, i as u32 + 1))
        .collect::<anyhow::Result<_>>()?;
    let (cache, mut renderer) = open(&args.db, config)?;
    let mut session = QuerySession::new(Arc::clone(&cache));
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
    let mut snapshot = FrameSnapshot::new(unix_time_s, vec![view]);
    snapshot.fog = Fog::from_visibility(fog_mode, args.visibility);
    snapshot.max_pixel_error = args.max_pixel_error;
    snapshot.wireframe = args.wireframe;
    snapshot.entities = entities;
    cache.update(&[view.eye]);
    cache.wait_idle();
    cig_render::load_for_view(&mut renderer, &cache, &snapshot, 0, 64)?;
    let (image, stats) = cig_render::render_image(&mut renderer, &cache, &snapshot, 0)?;
    write_png(&image, &args.out)?;
    if let Some(path) = &args.stats {
        let json = stats_json(&stats, renderer.gpu(), &view);
        let text = serde_json::to_string_pretty(&json)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    eprintln!(
        "rendered {}x{} to {}: {} triangles, {} nodes, {} draw calls, cpu {:.1} ms, gpu {:.1} ms ({})",
        view.width_px,
        view.height_px,
        args.out.display(),
        stats.triangles,
        stats.terrain_nodes,
        stats.draw_calls,
        stats.cpu_frame_ms,
        stats.gpu_ms,
        renderer.gpu().describe()
    );
    Ok(())
}
