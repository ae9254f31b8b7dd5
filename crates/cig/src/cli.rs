//! Command-line syntax.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "cig",
    version,
    about = "cig: a real-time computer image generator for training simulators"
)]
pub struct Cli {
    /// Configuration file (TOML); `cig config default` prints one with every setting.
    #[arg(long, global = true, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// More log output (-v info, -vv debug); CIG_LOG overrides (tracing filter syntax).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Build and inspect terrain databases.
    #[command(subcommand)]
    Db(DbCommand),
    /// Ask a database the host's terrain questions.
    #[command(subcommand)]
    Query(QueryCommand),
    /// Measure performance.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Render one frame off-screen to a PNG file.
    #[command(allow_negative_numbers = true)]
    Render(Box<RenderArgs>),
    /// Fly over a database in a window, with an operator panel (needs a display).
    #[command(allow_negative_numbers = true)]
    View(ViewArgs),
    /// Smoke plume model: Briggs/ISC3 rise and McMullen dispersion at one downwind distance.
    #[command(allow_negative_numbers = true)]
    Plume(PlumeArgs),
    /// Build the demo database if needed and show what cig does with it.
    Demo(DemoArgs),
    /// Configuration helpers.
    #[command(subcommand)]
    Config(ConfigCommand),
    /// Sun and moon positions, the moon's phase, rise/set and twilight times of the local
    /// day, and the natural illuminance, for a place and a UTC time (1900-2100).
    Ephem(EphemArgs),
    /// Be the image generator of a CIGI host (3.3 or 4.0), optionally in a DIS exercise.
    #[command(allow_negative_numbers = true)]
    Serve(ServeArgs),
    /// A small scripted CIGI host, for demos and tests.
    Host(HostArgs),
    /// DIS (IEEE 1278.1) diagnostic tools: print received PDUs, send Entity State PDUs.
    #[command(subcommand)]
    Dis(DisCommand),
    /// Level of detail of models: the detail control parameter of the GE study.
    #[command(subcommand)]
    Lod(LodCommand),
    /// Thermal infrared physics: band radiance, surface temperatures.
    #[command(subcommand)]
    Ir(IrCommand),
    /// The sea: wave statistics of the simulated surface, the horizon and hull-down ranges.
    #[command(subcommand)]
    Sea(SeaCommand),
}

#[derive(Subcommand)]
pub enum SeaCommand {
    /// Significant wave height, peak period and whitecap coverage measured from the simulated
    /// sea surface (cig's FFT cascades) for a wind and fetch or a WMO sea state code.
    #[command(allow_negative_numbers = true)]
    Stats(SeaStatsArgs),
    /// The sea horizon, its dip and how much of a target is hidden below it, on the round
    /// earth with standard terrestrial refraction (k = 0.13) or without.
    #[command(allow_negative_numbers = true)]
    Horizon(SeaHorizonArgs),
}

