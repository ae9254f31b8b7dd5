//! `cig view`: a window over a database with a free-flying camera and an operator panel.

use crate::cli::ViewArgs;
use crate::config::Config;
use crate::render::{parse_numbers, parse_size, parse_time, write_png};
use anyhow::{bail, Context};
use cig_geo::Geodetic;
use cig_render::{ViewerError, ViewerOptions};
use cig_scene::lighting::FogMode;
use cig_scene::Hpr;
use cig_terrain::TileCache;

/// Near the south edge of the database, a little above its highest point, in the middle.
pub fn default_eye(cache: &TileCache) -> Geodetic {
    let manifest = cache.database().manifest();
    let g = &manifest.layout.grid;
    let lat = g.south_lat_deg + 0.05 * (g.north_lat_deg() - g.south_lat_deg);
    let lon = 0.5 * (g.west_lon_deg + g.east_lon_deg());
    Geodetic::new(lat, lon, f64::from(manifest.max_elevation_m) + 300.0)
}

pub fn run(args: &ViewArgs, config: &Config) -> anyhow::Result<()> {
    let eye = args
        .eye
        .as_deref()
        .map(|text| parse_numbers(text, "--eye", &[3]).map(|e| Geodetic::new(e[0], e[1], e[2])))
        .transpose()?;
    let o = parse_numbers(&args.hpr, "--hpr", &[3])?;
    let orientation = Hpr {
        heading_deg: o[0],
        pitch_deg: o[1],
        roll_deg: o[2],
    };
    let (width_px, height_px) = parse_size(&args.size)?;
    let unix_time_s = parse_time(&args.time)?;
    if !(args.fov.is_finite() && args.fov > 0.0 && args.fov < 180.0) {
        bail!("--fov {} must lie between 0 and 180 degrees", args.fov);
    }
    if !(args.max_pixel_error.is_finite() && (0.0..=8.0).contains(&args.max_pixel_error)) {
        bail!(
            "--max-pixel-error {} must lie between 0 and 8 pixels",
            args.max_pixel_error
        );
    }
    if !(args.visibility.is_finite() && args.visibility > 0.0) {
        bail!(
            "--visibility {} must be more than 0 metres",
            args.visibility
        );
    }
    if !(args.speed.is_finite() && args.speed > 0.0) {
        bail!("--speed {} must be more than 0 m/s", args.speed);
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let fog_mode = FogMode::parse(&args.fog)
        .with_context(|| format!("--fog \"{}\" is not off, linear, exp or exp2", args.fog))?;
    let correction =
        crate::display::read_display_correction(args.warp.as_deref(), args.blend.as_deref())?;
    let cache = crate::dynterrain::open_cache(&args.db, &config.paging)?;
    let eye = eye.unwrap_or_else(|| default_eye(&cache));
    let mut options = ViewerOptions::new(eye, orientation);
    options.title = format!("cig view: {}", args.db.display());
    options.horizontal_fov_deg = args.fov;
    options.width_px = width_px;
    options.height_px = height_px;
    options.unix_time_s = unix_time_s;
    options.visibility_m = args.visibility;
    options.fog_mode = fog_mode;
    options.max_pixel_error = args.max_pixel_error;
    options.wireframe = args.wireframe;
    options.speed_mps = args.speed;
    options.exit_after_frames = args.frames;
    options.capture_last_frame = args.screenshot.is_some();
    options.overload = config.overload()?;
    options.display_correction = Some(correction);
    let report = match cig_render::run_viewer(cache, options) {
        Ok(report) => report,
        Err(ViewerError::NoDisplay(reason)) => {
            bail!("cig view needs a display; use cig render for off-screen frames ({reason})")
        }
        Err(ViewerError::Render(cig_render::RenderError::View(e))) => {
            bail!("the first view cannot be drawn: {e}")
        }
        Err(e) => return Err(e.into()),
    };
    if let Some(path) = &args.screenshot {
        match &report.last_frame {
            Some(image) => write_png(image, path)?,
            None => bail!(
                "no frame was drawn, so there is no screenshot for {}",
                path.display()
            ),
        }
    }
    let fps = if report.seconds > 0.0 {
        report.frames.saturating_sub(1) as f64 / report.seconds
    } else {
        0.0
    };
    eprintln!(
        "viewed {} frames in {:.1} s ({fps:.1} fps, {} triangles in the last) on {}, {}{}",
        report.frames,
        report.seconds,
        report.last_stats.triangles,
        report.adapter,
        report.colour_format,
        args.screenshot
            .as_ref()
            .map(|p| format!("; screenshot {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}