#[derive(Args)]
pub struct SeaStatsArgs {
    /// Wind speed 10 m above the sea, m/s (0-60).
    #[arg(long, conflicts_with = "sea_state")]
    pub wind_mps: Option<f64>,
    /// Fetch, km (default: a fully developed sea, Pierson-Moskowitz).
    #[arg(long, requires = "wind_mps")]
    pub fetch_km: Option<f64>,
    /// WMO sea state code, 0-9: a fully developed sea in the middle of the code's range.
    #[arg(long)]
    pub sea_state: Option<f64>,
    /// Direction the wind blows from, degrees true.
    #[arg(long, default_value_t = 270.0)]
    pub wind_from_deg: f64,
    /// Seed of the wave field (every IG of an exercise uses the same one).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SeaHorizonArgs {
    /// The eye's height above the sea, metres.
    #[arg(long)]
    pub eye_m: f64,
    /// A target's top (masthead) height above the sea, metres: the range at which it sinks
    /// below the horizon.
    #[arg(long)]
    pub top_m: Option<f64>,
    /// A target's range, metres: the height hidden below the horizon there.
    #[arg(long)]
    pub range_m: Option<f64>,
    /// Refraction coefficient k (0: the geometric horizon; default 0.13, standard).
    #[arg(long, default_value_t = 0.13)]
    pub refraction_k: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum IrCommand {
    /// Black-body radiance in a wavelength band (Planck integral by converging series).
    Radiance(IrRadianceArgs),
    /// Surface temperature of a material at a place and time, from the layered-slab model
    /// spun up over the two days before.
    #[command(allow_negative_numbers = true)]
    SurfaceTemp(IrSurfaceTempArgs),
    /// Band transmittance and path radiance of the atmosphere along a path (LOWTRAN 7 table).
    #[command(allow_negative_numbers = true)]
    Transmittance(IrTransmittanceArgs),
}

#[derive(Args)]
pub struct IrTransmittanceArgs {
    /// The band: 8-12 (LWIR) or 3-5 (MWIR), micrometres.
    #[arg(long, value_name = "LO-HI")]
    pub band: String,
    /// Path length, metres (0 or more).
    #[arg(long)]
    pub range_m: f64,
    /// Model atmosphere: us-standard, tropical, mid-latitude-summer, mid-latitude-winter,
    /// subarctic-summer, subarctic-winter (its sea-level temperature and humidity).
    #[arg(long, default_value = "us-standard")]
    pub atmosphere: String,
    /// Air temperature at the base, Celsius (replaces the model's).
    #[arg(long)]
    pub air_temp_c: Option<f64>,
    /// Relative humidity at the base, percent (replaces the model's).
    #[arg(long)]
    pub rh: Option<f64>,
    /// Aerosol model: none, rural, maritime, urban.
    #[arg(long, default_value = "none")]
    pub aerosol: String,
    /// Visibility (meteorological range), metres; default the aerosol model's (23 km, urban
    /// 5 km).
    #[arg(long)]
    pub visibility_m: Option<f64>,
    /// Height of the (horizontal) path above sea level, metres.
    #[arg(long, default_value_t = 0.0)]
    pub altitude_m: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct BenchSensorArgs {
    /// Terrain database directory.
    #[arg(long)]
    pub db: PathBuf,
    /// Frame size, pixels.
    #[arg(long, default_value = "640x360")]
    pub size: String,
    /// Vehicles in the frame.
    #[arg(long, default_value_t = 50)]
    pub entities: usize,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct BenchSeaArgs {
    /// Terrain database directory (the sea is measured beyond its western edge).
    #[arg(long)]
    pub db: PathBuf,
    /// Frame size, pixels.
    #[arg(long, default_value = "640x360")]
    pub size: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct IrRadianceArgs {
    /// The band in micrometres: 8-12 (LWIR), 3-5 (MWIR) or any LO-HI.
    #[arg(long, value_name = "LO-HI")]
    pub band: String,
    /// Temperature, kelvin (above 0).
    #[arg(long, allow_negative_numbers = true)]
    pub temp_k: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct IrSurfaceTempArgs {
    /// The material: water, sand, dry_clay, grass, forest, rock, snow, paved_road, dirt_road,
    /// hull_paint, superstructure, vehicle_armour, glass, rubber_tracks, clothing, skin,
    /// canopy_foliage, building_wall.
    #[arg(long)]
    pub material: String,
    /// Geodetic latitude, degrees, north positive.
    #[arg(long)]
    pub lat: f64,
    /// Longitude, degrees, east positive.
    #[arg(long)]
    pub lon: f64,
    /// The instant, ISO 8601 (no offset means UTC).
    #[arg(long, value_name = "ISO8601")]
    pub time: String,
    /// Daily minimum air temperature, Celsius (at sunrise).
    #[arg(long, default_value_t = 10.0)]
    pub air_min_c: f64,
    /// Daily maximum air temperature, Celsius (at 14:00 local solar time).
    #[arg(long, default_value_t = 24.0)]
    pub air_max_c: f64,
    /// Relative humidity, percent 0..100.
    #[arg(long, default_value_t = 50.0)]
    pub rh: f64,
    /// Wind speed, m/s.
    #[arg(long, default_value_t = 3.0)]
    pub wind_mps: f64,
    /// Cloud cover fraction 0..1.
    #[arg(long, default_value_t = 0.0)]
    pub cloud: f64,
    /// Deep-ground temperature at about 1 m, Celsius (default: the air's daily mean).
    #[arg(long)]
    pub deep_ground_c: Option<f64>,
    /// Angle of the surface's normal from straight up, degrees: 0 horizontal, 90 a wall.
    #[arg(long, default_value_t = 0.0)]
    pub tilt_deg: f64,
    /// Azimuth the surface's normal points to, degrees from north through east.
    #[arg(long, default_value_t = 180.0)]
    pub facing_deg: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum LodCommand {
    /// The detail control parameter N_e = K_LOD r_c / R_s of a model (source 004, Eq 16) and
    /// the step of Table 3 (1.5 step^2, steps 1-8) it reaches (0: below step 1, fading out).
    #[command(allow_negative_numbers = true)]
    Ne(LodNeArgs),
}

#[derive(Args)]
pub struct LodNeArgs {
    /// The model's critical radius, metres.
    #[arg(long)]
    pub radius_m: f64,
    /// Slant range from the eye to the model, metres.
    #[arg(long)]
    pub range_m: f64,
    /// The channel's horizontal field of view, degrees (0..180).
    #[arg(long)]
    pub fov_deg: f64,
    /// The channel's width, pixels.
    #[arg(long)]
    pub width_px: f64,
    /// Use this K_LOD instead of 1 / tan(FOV / width).
    #[arg(long)]
    pub klod: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct ServeArgs {
    /// Terrain database directory.
    #[arg(long)]
    pub db: PathBuf,
    /// Scenario file (TOML): entity-type table, owned entities, default view, DIS settings.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// UDP port the host's messages arrive on.
    #[arg(long, default_value_t = 8004)]
    pub cigi_port: u16,
    /// Where the IG's messages go, HOST:PORT (default: back to the sender of the host's
    /// messages).
    #[arg(long, value_name = "HOST:PORT")]
    pub cigi_host: Option<String>,
    /// Local address of the CIGI port: loopback, any, an address or an interface name.
    #[arg(long, default_value = "loopback")]
    pub cigi_bind: String,
    /// DIS port (joins the exercise even without a [dis] table in the scenario).
    #[arg(long)]
    pub dis_port: Option<u16>,
    /// Local address of the DIS port (overrides the scenario's).
    #[arg(long)]
    pub dis_bind: Option<String>,
    /// Draw off-screen instead of in a window.
    #[arg(long)]
    pub headless: bool,
    /// Draw nothing: answer the host and join the exercise only (a query-only IG, tests).
    #[arg(long)]
    pub no_render: bool,
    /// Frame size (each view).
    #[arg(long, value_name = "WxH", default_value = "640x480")]
    pub size: String,
    /// Write each frame as PNG into this folder (with --headless).
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Stop after N frames (default: run until killed or the window closes).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Frame rate, Hz.
    #[arg(long, default_value_t = 60.0)]
    pub rate_hz: f64,
    /// Simulation start, ISO 8601 UTC (default: the scenario's, else now).
    #[arg(long)]
    pub time: Option<String>,
    /// Database number reported in Start of Frame.
    #[arg(long, default_value_t = 1)]
    pub database_number: i8,
    /// Print the run's counters as one JSON line at the end.
    #[arg(long)]
    pub json: bool,
    /// Draw only the host's views with these identifiers: this process is the display
    /// channel (or channels) of those views; the world runs the same in every channel.
    #[arg(long = "view", value_delimiter = ',', value_name = "ID[,ID...]")]
    pub views: Vec<u16>,
    /// A channel's role: the master answers the host (Start of Frame, HAT/HOT, LOS,
    /// position, environment, collision) and publishes to the exercise; a slave only draws.
    #[arg(long, value_enum, default_value_t = ChannelRole::Master)]
    pub role: ChannelRole,
    /// Forward every datagram of the host to these slave channels, HOST:PORT[,...] (master
    /// only; a slave listens on its --cigi-port).
    #[arg(long, value_delimiter = ',', value_name = "HOST:PORT")]
    pub relay: Vec<String>,
    /// CIGI synchronous mode: draw one frame per host frame, the world on the host's clock
    /// (its IG Control timestamps), so every channel draws frame n from the host's frame n;
    /// a channel behind skips to the newest frame.
    #[arg(long)]
    pub sync: bool,
    /// Stop when no host frame has come for this many seconds (since the last one, or since
    /// serving began), so tests and soak runs end with their host.
    #[arg(long, value_name = "SECONDS")]
    pub idle_exit_s: Option<f64>,
    /// Terrain edits journal: start from the edits in FILE (made with `cig db edits
    /// --export` or an earlier `serve --edits`; created when missing) and append every edit
    /// made while serving (craters from detonations, the host's Terrain Edit Requests, ruts,
    /// other nodes' edits) and every heal, so the terrain's state survives a restart. The database's tiles are never changed.
    #[arg(long, value_name = "FILE")]
    pub edits: Option<PathBuf>,
    /// Exposure: `view` adapts to what the view shows; `natural` keeps the natural
    /// illuminance's, the same in every channel (so no seam). Default: natural when --view
    /// is given or the role is slave, else view.
    #[arg(long, value_enum)]
    pub exposure: Option<ExposureMode>,
    /// Geometric warp of the channel (a mesh of display positions; docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub warp: Option<PathBuf>,
    /// Edge-blend ramps of the channel (docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub blend: Option<PathBuf>,
    /// Frame lock, master: take the slaves' "frame drawn" reports on this UDP port and start
    /// no frame while a slave still draws an older one (with --sync; docs/channels.md).
    #[arg(long, value_name = "PORT")]
    pub lock_port: Option<u16>,
    /// Frame lock, slave: report each frame drawn to the master's --lock-port, HOST:PORT
    /// (with --sync).
    #[arg(long, value_name = "HOST:PORT")]
    pub lock: Option<String>,
    /// Frame lock: the longest a master waits for a slave before taking it out of the lock
    /// (it comes back with its next frame); the wait is eight of the IG's frames, at least
    /// 250 ms, up to this.
    #[arg(long, default_value_t = 1000, value_name = "MS")]
    pub lock_timeout_ms: u64,
    /// Write one JSON line per frame drawn to this file (frame, host frame, wall-clock time,
    /// frame time, host frames applied): the channel's timeline for operators and benchmarks.
    #[arg(long, value_name = "FILE")]
    pub frame_log: Option<PathBuf>,
}

/// What a `cig serve` process is among the channels of one IG.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ChannelRole {
    Master,
    Slave,
}

/// How a channel's exposure is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExposureMode {
    View,
    Natural,
}

#[derive(Args)]
pub struct HostArgs {
    /// Host script (TOML): entities and their paths, view, requests, time.
    #[arg(long)]
    pub script: PathBuf,
    /// The IG, HOST:PORT.
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:8004")]
    pub ig: String,
    /// Local UDP port the IG's messages arrive on (0: any free one).
    #[arg(long, default_value_t = 8005)]
    pub port: u16,
    /// Local address: loopback, any, an address or an interface name.
    #[arg(long, default_value = "loopback")]
    pub bind: String,
    /// Host frames to send (default: the script's).
    #[arg(long)]
    pub frames: Option<u32>,
    /// Frames to keep listening after the last one is sent.
    #[arg(long, default_value_t = 10)]
    pub drain_frames: u32,
    /// One JSON line per answer received, and a summary line.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum DbCommand {
    /// Generate a deterministic synthetic database.
    Synth(SynthArgs),
    /// Import DEM files (GeoTIFF, SRTM .hgt, DTED .dt0/.dt1/.dt2, ESRI .asc) into one database,
    /// optionally with orthoimagery (--imagery).
    Import(ImportArgs),
    /// Add orthoimagery (GeoTIFF, EPSG:4326 or UTM) to a database, replacing its imagery; the
    /// database is unchanged if anything fails.
    Imagery(ImageryArgs),
    /// Replace a database's culture with the culture of a feature file (as `import
    /// --features` reads it; its roads, rivers and lakes are laid only at import); the
    /// database is unchanged if anything fails.
    Culture(CultureArgs),
    /// Describe a database.
    Info(InfoArgs),
    /// Add a crater to a database's terrain edits (kept in DB/edits.jsonl beside its tiles,
    /// which are never changed): from a charge by cube-root scaling in the soil there, or of
    /// an explicit size.
    #[command(allow_negative_numbers = true)]
    Crater(CraterArgs),
    /// List, export, import (merge) or clear a database's terrain edits.
    Edits(EditsArgs),
}

#[derive(Args)]
pub struct CraterArgs {
    pub db: PathBuf,
    /// Where: "LAT,LON" in degrees.
    #[arg(long, value_name = "LAT,LON", allow_hyphen_values = true)]
    pub at: String,
    /// TNT-equivalent charge, kg: the crater's radius and depth follow cube-root scaling with
    /// the coefficients of the ground's material there.
    #[arg(long, allow_negative_numbers = true)]
    pub charge_kg: Option<f64>,
    /// An explicit crater radius, metres (with --depth-m).
    #[arg(long, allow_negative_numbers = true)]
    pub radius_m: Option<f64>,
    /// An explicit crater depth, metres (with --radius-m).
    #[arg(long, allow_negative_numbers = true)]
    pub depth_m: Option<f64>,
    /// The soil is wet (wet soils crater more).
    #[arg(long)]
    pub wet: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct EditsArgs {
    pub db: PathBuf,
    /// Write the database's edits to FILE.
    #[arg(long, value_name = "FILE")]
    pub export: Option<PathBuf>,
    /// Add the edits of FILE (one written by --export or `cig serve --edits`) to the
    /// database's; all or nothing.
    #[arg(long, value_name = "FILE")]
    pub import: Option<PathBuf>,
    /// Remove every edit.
    #[arg(long, conflicts_with_all = ["export", "import"])]
    pub clear: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SynthArgs {
    /// Output database directory.
    #[arg(long)]
    pub out: PathBuf,
    /// South-west corner, "LAT,LON" in degrees.
    #[arg(long, value_name = "LAT,LON", allow_hyphen_values = true)]
    pub origin: String,
    /// Side of the square area, km.
    #[arg(long, allow_negative_numbers = true)]
    pub size_km: f64,
    /// Post spacing, metres.
    #[arg(long, allow_negative_numbers = true)]
    pub spacing_m: f64,
    /// Random seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Make the land fall into open sea on this side: west, east, north or south (a coast;
    /// about the outer third of the area is sea, water at 0 m, and it goes on beyond the edge).
    #[arg(long, value_name = "SIDE")]
    pub sea_side: Option<String>,
    /// Replace the output if it exists.
    #[arg(long)]
    pub force: bool,
}

#[derive(Args)]
pub struct ImportArgs {
    /// Output database directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace the output if it exists.
    #[arg(long)]
    pub force: bool,
    /// DEM files; several are mosaicked into one database.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Orthoimages (GeoTIFF, 8- or 16-bit grey/RGB/RGBA, EPSG:4326 or WGS84 UTM) draped over
    /// the database; finer images are drawn over coarser ones.
    #[arg(long, num_args = 1.., value_name = "IMAGE")]
    pub imagery: Vec<PathBuf>,
    /// Roads, rivers, lakes and culture: a GeoJSON file, WGS84 [lon, lat]. Roads and rivers
    /// are LineStrings (property "type": paved_road, dirt_road or river, and "width_m"), lakes
    /// Polygons ("type": lake, optional "level_m"): roads are painted at their width with
    /// markings and the ground levelled across them; lakes are flat at their level. Culture
    /// ("type": conifer_tree, broadleaf_tree, bush, house, shed, large_building, wall, fence or
    /// power_pole; "height_m", required for buildings, walls and fences; optional "width_m",
    /// "length_m", "heading_deg", "spacing_m") stands on the terrain: Points are single
    /// objects, building Polygons footprints, tree and bush Polygons stands at
    /// "density_per_ha", wall and fence LineStrings cut into segments, power pole LineStrings
    /// a pole every "spacing_m" (default 50 m).
    #[arg(long, value_name = "FILE")]
    pub features: Option<PathBuf>,
    /// Trees and bushes scattered by material: "default" (open woodland in forest, single
    /// trees and bushes on grass) or a TOML file of rules per material (`[forest]
    /// trees_per_ha`, `bushes_per_ha`, `conifer_fraction`, ...; unknown keys refused).
    #[arg(long, value_name = "default|FILE.toml")]
    pub culture_rules: Option<String>,
}

#[derive(Args)]
pub struct ImageryArgs {
    /// Database directory.
    pub db: PathBuf,
    /// Orthoimages (GeoTIFF, 8- or 16-bit grey/RGB/RGBA, EPSG:4326 or WGS84 UTM); finer images
    /// are drawn over coarser ones.
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
}

#[derive(Args)]
pub struct CultureArgs {
    /// Database directory.
    pub db: PathBuf,
    /// GeoJSON feature file whose culture features replace the database's culture (a file
    /// without any removes it).
    pub features: PathBuf,
}

#[derive(Args)]
pub struct InfoArgs {
    pub db: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Also read every tile and report, per level, the geometric error of the level-of-detail
    /// nodes (median, p90, max): how far each level refines at a given pixel error.
    #[arg(long)]
    pub lod_errors: bool,
}

#[derive(Subcommand)]
pub enum QueryCommand {
    /// Height of terrain (and above terrain with --alt) at a point, with normal and material.
    #[command(allow_negative_numbers = true)]
    Hat(HatArgs),
    /// Line of sight between two points (altitudes above the WGS84 ellipsoid).
    #[command(allow_negative_numbers = true)]
    Los(LosArgs),
    /// The soil under a point for a vehicle: Bekker sinkage, compaction resistance, go/no-go.
    #[command(allow_negative_numbers = true)]
    Soil(SoilArgs),
}

#[derive(Args)]
pub struct SoilArgs {
    pub db: PathBuf,
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
    /// The vehicle's mass, kg.
    #[arg(long, allow_negative_numbers = true)]
    pub vehicle_mass_kg: f64,
    /// Its ground contact area (all tracks, wheels or feet together), square metres.
    #[arg(long, allow_negative_numbers = true)]
    pub contact_area_m2: f64,
    /// Running gear: tracked, wheeled or foot.
    #[arg(long, default_value = "tracked")]
    pub gear: String,
    /// The soil is wet.
    #[arg(long)]
    pub wet: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct HatArgs {
    pub db: PathBuf,
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
    /// Altitude of the asking point above the WGS84 ellipsoid, metres: adds height above terrain.
    #[arg(long, allow_negative_numbers = true)]
    pub alt: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct LosArgs {
    pub db: PathBuf,
    pub lat1: f64,
    pub lon1: f64,
    pub alt1: f64,
    pub lat2: f64,
    pub lon2: f64,
    pub alt2: f64,
    /// Terrestrial refraction's coefficient k for the sightline: "standard" (0.13, as the IG
    /// answers its host and draws), "off" (a straight line) or a number in -1..0.9.
    #[arg(
        long,
        value_name = "K",
        default_value = "standard",
        allow_hyphen_values = true
    )]
    pub refraction: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Terrain database benchmarks: HAT and LOS rates, tile loads, build and import times.
    Db(BenchDbArgs),
    /// Orthoimagery import: a synthetic SIZE x SIZE RGB GeoTIFF imported into a scratch
    /// database (time, MB/s, peak memory).
    Imagery(BenchImageryArgs),
    /// Obscurant particle update cost: 32 plumes of 5 x 75 puffs and 200 dust trails of 50.
    Particles(BenchParticlesArgs),
    /// Renderer: a 300 m/s low-level pass, level of detail against full detail in one run.
    Render(BenchRenderArgs),
    /// Culture: triangles and frame time with level-of-detail management against full detail
    /// over the densest area, the overload control through a climb, selection CPU time.
    Culture(BenchCultureArgs),
    /// Network side of the IG: DIS decoding, 10,000 dead-reckoned remote entities, 100 HAT/HOT
    /// requests a frame, CIGI decoding, and (with --flood) a 100,000 PDU/s flood at 60 Hz.
    #[command(allow_negative_numbers = true)]
    Net(BenchNetArgs),
    /// Environment: ephemeris cost per update, and the physical sky, aerial perspective and fog
    /// against a flat sky in the same run (share of the frame).
    Env(BenchEnvArgs),
    /// Display channels: three `cig serve` processes (a master and two slaves) frame-locked
    /// to a host; the spread of their frames, a slave's frame cost against a master's, and a
    /// killed slave's time back on the current frame.
    Channels(BenchChannelsArgs),
    /// Soak: `cig serve` for MINUTES under a host flying at 300 m/s, 200 dead-reckoned DIS
    /// entities, smoke, clouds and a storm; resident memory, frame time, descriptors and
    /// threads watched for drift (exits 1 when they drift).
    Soak(BenchSoakArgs),
    /// The thermal sensor channel: an LWIR frame against the visible frame of the same view
    /// (50 vehicles), the surface table's spin-up and its advance by one second.
    Sensor(BenchSensorArgs),
    /// The sea: the wave cascades' update, 1000 HOT over the sea, a periscope frame at sea
    /// state 5 with three ships against a flat sea.
    Sea(BenchSeaArgs),
    /// Dynamic terrain: a crater applied, and HAT and LOS inside an area of 1000 edits
    /// against the same queries on the unedited terrain.
    Dynterrain(BenchDynterrainArgs),
}

#[derive(Args)]
pub struct BenchDynterrainArgs {
    /// Terrain database directory (edits are made in memory around its centre; its edit
    /// file is not read or changed).
    #[arg(long)]
    pub db: PathBuf,
    /// Frames of the pass under 100 craters a second (60 Hz).
    #[arg(long, default_value_t = 180)]
    pub frames: usize,
    /// Frame size of that pass.
    #[arg(long, default_value = "640x360")]
    pub size: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct BenchChannelsArgs {
    /// Terrain database; default: the demo database "demo-db", built when missing.
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Each channel's frame size.
    #[arg(long, default_value = "320x240")]
    pub size: String,
    /// Host frames a second.
    #[arg(long, default_value_t = 30.0)]
    pub rate_hz: f64,
    /// Seconds of warm-up before measuring.
    #[arg(long, default_value_t = 5.0, value_name = "S")]
    pub warmup_s: f64,
    /// Seconds measured.
    #[arg(long, default_value_t = 20.0, value_name = "S")]
    pub seconds: f64,
    /// Keep the processes' frame logs, output and scenario in this folder.
    #[arg(long, value_name = "DIR")]
    pub keep_dir: Option<PathBuf>,
}

#[derive(Args)]
pub struct BenchSoakArgs {
    /// Terrain database; default: the demo database "demo-db", built when missing.
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Length of the run.
    #[arg(long, default_value_t = 60.0)]
    pub minutes: f64,
    /// Frame size.
    #[arg(long, default_value = "320x240")]
    pub size: String,
    /// Host frames (and IG frames) a second.
    #[arg(long, default_value_t = 60.0)]
    pub rate_hz: f64,
    /// Dead-reckoned DIS entities of the exercise.
    #[arg(long, default_value_t = 200)]
    pub entities: u32,
    /// The eyepoint's speed, m/s.
    #[arg(long, default_value_t = 300.0)]
    pub speed_mps: f64,
    /// Seconds between looks at the process.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub sample_s: f64,
    /// The most resident memory may grow after the warm-up, percent.
    #[arg(long, default_value_t = 2.0)]
    pub rss_growth_max_pct: f64,
    /// Keep the processes' frame logs, output and scenario in this folder.
    #[arg(long, value_name = "DIR")]
    pub keep_dir: Option<PathBuf>,
}

#[derive(Args)]
pub struct BenchEnvArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Terrain database; default: the demo database "demo-db", built when missing.
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Frame size.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Frames along the pass, each drawn both ways every round.
    #[arg(long, default_value_t = 12)]
    pub frames: usize,
    /// Interleaved rounds.
    #[arg(long, default_value_t = 3)]
    pub rounds: usize,
}

#[derive(Args)]
pub struct BenchNetArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Seconds each measure may take.
    #[arg(long, default_value_t = 2.0, value_name = "S")]
    pub seconds: f64,
    /// Terrain database for the HAT/HOT measure; default: the demo database "demo-db", built
    /// when missing.
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Also run the flood: Entity State PDUs into a loopback endpoint while a 60 Hz loop runs.
    #[arg(long)]
    pub flood: bool,
    /// Seconds of flood.
    #[arg(long, default_value_t = 60.0, value_name = "S")]
    pub flood_s: f64,
    /// PDUs per second of the flood.
    #[arg(long, default_value_t = 100_000, value_name = "N")]
    pub flood_rate: u64,
}

#[derive(Args)]
pub struct BenchCultureArgs {
    /// Terrain database directory (with culture).
    #[arg(long)]
    pub db: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Frame size.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Horizontal field of view, degrees.
    #[arg(long, default_value_t = 60.0)]
    pub fov: f64,
    /// Frames (at 60 Hz) of the climb from 50 m to 3000 m.
    #[arg(long, default_value_t = 240)]
    pub climb_frames: usize,
}

#[derive(Args)]
pub struct BenchRenderArgs {
    /// Terrain database directory.
    #[arg(long)]
    pub db: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Frame size.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Horizontal field of view, degrees.
    #[arg(long, default_value_t = 60.0)]
    pub fov: f64,
    /// Level-of-detail threshold, pixels.
    #[arg(long, default_value_t = 1.0)]
    pub max_pixel_error: f64,
    /// Frames of the 60 Hz pass.
    #[arg(long, default_value_t = 300)]
    pub frames: usize,
    /// Frames of the pass drawn both ways for the comparison.
    #[arg(long, default_value_t = 6)]
    pub compare_frames: usize,
}

#[derive(Args)]
pub struct BenchParticlesArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Frames to time (each one fixed step of 1/60 s).
    #[arg(long, default_value_t = 1200)]
    pub frames: u32,
    /// Simulation seconds run before timing (100 s fills every pool: smoke lives 90 s).
    #[arg(long, default_value_t = 100)]
    pub warm_seconds: u32,
}

#[derive(Args)]
pub struct PlumeArgs {
    /// Pasquill stability class A-F; derived from --sun-elevation-deg, --cloud-cover and
    /// --ceiling-m with the wind (Turner's key) when omitted.
    #[arg(long)]
    pub class: Option<String>,
    /// Wind speed at source height, m/s.
    #[arg(long, value_name = "MPS")]
    pub wind: f64,
    /// Downwind distance, m.
    #[arg(long, value_name = "M")]
    pub x: f64,
    /// Stack exit velocity, m/s.
    #[arg(long, value_name = "MPS", default_value_t = 10.0)]
    pub stack_velocity: f64,
    /// Stack inside diameter, m.
    #[arg(long, value_name = "M", default_value_t = 1.0)]
    pub stack_diameter: f64,
    /// Stack exit temperature, K.
    #[arg(long, value_name = "K", default_value_t = 400.0)]
    pub stack_temp: f64,
    /// Ambient air temperature, K.
    #[arg(long, value_name = "K", default_value_t = 293.15)]
    pub air_temp: f64,
    /// Potential temperature gradient for stable classes E and F, K/m (default 0.020 for E,
    /// 0.035 for F).
    #[arg(long, value_name = "K_PER_M")]
    pub stable_dtheta_dz: Option<f64>,
    /// Sun elevation, degrees (negative at night), to derive the class.
    #[arg(long, value_name = "DEG")]
    pub sun_elevation_deg: Option<f64>,
    /// Total cloud cover 0-1, to derive the class.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.0)]
    pub cloud_cover: f64,
    /// Cloud ceiling, m (default: no ceiling), to derive the class.
    #[arg(long, value_name = "M")]
    pub ceiling_m: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct BenchImageryArgs {
    /// Print JSON on one line.
    #[arg(long)]
    pub json: bool,
    /// Pixels along the square image's side.
    #[arg(long, default_value_t = 20_000)]
    pub size: u32,
    /// Directory for the scratch image and database (default: the system's temporary one).
    #[arg(long)]
    pub scratch: Option<PathBuf>,
}

#[derive(Args)]
pub struct BenchDbArgs {
    pub db: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Seconds to spend on each rate measurement.
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f64,
    /// Skip the build and import timings (they write about 100 MB to a temporary directory).
    #[arg(long)]
    pub no_build: bool,
}

#[derive(Args)]
pub struct RenderArgs {
    /// Terrain database directory.
    #[arg(long)]
    pub db: PathBuf,
    /// Eyepoint "LAT,LON,ALT": degrees, and metres above the WGS84 ellipsoid.
    #[arg(long, value_name = "LAT,LON,ALT", allow_hyphen_values = true)]
    pub eye: String,
    /// Heading, pitch, roll in degrees (heading clockwise from true north, pitch up positive,
    /// roll right wing down positive).
    #[arg(
        long,
        value_name = "H,P,R",
        default_value = "0,0,0",
        allow_hyphen_values = true
    )]
    pub hpr: String,
    /// Horizontal field of view in degrees, optionally ",VERTICAL" (else from the aspect
    /// ratio), or "LEFT,RIGHT,DOWN,UP" half-angles for an asymmetric frustum.
    #[arg(
        long,
        value_name = "DEG[,VDEG]",
        default_value = "60",
        allow_hyphen_values = true
    )]
    pub fov: String,
    /// Frame size in pixels.
    #[arg(long, value_name = "WxH", default_value = "640x480")]
    pub size: String,
    /// Time of day (UTC, ISO 8601, e.g. 2026-06-21T18:00:00Z): sets the sun.
    #[arg(long, default_value = "2026-06-21T19:00:00Z")]
    pub time: String,
    /// Output PNG file.
    #[arg(long)]
    pub out: PathBuf,
    /// Largest terrain error on screen, pixels (0: full detail everywhere).
    #[arg(long, default_value_t = 1.0)]
    pub max_pixel_error: f64,
    /// Meteorological visibility, metres (2 % contrast).
    #[arg(long, default_value_t = 40_000.0)]
    pub visibility: f64,
    /// Fog mode: off, linear, exp, exp2.
    #[arg(long, default_value = "exp")]
    pub fog: String,
    /// A ground fog layer "TOP_M,VISIBILITY_M": below TOP_M (above the WGS84 ellipsoid, as
    /// `--eye`) the visibility is VISIBILITY_M, so valleys are fogged and hills clear.
    #[arg(long, value_name = "TOP_M,VISIBILITY_M", allow_hyphen_values = true)]
    pub ground_fog: Option<String>,
    /// Sky: physical (atmosphere, sun disc, aerial perspective) or flat (the fog colour).
    #[arg(long, default_value = "physical")]
    pub sky: String,
    /// Exposure compensation, EV (added to the exposure the natural light sets; -10..10).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure_ev: f64,
    /// Expose for this incident-light EV (log2(lux / 2.5), -20..20) instead of the natural
    /// light.
    #[arg(long, allow_hyphen_values = true)]
    pub fixed_exposure_ev: Option<f64>,
    /// A cloud layer "BASE_M,THICKNESS_M,COVERAGE[,KIND[,WIND_MPS,FROM_DEG]]": base above the
    /// WGS84 ellipsoid (as `--eye`), coverage 0..1, kind cumulus (default), stratus,
    /// stratocumulus, nimbostratus, cumulonimbus, altocumulus, altostratus, cirrus,
    /// cirrocumulus or cirrostratus; the layer drifts with its wind for --time. Repeatable (4).
    #[arg(
        long = "cloud",
        value_name = "BASE_M,THICKNESS_M,COVERAGE[,KIND[,WIND_MPS,FROM_DEG]]",
        allow_hyphen_values = true
    )]
    pub clouds: Vec<String>,
    /// Draw the terrain as a wireframe.
    #[arg(long)]
    pub wireframe: bool,
    /// Entities "MODEL,LAT,LON,ALT[,HEADING[,clamp][,speed=MPS][,turn=DEG_S]]" (altitude
    /// above the ellipsoid, or above the terrain with "clamp"; a ship under way at speed MPS
    /// leaves its wake on the sea, along the circle it has been turning on at DEG_S degrees a
    /// second, positive to starboard); built-in models: tank, truck, destroyer (or ship), merchant,
    /// patrol_craft, building, tree (ships float on the sea with --sea-state or --sea-wind);
    /// or a glTF file path as MODEL.
    #[arg(long = "entity", value_name = "SPEC", allow_hyphen_values = true)]
    pub entities: Vec<String>,
    /// A fire "LAT,LON[,HEAT_MW[,SECONDS]]" on the terrain: a smoke plume and its flames,
    /// releasing HEAT_MW (default 5) and burning for SECONDS (default 120) at --time.
    /// Repeatable.
    #[arg(
        long = "smoke",
        value_name = "LAT,LON[,HEAT_MW[,SECONDS]]",
        allow_hyphen_values = true
    )]
    pub smoke: Vec<String>,
    /// Wind for --smoke "SPEED,FROM_DEG": m/s, and the direction it blows from (degrees
    /// clockwise from true north).
    #[arg(
        long,
        value_name = "SPEED,FROM_DEG",
        default_value = "5,270",
        allow_hyphen_values = true
    )]
    pub wind: String,
    /// Rain at MM_PER_H of water (0..200): lowers the visibility (Marshall-Palmer extinction
    /// added to the fog's) and draws streaks near the eye.
    #[arg(
        long,
        value_name = "MM_PER_H",
        allow_hyphen_values = true,
        conflicts_with = "snow"
    )]
    pub rain: Option<String>,
    /// Snow at MM_PER_H of water (0..200): lowers the visibility and draws flakes near the eye.
    #[arg(long, value_name = "MM_PER_H", allow_hyphen_values = true)]
    pub snow: Option<String>,
    /// A lightning bolt "SEED[,DIST_M]" at its brightest, DIST_M (default 3000, 100..50000)
    /// ahead of the eye, and its flash.
    #[arg(long, value_name = "SEED[,DIST_M]", allow_hyphen_values = true)]
    pub lightning: Option<String>,
    /// Write frame statistics (triangles, tiles, draw calls, CPU and GPU time) as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// The level-of-detail constant K_LOD of the models' detail control parameter (positive;
    /// default 1 / tan(FOV / width) of the view): larger keeps finer levels farther away.
    #[arg(long, allow_hyphen_values = true)]
    pub klod: Option<f64>,
    /// Draw the database's culture (trees, buildings, walls, fences, power poles): on or off.
    #[arg(long, value_name = "on|off", default_value = "on")]
    pub culture: String,
    /// Cull the culture the terrain hides behind ridges: on or off (default: the
    /// configuration's `culture.occlusion`, on).
    #[arg(long, value_name = "on|off")]
    pub culture_occlusion: Option<String>,
    /// Geometric warp of the frame, as a projected channel's (docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub warp: Option<PathBuf>,
    /// The sensor: visible (the eye's picture), lwir (8-12 um thermal), mwir (3-5 um) or nvg
    /// (a Gen III image intensifier's goggle).
    #[arg(long, default_value = "visible")]
    pub sensor: String,
    /// Night vision: the goggle's manual gain, 0.1..10 (1 nominal): scales the brightness the
    /// automatic brightness control holds and its limits.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub nvg_gain: f64,
    /// Night vision: the tube's phosphor, p43 (green) or white.
    #[arg(long, default_value = "p43")]
    pub phosphor: String,
    /// A light point "LAT,LON,ALT_M,CANDELA[,COLOUR]" (altitude above the ellipsoid; colour
    /// white, warm, red, green, amber, blue or sodium; default warm, an incandescent lamp).
    /// Repeatable.
    #[arg(
        long = "light",
        value_name = "LAT,LON,ALT_M,CANDELA[,COLOUR]",
        allow_hyphen_values = true
    )]
    pub lights: Vec<String>,
    /// An illumination flare "LAT,LON,ALT_M" burning at --time (just lit), lighting the ground
    /// around it. Repeatable.
    #[arg(
        long = "flare",
        value_name = "LAT,LON,ALT_M",
        allow_hyphen_values = true
    )]
    pub flares: Vec<String>,
    /// A sea at mean sea level, fully developed for a WMO sea state code 0-9 (the open ocean
    /// beyond the database and wherever the ground lies below sea level).
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "sea_wind",
        allow_hyphen_values = true
    )]
    pub sea_state: Option<f64>,
    /// A sea raised by this wind (m/s at 10 m) blowing from FROM_DEG (default 270), fully
    /// developed.
    #[arg(long, value_name = "MPS[,FROM_DEG]", allow_hyphen_values = true)]
    pub sea_wind: Option<String>,
    /// A periscope's view "HEIGHT_M,MAG": the head HEIGHT_M above mean sea level (-11000 to
    /// 30) at --eye's place (its altitude is ignored), magnification MAG (the field is 48/MAG
    /// degrees wide: 1.5x 32, 6x 8, 12x 4), with the reticle and the true bearing drawn; a
    /// wave over the head covers the view and drains off it.
    #[arg(long, value_name = "HEIGHT_M,MAG", allow_hyphen_values = true)]
    pub periscope: Option<String>,
    /// Terrestrial refraction's coefficient k for what the eye sees: "standard" (0.13: a
    /// distant ship shows more of itself over the horizon), "off" (the geometric earth) or a
    /// number in -1..0.9 (ducting above about 0.5).
    #[arg(
        long,
        value_name = "K",
        default_value = "standard",
        allow_hyphen_values = true
    )]
    pub refraction: String,
    /// An explicit wave on the sea (as a host's CIGI Wave Control)
    /// "HEIGHT_M,WAVELENGTH_M,PERIOD_S,TOWARD_DEG[,PHASE_DEG[,LEADING]]": trough-to-crest
    /// height 0-30 m, wavelength 0.1-5000 m, period 0.1-100 s, the direction it travels
    /// toward, its phase at the sea's origin and crest sharpness 0-1. Followed by
    /// "@LAT,LON,SIZE_X_M,SIZE_Y_M[,ROTATION_DEG[,CORNER_RADIUS_M[,TRANSITION_M]]]" the wave
    /// applies only over that region (as a host's regional Wave Control), fading out across
    /// its transition band. Repeatable; needs --sea-state or --sea-wind (0 for a swell alone).
    #[arg(long = "sea-wave", value_name = "SPEC", allow_hyphen_values = true)]
    pub sea_waves: Vec<String>,
    /// Thermal polarity: white-hot or black-hot.
    #[arg(long, default_value = "white-hot")]
    pub polarity: String,
    /// Thermal manual gain (contrast), 0..1, with --level (without both: automatic gain).
    #[arg(long)]
    pub gain: Option<f64>,
    /// Thermal manual level (brightness), 0..1, with --gain.
    #[arg(long)]
    pub level: Option<f64>,
    /// Thermal detector noise: its noise-equivalent temperature difference, kelvin (0: none).
    #[arg(long, default_value_t = 0.05)]
    pub noise: f64,
    /// Thermal display colour: white or green.
    #[arg(long, default_value = "white")]
    pub display: String,
    /// Thermal AC coupling: the detector's line-wise decay time constant, microseconds (0: off).
    #[arg(long, default_value_t = 0.0)]
    pub ac_coupling_us: f64,
    /// Thermal: line-by-line dropout.
    #[arg(long)]
    pub line_dropout: bool,
    /// Thermal: the day's air temperature "MIN,MAX", Celsius (minimum at sunrise, maximum at
    /// 14:00 local solar time), driving the surfaces' temperatures.
    #[arg(long, default_value = "10,24", allow_hyphen_values = true)]
    pub air_c: String,
    /// Thermal: relative humidity, percent.
    #[arg(long, default_value_t = 50.0)]
    pub rh: f64,
    /// Thermal: the entities' engines, running or off (off: at the air's and sun's
    /// temperature).
    #[arg(long, default_value = "running")]
    pub engines: String,
    /// Edge-blend ramps of the frame, as a projected channel's (docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub blend: Option<PathBuf>,
}

#[derive(Args)]
pub struct ViewArgs {
    /// Terrain database directory.
    #[arg(long)]
    pub db: PathBuf,
    /// First eyepoint "LAT,LON,ALT": degrees, and metres above the WGS84 ellipsoid (default:
    /// near the database's south edge, above its highest point, looking north).
    #[arg(long, value_name = "LAT,LON,ALT", allow_hyphen_values = true)]
    pub eye: Option<String>,
    /// First heading, pitch, roll in degrees.
    #[arg(
        long,
        value_name = "H,P,R",
        default_value = "0,-10,0",
        allow_hyphen_values = true
    )]
    pub hpr: String,
    /// Horizontal field of view in degrees (the vertical one follows the window's shape).
    #[arg(long, value_name = "DEG", default_value_t = 60.0)]
    pub fov: f64,
    /// First window size in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720")]
    pub size: String,
    /// First time of day (UTC, ISO 8601, e.g. 2026-06-21T18:00:00Z).
    #[arg(long, default_value = "2026-06-21T19:00:00Z")]
    pub time: String,
    /// First meteorological visibility, metres.
    #[arg(long, default_value_t = 40_000.0)]
    pub visibility: f64,
    /// First fog mode: off, linear, exp, exp2.
    #[arg(long, default_value = "exp")]
    pub fog: String,
    /// First level-of-detail threshold: largest terrain error on screen, pixels (0..8).
    #[arg(long, default_value_t = 1.0)]
    pub max_pixel_error: f64,
    /// Start with the terrain drawn as a wireframe.
    #[arg(long)]
    pub wireframe: bool,
    /// First flying speed, metres per second (the mouse wheel changes it).
    #[arg(long, default_value_t = 100.0)]
    pub speed: f64,
    /// Close the window after N frames (for automated checks).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Save the last frame (terrain and panel, drawn again off-screen) as PNG on exit.
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// A projected channel's geometric warp, drawn last (docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub warp: Option<PathBuf>,
    /// A projected channel's edge-blend ramps, drawn last (docs/channels.md).
    #[arg(long, value_name = "FILE")]
    pub blend: Option<PathBuf>,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Demo database directory (built when missing).
    #[arg(long, default_value = "demo-db")]
    pub db: PathBuf,
    /// Where the flight's frames and contact sheet go (when there is no display).
    #[arg(long, default_value = "demo-out")]
    pub out: PathBuf,
    /// Render the flight to PNG files even when there is a display.
    #[arg(long)]
    pub no_window: bool,
    /// Close the window after this many frames (for tests).
    #[arg(long, hide = true)]
    pub exit_after_frames: Option<u64>,
}

#[derive(Subcommand)]
pub enum ConfigCommand {
    /// Print the default configuration as TOML.
    Default,
}

#[derive(Args)]
pub struct EphemArgs {
    /// Geodetic latitude, degrees, north positive (-90..90).
    #[arg(long, allow_negative_numbers = true)]
    pub lat: f64,
    /// Longitude, degrees, east positive (-180..180).
    #[arg(long, allow_negative_numbers = true)]
    pub lon: f64,
    /// Height above the WGS84 ellipsoid, metres.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub alt: f64,
    /// The instant, ISO 8601: "2024-06-21T12:00:00Z"; an offset such as "+02:00" is
    /// converted to UTC; no offset means UTC; a date alone means its midnight UTC.
    #[arg(long, value_name = "ISO8601")]
    pub time: String,
    /// Cloud cover fraction 0..1: divides the natural illuminance by the sky-condition
    /// factor 10^(cover^2) (1 clear, 10 overcast).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "FRACTION",
        allow_negative_numbers = true
    )]
    pub cloud_cover: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum DisCommand {
    /// Print each PDU received on a UDP port: one readable line, or one JSON line with --json.
    #[command(allow_negative_numbers = true)]
    Listen(DisListenArgs),
    /// Send Entity State PDUs for one entity (built by cig's DIS encoder).
    #[command(allow_negative_numbers = true)]
    Send(DisSendArgs),
}

#[derive(Args)]
pub struct DisListenArgs {
    /// UDP port to listen on (DIS commonly uses 3000).
    #[arg(long, value_name = "P")]
    pub port: u16,
    /// Where to listen: "loopback" (default), "any" (every interface), an IP address or an
    /// interface name.
    #[arg(long, value_name = "B", default_value = "loopback")]
    pub bind: String,
    /// Receive the subnet's broadcasts (binds the interface's broadcast address).
    #[arg(long, conflicts_with = "multicast")]
    pub broadcast: bool,
    /// Join this IPv4 multicast group on the bound interface.
    #[arg(long, value_name = "GROUP")]
    pub multicast: Option<String>,
    /// Print only PDUs of this exercise.
    #[arg(long, value_name = "N")]
    pub exercise: Option<u8>,
    /// Stop after this many PDUs (bad datagrams do not count).
    #[arg(long, value_name = "N")]
    pub count: Option<u64>,
    /// Stop after this many seconds; an error when --count PDUs have not arrived by then.
    #[arg(long, value_name = "S")]
    pub timeout_s: Option<f64>,
    /// Print JSON lines.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct DisSendArgs {
    /// Destination UDP port.
    #[arg(long, value_name = "P")]
    pub port: u16,
    /// Destination host (name or address); default 127.0.0.1, or the broadcast address or
    /// group with --broadcast / --multicast.
    #[arg(long, value_name = "HOST")]
    pub to: Option<String>,
    /// Where to send from: "loopback" (default), "any", an IP address or an interface name.
    #[arg(long, value_name = "B", default_value = "loopback")]
    pub bind: String,
    /// Broadcast to the bound interface's subnet.
    #[arg(long, conflicts_with = "multicast")]
    pub broadcast: bool,
    /// Send to this IPv4 multicast group through the bound interface.
    #[arg(long, value_name = "GROUP")]
    pub multicast: Option<String>,
    /// Entity ID "SITE:APP:ID".
    #[arg(long, value_name = "SITE:APP:ID")]
    pub entity: String,
    /// Entity type "KIND:DOMAIN:COUNTRY:CATEGORY:SUBCATEGORY[:SPECIFIC:EXTRA]".
    #[arg(long = "type", value_name = "K:D:C:CAT:SUB[:SPEC:EXTRA]")]
    pub entity_type: String,
    /// Latitude, degrees (-90..90).
    #[arg(long)]
    pub lat: f64,
    /// Longitude, degrees (-180..180).
    #[arg(long)]
    pub lon: f64,
    /// Height above the WGS84 ellipsoid, metres.
    #[arg(long, value_name = "M")]
    pub alt: f64,
    /// Velocity "EAST,NORTH,UP", m/s; with --count the entity moves by it between PDUs.
    #[arg(long, value_name = "E,N,U", allow_hyphen_values = true)]
    pub velocity: Option<String>,
    /// Heading, degrees clockwise from north; default: the direction of the horizontal
    /// velocity, or north.
    #[arg(long, value_name = "H")]
    pub heading_deg: Option<f64>,
    /// Appearance bits, hexadecimal ("0x8020": smoke and flaming).
    #[arg(long, value_name = "HEX")]
    pub appearance: Option<String>,
    /// Marking text (up to 11 ASCII characters).
    #[arg(long, default_value = "cig")]
    pub marking: String,
    /// Force ID (0 other, 1 friendly, 2 opposing, 3 neutral).
    #[arg(long, default_value_t = 1)]
    pub force_id: u8,
    /// Exercise ID.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub exercise: u8,
    /// Dead-reckoning algorithm 0-9 (2: FPW, fixed orientation, constant velocity).
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub dr: u8,
    /// DIS protocol version: 7 (IEEE 1278.1-2012) or 6 (IEEE 1278.1a-1998).
    #[arg(long, default_value_t = 7)]
    pub version: u8,
    /// PDUs to send.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub count: u64,
    /// Seconds between PDUs.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    pub interval_s: f64,
}
