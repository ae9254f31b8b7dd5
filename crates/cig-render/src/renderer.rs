//! The frame: sky, terrain and models of one view drawn as pre-exposed radiance into a
//! multisampled half-float target, puffs composited, then tone-mapped into the caller's target.
//!
//! Algorithm: per view, the CPU selects terrain nodes (`cig_scene::lod`), refreshes the meshes
//! of nodes whose data changed, writes one record per node and one per entity with positions
//! relative to the eye (differences taken in f64, then rounded), computes the frame's light and
//! exposure (`cig_scene::Lighting::with_sky`: sun and moon from the ephemeris, colours from the
//! physical atmosphere, exposure from the natural illuminance), and records: the sky-view table
//! of the physical atmosphere ([`crate::atmosphere`], Hillaire 2020); one render pass with the
//! terrain (every node in one indexed draw, nearest first, from one vertex pool), then entity
//! models, terrain and models with the aerial perspective, the classic fog and the ground fog
//! layer, then the sky as a full-screen triangle where nothing was drawn (the sky-view table,
//! the limb-darkened sun disc through the atmosphere's transmittance); the obscurant puffs
//! ([`crate::puffs`]) composited onto the resolved scene; the eye's adaptation to what the view
//! shows ([`crate::adaptation`]: a histogram of the resolved scene, within bounds of the natural
//! exposure); and the tone map (the adapted factor, scotopic shift at night, ACES filmic curve,
//! sRGB) into the caller's target. The terrain shader draws the materials with smooth borders
//! and detail noise in the database centre's tangent plane (`ground_detail`). Every pass writes pre-exposed
//! linear radiance (`exposed()` in common.wgsl) into Rgba16Float, so a moonless night and noon
//! keep their precision alike. Depth is reversed (1 at the near plane, 0 at infinity) in a
//! 32-bit float buffer with a `Greater` test; colour is rendered with 4x multisampling and
//! resolved (the edge smoothing of source 001).
//!
//! Limits: one scene pass per view, no shadows (mountains do not shade the air or each other);
//! the aerial perspective is the cheap sky-view approximation of [`crate::atmosphere`], not a
//! froxel volume; the ground's detail noise lies in one tangent plane, so on steep slopes it
//! stretches into streaks along the fall line.

use crate::adaptation::{AdaptRequest, Adaptation, AdaptationPass};
use crate::atmosphere::{atmosphere_shader, AtmosphereGpu, ToneMap, HDR_FORMAT};
use crate::celestial::CelestialPass;
use crate::clouds::CloudPass;
use crate::gpu::{Gpu, RenderError};
use crate::imagery::ImageryClipmap;
use crate::pass::{
    sampler_entry, storage_entry, texture_array_entry, texture_entry, uint_texture_array_entry,
    uniform_entry, DEPTH_FORMAT,
};
use crate::puffs::PuffPass;
use crate::terrain::{MeshStats, NodeRecord, TerrainFrame, TerrainGpu};
use cig_geo::Geodetic;
use cig_scene::culture::{CultureFrame, CultureInstance, CultureSelect, CultureSelector};
use cig_scene::thermal::{DisplayColour, Polarity, SensorView};

// Culture instances are read by the model pass as instance records, from the same buffer.
const _: () =
    assert!(std::mem::size_of::<CultureInstance>() == std::mem::size_of::<InstanceRecord>());
use cig_scene::detail::DetailSettings;
use cig_scene::lighting::{FogMode, Lighting, SkyModel, Weighting};
use cig_scene::lod::{LodSettings, NodeLayout, TerrainLod};
use cig_scene::models::{Model, ModelVertex};
use cig_scene::nvg::NvgView;
use cig_scene::overload::{
    klod_for, OverloadControl, OverloadCounters, OverloadError, OverloadSettings,
};
use cig_scene::{Camera, FrameSnapshot};
use cig_terrain::database::GeoidLookup;
use cig_terrain::CultureKind;
use cig_terrain::TileCache;
use serde_like::FrameStats;
use std::collections::HashMap;
use std::sync::Arc;

/// Frame statistics (also written by `cig render --stats`).
pub mod serde_like {
    /// What one view's frame cost and drew.
    #[derive(Clone, Debug, Default, PartialEq)]
    pub struct FrameStats {
        pub triangles: u64,
        pub terrain_triangles: u64,
        pub model_triangles: u64,
        pub draw_calls: u32,
        pub terrain_nodes: u32,
        pub nodes_visited: u32,
        pub meshes_built: u32,
        pub meshes_deferred: u32,
        /// Ancestors drawn in place of nodes whose meshes were not built yet.
        pub node_stand_ins: u32,
        pub nodes_dropped: u32,
        pub entities_drawn: u32,
        /// Culture objects drawn (one blending two levels counts once), their triangles, and
        /// the CPU time of their selection and culling, milliseconds.
        pub culture_drawn: u32,
        pub culture_triangles: u64,
        /// Culture blocks (8 x 8 cells) in the view that the terrain hid.
        pub culture_blocks_occluded: u32,
        pub culture_cpu_ms: f64,
        /// Obscurant puffs drawn (after culling to the view).
        pub puffs_drawn: u32,
        pub tiles_resident: u32,
        pub tiles_wanted: u32,
        /// Draped imagery tiles written to the GPU this frame, and still loading.
        pub imagery_tiles_uploaded: u32,
        pub imagery_tiles_pending: u32,
        /// CPU time of level-of-detail selection and culling, milliseconds.
        pub cpu_select_ms: f64,
        /// CPU time of the whole frame (selection, meshes, encoding, submission).
        pub cpu_frame_ms: f64,
        /// GPU time of the frame's passes (timestamp queries: the scene pass and, when puffs
        /// are drawn, the puff passes) or, when the device has none, the time from submission
        /// to completion.
        pub gpu_ms: f64,
        /// GPU time of the puff passes (timestamp queries; 0 without them or without puffs).
        pub puff_gpu_ms: f64,
        /// Cloud layers drawn.
        pub cloud_layers_drawn: u32,
        /// GPU time of the cloud pass (timestamp queries; 0 without them or without clouds).
        pub cloud_gpu_ms: f64,
        pub gpu_timed_by: &'static str,
        /// Natural illuminance of the frame (the exposure's input), lux.
        pub illuminance_lux: f64,
        /// The exposure the frame was drawn at, as an incident-light EV (`log2(lux / 2.5)`,
        /// compensation and the eye's adaptation to the view included).
        pub exposure_ev: f64,
        /// How far the eye's adaptation to the view moved the natural illuminance's exposure,
        /// EV (positive: the picture was brightened; 0 with adaptation off).
        pub view_adaptation_ev: f64,
        /// Lightning bolt lines drawn.
        pub bolt_lines_drawn: u32,
        /// Light points drawn (those the observer sees).
        pub light_points: u32,
        /// Rain drops or snow flakes drawn.
        pub precipitation_particles: u32,
        /// The detail control parameter's constant `K_LOD` models were drawn at this frame
        /// (the overload control's; cue-important models take the nominal).
        pub klod: f64,
        /// The view's nominal `K_LOD` (from its field of view and width, or the fixed one).
        pub klod_nominal: f64,
        /// What the overload control made of this frame's counters for the next frame:
        /// "decrement", "hold", "increment", or "off" without one.
        pub overload: &'static str,
    }
}

/// Sample count of the colour and depth targets (defined in [`crate::pass`]).
pub use crate::pass::MSAA_SAMPLES;
/// Format of off-screen frames.
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Node meshes the GPU pool holds at most (about 280 MB with the atlases at 16 cells).
const MAX_NODE_SLOTS: usize = 16384;
/// Terrain records are kept by slot, so there is room for one per slot.
const MAX_NODE_RECORDS: usize = MAX_NODE_SLOTS;
const MAX_INSTANCES: usize = 8192;
/// Culture instances a view draws at most (64 MB of records; also bounded by the device's
/// largest storage binding): a frame past it drops the farthest kinds' rest.
const MAX_CULTURE_INSTANCES: usize = 1_000_000;
/// The farthest the culture's street and settlement lights are gathered from, metres (their
/// reach is Allard's law's; the resident tiles rarely reach this far).
const MAX_CULTURE_LIGHT_RANGE_M: f64 = 60_000.0;
/// Lights that light the surfaces around them, at most (flares, fires, headlights).
const MAX_LOCAL_LIGHTS: usize = 8;
/// A light's illuminance at a goggle below which it is not drawn, lx_A: about 50
/// photoelectrons a frame through a 25 mm objective, lost in any background.
const NVG_LIGHT_THRESHOLD_LXA: f64 = 1e-9;
/// Tile loads a view may request per frame beyond the paging areas.
const PREFETCH_PER_FRAME: usize = 8;
/// Detail-noise cell sizes, metres (incommensurate so the pattern never visibly repeats).
const NOISE_CELLS_M: [f64; 3] = [2.7, 19.3, 151.0];

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    cam_forward: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    tangents: [f32; 4],
    eye_up: [f32; 4],
    sun_dir: [f32; 4],
    sun_colour: [f32; 4],
    ambient: [f32; 4],
    sky_zenith: [f32; 4],
    sky_horizon: [f32; 4],
    fog_colour: [f32; 4],
    fog: [f32; 4],
    noise0: [f32; 4],
    noise1: [f32; 4],
    noise2: [f32; 4],
    flags: [f32; 4],
    fog_layer: [f32; 4],
    moon_dir: [f32; 4],
    moon_colour: [f32; 4],
    sun_toa: [f32; 4],
    moon_toa: [f32; 4],
    atmos: [f32; 4],
    night_sky: [f32; 4],
    tonemap: [f32; 4],
    sky_frame_x: [f32; 4],
    sky_frame_y: [f32; 4],
    detail_east: [f32; 4],
    detail_north: [f32; 4],
    sensor: [f32; 4],
    sensor_sky0: [f32; 4],
    sensor_sky1: [f32; 4],
    sensor_display: [f32; 4],
    sensor_display2: [f32; 4],
    nvg: [f32; 4],
    nvg2: [f32; 4],
    nvg3: [f32; 4],
    local_lights: [[f32; 4]; 24],
}

/// The sky-view table's frame for the frame's up and sun (single precision, as the shaders
/// used to work it out for every pixel): its x axis (horizontal towards the sun's azimuth,
/// or a fixed horizontal with the sun at the zenith) with the horizon's zenith angle for the
/// eye's radius `eye_radius_m` in w, and its y axis (`up x x`) with the table row of the fog's
/// horizon sky in w.
fn sky_frame(up: [f32; 4], sun: [f32; 4], eye_radius_m: f32) -> ([f32; 4], [f32; 4]) {
    let up = glam::Vec3::new(up[0], up[1], up[2]);
    let sun = glam::Vec3::new(sun[0], sun[1], sun[2]);
    let mut toward = sun - up * sun.dot(up);
    if toward.dot(toward) < 1e-8 {
        let other = if up.z.abs() > 0.9 {
            glam::Vec3::X
        } else {
            glam::Vec3::Z
        };
        toward = other - up * other.dot(up);
    }
    let x = toward.normalize_or_zero();
    let y = up.cross(x);
    let bottom = cig_environment::AtmosphereParams::EARTH.bottom_radius_m as f32;
    let r = eye_radius_m.max(1.0);
    let cos_beta = (r * r - bottom * bottom).max(0.0).sqrt() / r;
    let horizon_zenith = std::f32::consts::PI - cos_beta.clamp(-1.0, 1.0).acos();
    let fog_row = sky_view_row(
        std::f32::consts::FRAC_PI_2 - FOG_SKY_ELEVATION_RAD,
        horizon_zenith,
    );
    ([x.x, x.y, x.z, horizon_zenith], [y.x, y.y, y.z, fog_row])
}

/// How far above the horizontal the fog takes its colour from the sky (radians): the horizon
/// sky of the ray's azimuth, clear of the ground at any altitude the sky-view table covers.
const FOG_SKY_ELEVATION_RAD: f32 = 0.02;

/// The sky-view table's row (v) of a zenith angle: Hillaire's latitude mapping, concentrated at
/// the horizon's zenith angle `horizon_zenith` (the same mapping as `sky_view_uv` in
/// `shaders/atmosphere.wgsl`).
fn sky_view_row(zenith: f32, horizon_zenith: f32) -> f32 {
    let beta = std::f32::consts::PI - horizon_zenith;
    if zenith < horizon_zenith {
        0.5 * (1.0 - (1.0 - zenith / horizon_zenith).max(0.0).sqrt())
    } else {
        0.5 + 0.5 * ((zenith - horizon_zenith) / beta).clamp(0.0, 1.0).sqrt()
    }
}

/// The Rayleigh and Mie profiles' relative densities at the eye's altitude, for the aerial
/// perspective's optical depth (`g.atmos.zw`).
fn eye_densities(eye_radius_m: f32) -> (f32, f32) {
    let p = cig_environment::AtmosphereParams::EARTH;
    let altitude_m = f64::from(eye_radius_m) - p.bottom_radius_m;
    (
        (-altitude_m / p.rayleigh_scale_height_m).exp() as f32,
        (-altitude_m / p.mie_scale_height_m).exp() as f32,
    )
}

/// Timestamp queries of the frame: 0 start, 1 end, then pass starts and ends as needed.
const QUERY_COUNT: u32 = 6;

/// Which timestamp queries a frame wrote: how many, and the (begin, end) of the puff passes
/// and of the cloud pass.
struct PassQueries {
    count: u32,
    puff: Option<(u32, u32)>,
    cloud: Option<(u32, u32)>,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct InstanceRecord {
    /// Columns of the body-to-ECEF rotation; `col0.w..col1.w` is the share of the model's
    /// pixels (dither thresholds) this draw covers, for level-of-detail blending.
    col0: [f32; 4],
    col1: [f32; 4],
    col2: [f32; 4],
    origin: [f32; 4],
}

/// One level of a model in the shared buffers: first index, index count, base vertex,
/// triangles.
type LevelRange = (u32, u32, i32, u32);

struct GpuModel {
    /// Per level: first index, index count, base vertex, triangles.
    lods: Vec<LevelRange>,
    model: Model,
}

struct Targets {
    size: (u32, u32),
    msaa_colour: wgpu::TextureView,
    /// The resolved scene: pre-exposed radiance, read by the tone map.
    hdr: wgpu::TextureView,
    /// Its texture (a sensor's tracker reads its gate from it).
    hdr_texture: wgpu::Texture,
    tone_map_bind: wgpu::BindGroup,
    depth: wgpu::TextureView,
}

/// Renders views of one terrain database.
pub struct Renderer {
    gpu: Arc<Gpu>,
    pub lod: TerrainLod,
    terrain: TerrainGpu,
    /// The draped imagery's clipmap (a stand-in when the database has none).
    imagery: ImageryClipmap,
    /// The last view's terrain draw (its buffers are reused).
    terrain_frame: TerrainFrame,
    colour_format: wgpu::TextureFormat,
    globals: wgpu::Buffer,
    /// The thermal sensor views' tables (sensor.rs).
    thermal: wgpu::Buffer,
    node_records: wgpu::Buffer,
    instances: wgpu::Buffer,
    /// Instance records the instance buffer holds (entities first, then culture).
    instance_capacity: usize,
    model_layout: wgpu::BindGroupLayout,
    terrain_bind: wgpu::BindGroup,
    model_bind: wgpu::BindGroup,
    /// The culture standing on the resident tiles, selected per view.
    culture: CultureSelector,
    /// Each culture kind's levels in the model buffers (by the kind's byte), found again
    /// whenever the models are uploaded.
    culture_lods: Vec<Vec<LevelRange>>,
    /// Culture kinds that keep the nominal `K_LOD` under overload (cue-important, §4.6).
    pub culture_cue_important: Vec<CultureKind>,
    /// Cull culture blocks hidden behind the terrain (on by default).
    pub culture_occlusion: bool,
    sky_bind: wgpu::BindGroup,
    terrain_pipelines: TerrainPipelines,
    /// East and north (ECEF unit vectors) of the database centre's tangent plane, the plane the
    /// ground's detail noise lies in.
    detail_axes: [glam::DVec3; 2],
    /// Draw the terrain with pipelines built for the frame's switches (see
    /// `set_shader_specialisation`).
    specialise: bool,
    model_pipeline: wgpu::RenderPipeline,
    sky_pipeline: wgpu::RenderPipeline,
    atmosphere: AtmosphereGpu,
    tone_map: ToneMap,
    /// The eye's adaptation to what each view shows (the tone map's factor).
    adaptation: AdaptationPass,
    /// A thermal sensor's AC coupling (`None` without compute shaders).
    ac_coupling: Option<crate::ac_coupling::AcCouplingPass>,
    model_vertices: wgpu::Buffer,
    model_indices: wgpu::Buffer,
    models: HashMap<String, GpuModel>,
    /// How models' levels are chosen: the detail control parameter's table, an optional fixed
    /// `K_LOD` (else each view's) and the area of interest around the view's centre.
    pub detail: DetailSettings,
    /// The overload control's settings (source 004 Table 4; `None`: off) and each view's
    /// state, fed each frame's counters after the frame, for the next one.
    overload: Option<OverloadSettings>,
    /// The channel's display correction (warp and blend), the frame's last pass.
    display: Option<crate::display::DisplayPass>,
    overload_controls: Vec<OverloadControl>,
    /// When each drawn node of each view first appeared, and the frame it was last drawn.
    node_first_seen: HashMap<(usize, cig_scene::NodeKey), (std::time::Instant, u64)>,
    targets: Option<Targets>,
    puffs: PuffPass,
    /// The moon and stars of the sky pass (its `@group(2)`).
    celestial: CelestialPass,
    clouds: CloudPass,
    bolts: crate::bolts::BoltPass,
    light_points: crate::lights::LightPass,
    sea: crate::sea::SeaPass,
    sea_pipeline: wgpu::RenderPipeline,
    /// This view's light points (the world's and the culture's), kept for their room.
    lights_scratch: Vec<cig_scene::lights::LightPoint>,
    drawn_scratch: Vec<cig_scene::lights::DrawnLight>,
    precipitation: crate::precipitation::PrecipitationPass,
    /// Queries: 0 the frame's start, 1 its end (the tone map's), then as needed the start and
    /// end of the puff passes and of the cloud passes.
    timestamps: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    frame: u64,
}

struct PipelineSpec<'a> {
    label: &'a str,
    module: &'a wgpu::ShaderModule,
    /// Bind group layouts, group 0 first.
    layouts: &'a [&'a wgpu::BindGroupLayout],
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth_write: bool,
    depth_compare: wgpu::CompareFunction,
    polygon_mode: wgpu::PolygonMode,
    cull: Option<wgpu::Face>,
    /// Values of the module's pipeline-overridable constants (`ShaderSwitches`).
    constants: &'a [(&'a str, f64)],
}

fn pipeline(
    gpu: &Gpu,
    format: wgpu::TextureFormat,
    spec: &PipelineSpec<'_>,
) -> wgpu::RenderPipeline {
    let layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(spec.label),
            bind_group_layouts: &spec.layouts.iter().map(|l| Some(*l)).collect::<Vec<_>>(),
            immediate_size: 0,
        });
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(spec.label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: spec.module,
                entry_point: Some("vs_main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: spec.constants,
                    ..Default::default()
                },
                buffers: spec.buffers,
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: spec.cull,
                polygon_mode: spec.polygon_mode,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(spec.depth_write),
                depth_compare: Some(spec.depth_compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: MSAA_SAMPLES,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module: spec.module,
                entry_point: Some("fs_main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: spec.constants,
                    ..Default::default()
                },
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// The sky pipeline: group 0 the frame's globals, group 1 the atmosphere's tables. Built here
/// only (the celestial sky adds its group 2 to this list).
fn sky_pipeline(
    gpu: &Gpu,
    globals_layout: &wgpu::BindGroupLayout,
    atmosphere_layout: &wgpu::BindGroupLayout,
    celestial_layout: &wgpu::BindGroupLayout,
) -> wgpu::RenderPipeline {
    let module = atmosphere_shader(
        gpu,
        "sky",
        &[
            crate::celestial::WGSL,
            include_str!("shaders/thermal_common.wgsl"),
            include_str!("shaders/sky.wgsl"),
        ]
        .concat(),
    );
    pipeline(
        gpu,
        HDR_FORMAT,
        &PipelineSpec {
            label: "sky",
            module: &module,
            layouts: &[globals_layout, atmosphere_layout, celestial_layout],
            buffers: &[],
            depth_write: false,
            // Drawn after the opaque geometry, at the far plane (reversed Z: depth 0), only
            // where nothing was drawn: no sky is shaded under the terrain.
            depth_compare: wgpu::CompareFunction::Equal,
            polygon_mode: wgpu::PolygonMode::Fill,
            cull: None,
            constants: &[],
        },
    )
}

/// The frame's uniform switches a pipeline can be built for (the `override`s of
/// `shaders/common.wgsl`). A pipeline built for them has the other settings' paths folded away
/// by the shader compiler: on GPUs that is fewer registers, and on lavapipe, which runs every
/// branch of a shader under a mask, it is every path the frame does not take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct ShaderSwitches {
    /// As `Globals.fog.x`: 0 off, 1 linear, 2 exponential, 3 exponential-squared.
    fog_mode: u8,
    ground_fog: bool,
    physical_sky: bool,
    ground_detail: bool,
    /// The sea is drawn: the terrain leaves its sea posts to it (a discard, which costs the
    /// early depth test, so only these frames pay it).
    sea_cut: bool,
}

impl ShaderSwitches {
    fn of(snapshot: &FrameSnapshot) -> ShaderSwitches {
        ShaderSwitches {
            fog_mode: fog_mode_index(snapshot.fog.mode),
            ground_fog: drawn_ground_fog(snapshot).is_some(),
            physical_sky: snapshot.sky.model == SkyModel::Physical,
            ground_detail: snapshot.ground_detail,
            sea_cut: snapshot.sea.is_some(),
        }
    }

    fn constants(self) -> [(&'static str, f64); 5] {
        [
            ("FOG_MODE", f64::from(self.fog_mode)),
            ("GROUND_FOG", f64::from(u8::from(self.ground_fog))),
            ("PHYSICAL_SKY", f64::from(u8::from(self.physical_sky))),
            ("GROUND_DETAIL", f64::from(u8::from(self.ground_detail))),
            ("SEA_CUT", f64::from(u8::from(self.sea_cut))),
        ]
    }
}

fn fog_mode_index(mode: FogMode) -> u8 {
    match mode {
        FogMode::Off => 0,
        FogMode::Linear => 1,
        FogMode::Exponential => 2,
        FogMode::ExponentialSquared => 3,
    }
}

/// The frame's ground fog layer, where it has one the shaders can draw.
/// Where the trainee looks (ECEF unit vector): the host's point of interest, else the view's
/// centre.
fn aim_of(camera: &Camera, point_of_interest_deg: Option<[f64; 2]>) -> glam::DVec3 {
    point_of_interest_deg.map_or(camera.forward, |[right, up]| {
        let (r, u) = (right.to_radians(), up.to_radians());
        (camera.forward * (r.cos() * u.cos())
            + camera.right * (r.sin() * u.cos())
            + camera.up * u.sin())
        .normalize()
    })
}

fn drawn_ground_fog(snapshot: &FrameSnapshot) -> Option<cig_scene::FogLayer> {
    snapshot
        .ground_fog
        .filter(|layer| layer.visibility_m.is_finite() && layer.top_m.is_finite())
}

/// The terrain's pipelines, one per `ShaderSwitches` (or none: the unspecialised pipeline that
/// reads every switch from the globals) and fill or wireframe, each built when a frame first
/// needs it (the default settings' at start-up): a frame that first uses another fog mode, the
/// ground fog or the flat sky waits for one pipeline's compilation.
struct TerrainPipelines {
    module: wgpu::ShaderModule,
    /// The terrain's, the atmosphere's and the edit patches' marks'.
    layouts: [wgpu::BindGroupLayout; 3],
    /// Whether the device draws lines (wireframe).
    wire_supported: bool,
    built: HashMap<(Option<ShaderSwitches>, bool), wgpu::RenderPipeline>,
}

impl TerrainPipelines {
    fn get(
        &mut self,
        gpu: &Gpu,
        switches: Option<ShaderSwitches>,
        wire: bool,
    ) -> &wgpu::RenderPipeline {
        let wire = wire && self.wire_supported;
        // The wireframe's fragment shader returns before any switch is read: one pipeline.
        let switches = if wire { None } else { switches };
        self.built.entry((switches, wire)).or_insert_with(|| {
            let buffers = [Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<cig_scene::terrain_mesh::TerrainVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![
                    0 => Float32x3,
                    1 => Float32x3,
                    2 => Float32x2,
                    3 => Float32
                ],
            })];
            let [terrain_layout, atmosphere_layout, marks_layout] = &self.layouts;
            let constants = switches.map(ShaderSwitches::constants);
            pipeline(
                gpu,
                HDR_FORMAT,
                &PipelineSpec {
                    label: if wire { "terrain wireframe" } else { "terrain" },
                    module: &self.module,
                    layouts: &[terrain_layout, atmosphere_layout, marks_layout],
                    buffers: &buffers,
                    depth_write: true,
                    depth_compare: if wire {
                        wgpu::CompareFunction::GreaterEqual
                    } else {
                        wgpu::CompareFunction::Greater
                    },
                    polygon_mode: if wire {
                        wgpu::PolygonMode::Line
                    } else {
                        wgpu::PolygonMode::Fill
                    },
                    cull: None,
                    constants: constants.as_ref().map_or(&[], |c| &c[..]),
                },
            )
        })
    }
}

/// The earth's radius the sea, the terrain's sea cut and the refraction take at a latitude,
/// metres: the ellipsoid's Gaussian mean radius of curvature there, `√(M N)` (within 0.35 % of
/// its radius in any direction).
pub(crate) fn earth_radius_m(lat_deg: f64) -> f64 {
    let (a, e2) = (cig_geo::WGS84_A_M, cig_geo::WGS84_E2);
    let w2 = 1.0 - e2 * lat_deg.to_radians().sin().powi(2);
    a * (1.0 - e2).sqrt() / w2
}

/// An IEEE half-precision value as f32.
fn f16_to_f32(bits: u16) -> f32 {
    half::f16::from_bits(bits).to_f32()
}

/// The models' bind group: the globals, the instance records and the thermal tables.
fn model_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    [globals, instances, thermal]: [&wgpu::Buffer; 3],
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("model"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: instances.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 9,
                resource: thermal.as_entire_binding(),
            },
        ],
    })
}

/// Options of one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameOptions {
    /// Node meshes built at most per frame (`usize::MAX` for one-off frames that must be
    /// complete).
    pub mesh_budget: usize,
    /// Paint the sky in pure magenta, so tests can see where the background shows through; the
    /// tone map then passes the pre-exposed linear radiance through (clamped to 1).
    pub key_background: bool,
    /// Seconds over which a node that newly replaces its parent morphs from the parent's shape
    /// into its own (finer data fades in rather than pops); 0 for one-off frames.
    pub fade_in_s: f32,
    /// How the eye's adaptation to the view advances (settled at once by default: still
    /// frames; interactive loops step it by their frame time).
    pub adaptation: Adaptation,
}

impl Default for FrameOptions {
    fn default() -> Self {
        FrameOptions {
            mesh_budget: 48,
            key_background: false,
            fade_in_s: 0.5,
            adaptation: Adaptation::Settled,
        }
    }
}

impl Renderer {
    /// A renderer for the database behind `cache`, drawing into `colour_format` targets.
    pub fn new(gpu: Arc<Gpu>, cache: &TileCache, colour_format: wgpu::TextureFormat) -> Renderer {
        let manifest = cache.database().manifest();
        // Roads are shapes where the database drapes imagery (painted, or in the photograph).
        let layout =
            NodeLayout::new(manifest.layout).with_roads_as_shapes(manifest.imagery.is_some());
        let lod = TerrainLod::new(layout, GeoidLookup::new(&manifest.geoid));
        // No more slots than the database has nodes (a small database needs a small pool).
        let capacity = layout.node_count().min(MAX_NODE_SLOTS as u64) as usize;
        let [north_m, east_m] = manifest.spacing_m;
        let finest_post_m = (north_m * east_m).sqrt() as f32;
        let grid = layout.pyramid.grid;
        let centre = cig_geo::EnuFrame::new(Geodetic::new(
            0.5 * (grid.south_lat_deg + grid.north_lat_deg()),
            0.5 * (grid.west_lon_deg + grid.east_lon_deg()),
            0.0,
        ));
        let detail_axes = [
            centre.enu_vector_to_ecef(glam::DVec3::X),
            centre.enu_vector_to_ecef(glam::DVec3::Y),
        ];
        let terrain = TerrainGpu::new(&gpu, layout.node_cells, capacity, finest_post_m);
        let device = &gpu.device;
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let node_records = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("node records"),
            size: (MAX_NODE_RECORDS * std::mem::size_of::<NodeRecord>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let instances = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (MAX_INSTANCES * std::mem::size_of::<InstanceRecord>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("atlas"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let imagery = ImageryClipmap::new(&gpu, cache);
        let imagery_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("imagery"),
            // The clipmap's windows are toroidal: texture coordinates wrap.
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let terrain_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("terrain"),
            entries: &[
                uniform_entry(0),
                storage_entry(1),
                texture_entry(2),
                texture_entry(3),
                sampler_entry(4),
                uniform_entry(5),
                texture_array_entry(6),
                uint_texture_array_entry(7),
                sampler_entry(8),
                storage_entry(9),
            ],
        });
        let model_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("model"),
            entries: &[uniform_entry(0), storage_entry(1), storage_entry(9)],
        });
        // The thermal sensor views' tables (sensor.rs), at binding 9 of the terrain and models.
        let thermal = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("thermal"),
            size: (crate::sensor::THERMAL_LEN * 4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sky_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sky"),
            entries: &[uniform_entry(0)],
        });
        let normal_view = terrain.normal_atlas.create_view(&Default::default());
        let colour_view = terrain.colour_atlas.create_view(&Default::default());
        let terrain_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("terrain"),
            layout: &terrain_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: node_records.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&normal_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&colour_view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: imagery.params_buffer().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::TextureView(&imagery.texture_view()),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: wgpu::BindingResource::TextureView(&imagery.pages_view()),
                },
                wgpu::BindGroupEntry {
                    binding: 8,
                    resource: wgpu::BindingResource::Sampler(&imagery_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 9,
                    resource: thermal.as_entire_binding(),
                },
            ],
        });
        let model_bind = model_bind_group(device, &model_layout, [&globals, &instances, &thermal]);
        let sky_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky"),
            layout: &sky_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let atmosphere = AtmosphereGpu::new(&gpu, &sky_layout, sky_bind.clone());
        let tone_map = ToneMap::new(&gpu, &sky_layout, colour_format);
        let adaptation = AdaptationPass::new(&gpu);
        let ac_coupling = crate::ac_coupling::AcCouplingPass::new(&gpu);
        let terrain_module = atmosphere_shader(
            &gpu,
            "terrain",
            &[
                include_str!("shaders/thermal_common.wgsl"),
                include_str!("shaders/thermal.wgsl"),
                include_str!("shaders/terrain.wgsl"),
            ]
            .concat(),
        );
        let model_module = atmosphere_shader(
            &gpu,
            "model",
            &[
                include_str!("shaders/thermal_common.wgsl"),
                include_str!("shaders/thermal.wgsl"),
                include_str!("shaders/model.wgsl"),
            ]
            .concat(),
        );
        let celestial = CelestialPass::new(&gpu);
        let model_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<ModelVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Unorm8x4],
        })];
        let mut terrain_pipelines = TerrainPipelines {
            module: terrain_module,
            layouts: [
                terrain_layout,
                atmosphere.layout.clone(),
                terrain.marks_layout.clone(),
            ],
            wire_supported: gpu
                .device
                .features()
                .contains(wgpu::Features::POLYGON_MODE_LINE),
            built: HashMap::new(),
        };
        terrain_pipelines.get(
            &gpu,
            Some(ShaderSwitches::of(&FrameSnapshot::new(0.0, Vec::new()))),
            false,
        );
        let model_pipeline = pipeline(
            &gpu,
            HDR_FORMAT,
            &PipelineSpec {
                label: "model",
                module: &model_module,
                layouts: &[&model_layout, &atmosphere.layout],
                buffers: &model_buffers,
                depth_write: true,
                depth_compare: wgpu::CompareFunction::Greater,
                polygon_mode: wgpu::PolygonMode::Fill,
                cull: None,
                constants: &[],
            },
        );
        let sky_pipeline = sky_pipeline(&gpu, &sky_layout, &atmosphere.layout, celestial.layout());
        let empty = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 64,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let timestamps = gpu.timestamps.then(|| {
            (
                device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("frame time"),
                    ty: wgpu::QueryType::Timestamp,
                    count: QUERY_COUNT,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: u64::from(QUERY_COUNT) * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps readback"),
                    size: u64::from(QUERY_COUNT) * 8,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
            )
        });
        // The puffs and clouds composite onto the resolved scene before the tone map.
        let puffs = PuffPass::new(&gpu, HDR_FORMAT, &atmosphere.layout);
        let clouds = CloudPass::new(&gpu, HDR_FORMAT);
        let bolts = crate::bolts::BoltPass::new(&gpu, HDR_FORMAT, &globals);
        let light_points = crate::lights::LightPass::new(&gpu, HDR_FORMAT, &globals);
        let sea =
            crate::sea::SeaPass::new(&gpu, GeoidLookup::new(&cache.database().manifest().geoid));
        let sea_module = atmosphere_shader(
            &gpu,
            "sea",
            &[
                include_str!("shaders/thermal_common.wgsl"),
                include_str!("shaders/thermal.wgsl"),
                include_str!("shaders/sea.wgsl"),
            ]
            .concat(),
        );
        let sea_pipeline = pipeline(
            &gpu,
            HDR_FORMAT,
            &PipelineSpec {
                label: "sea",
                module: &sea_module,
                layouts: &[&sea.layout, &atmosphere.layout],
                buffers: &[],
                depth_write: true,
                depth_compare: wgpu::CompareFunction::Greater,
                polygon_mode: wgpu::PolygonMode::Fill,
                cull: None,
                constants: &[],
            },
        );
        let precipitation =
            crate::precipitation::PrecipitationPass::new(&gpu, HDR_FORMAT, &globals);
        let mut renderer = Renderer {
            model_vertices: empty("model vertices", wgpu::BufferUsages::VERTEX),
            model_indices: empty("model indices", wgpu::BufferUsages::INDEX),
            gpu,
            lod,
            terrain,
            imagery,
            terrain_frame: TerrainFrame::default(),
            colour_format,
            globals,
            thermal,
            node_records,
            instances,
            instance_capacity: MAX_INSTANCES,
            model_layout,
            terrain_bind,
            model_bind,
            culture_cue_important: Vec::new(),
            culture_occlusion: true,
            culture_lods: Vec::new(),
            culture: CultureSelector::new(
                *cache.database().layout(),
                GeoidLookup::new(&cache.database().manifest().geoid),
            ),
            sky_bind,
            terrain_pipelines,
            specialise: true,
            model_pipeline,
            sky_pipeline,
            atmosphere,
            tone_map,
            adaptation,
            ac_coupling,
            detail_axes,
            models: HashMap::new(),
            detail: DetailSettings::standard(),
            overload: Some(OverloadSettings::default()),
            display: None,
            overload_controls: Vec::new(),
            node_first_seen: HashMap::new(),
            targets: None,
            puffs,
            celestial,
            clouds,
            bolts,
            light_points,
            sea,
            sea_pipeline,
            lights_scratch: Vec::new(),
            drawn_scratch: Vec::new(),
            precipitation,
            timestamps,
            frame: 0,
        };
        let builtins: Vec<Model> = cig_scene::models::BUILTIN_MODELS
            .iter()
            .filter_map(|name| cig_scene::models::builtin(name))
            .collect();
        renderer.set_models(builtins);
        let culture_models: Vec<Model> = CultureKind::ALL
            .into_iter()
            .map(cig_scene::culture::culture_model)
            .collect();
        renderer.set_models(culture_models);
        renderer
    }

    /// Whether the terrain is drawn with pipelines built for each frame's fog mode, ground fog
    /// and sky model, and the sky-view table with or without the moon's light (on, the
    /// default), or with pipelines that read them every frame (the same image, more shader
    /// work; for diagnosing a shader compiler).
    pub fn set_shader_specialisation(&mut self, on: bool) {
        self.specialise = on;
    }

    pub fn gpu(&self) -> &Arc<Gpu> {
        &self.gpu
    }

    pub fn colour_format(&self) -> wgpu::TextureFormat {
        self.colour_format
    }

    /// Adds or replaces models (by name) and uploads every model's levels in one buffer pair.
    pub fn set_models(&mut self, new_models: Vec<Model>) {
        let mut all: Vec<Model> = self.models.drain().map(|(_, m)| m.model).collect();
        for m in new_models {
            all.retain(|old| old.name != m.name);
            all.push(m);
        }
        all.sort_by(|a, b| a.name.cmp(&b.name));
        let mut vertices: Vec<ModelVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        for model in all {
            let mut lods = Vec::new();
            for mesh in &model.lods {
                let first = indices.len() as u32;
                lods.push((
                    first,
                    mesh.indices.len() as u32,
                    vertices.len() as i32,
                    mesh.triangle_count() as u32,
                ));
                vertices.extend_from_slice(&mesh.vertices);
                indices.extend_from_slice(&mesh.indices);
            }
            self.models
                .insert(model.name.clone(), GpuModel { lods, model });
        }
        let device = &self.gpu.device;
        let buffer = |label, bytes: &[u8], usage| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (bytes.len() as u64).max(4).next_multiple_of(4),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.gpu.queue.write_buffer(&b, 0, bytes);
            b
        };
        self.model_vertices = buffer(
            "model vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        self.model_indices = buffer(
            "model indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        self.culture_lods = CultureKind::ALL
            .into_iter()
            .map(|kind| {
                let name = cig_scene::culture::culture_model_name(kind);
                self.models
                    .get(&name)
                    .map_or(Vec::new(), |m| m.lods.clone())
            })
            .collect();
    }

    /// Names of the models the renderer can draw.
    pub fn model_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.models.keys().cloned().collect();
        names.sort();
        names
    }

    fn targets(&mut self, size: (u32, u32)) {
        if self.targets.as_ref().map(|t| t.size) != Some(size) {
            let device = &self.gpu.device;
            let make = |label, format, usage| {
                crate::gpu::render_target(device, label, size, format, MSAA_SAMPLES, usage, &[])
                    .create_view(&Default::default())
            };
            let hdr_texture = crate::gpu::render_target(
                device,
                "scene",
                size,
                HDR_FORMAT,
                1,
                wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                &[],
            );
            let hdr = hdr_texture.create_view(&Default::default());
            let targets = Targets {
                size,
                msaa_colour: make("msaa colour", HDR_FORMAT, wgpu::TextureUsages::empty()),
                tone_map_bind: self
                    .tone_map
                    .bind(&self.gpu, &hdr, &self.adaptation.tone_exposure),
                hdr,
                hdr_texture,
                // The puff pass may read the depth samples.
                depth: make(
                    "depth",
                    DEPTH_FORMAT,
                    self.puffs.depth_usage() | self.clouds.depth_usage(),
                ),
            };
            self.adaptation.bind_scene(&self.gpu, &targets.hdr);
            self.puffs
                .resize(&self.gpu, size, &targets.depth, &self.globals);
            self.clouds
                .resize(&self.gpu, size, &targets.depth, &self.globals);
            self.targets = Some(targets);
        }
    }

    /// Selects terrain for `view_index` of `snapshot` and returns the tiles it would refine
    /// into that are not resident (for callers that want a complete frame).
    pub fn missing_tiles(
        &mut self,
        cache: &TileCache,
        snapshot: &FrameSnapshot,
        view_index: usize,
    ) -> Result<Vec<cig_terrain::TileKey>, RenderError> {
        let view = snapshot
            .views
            .get(view_index)
            .ok_or_else(|| RenderError::Gpu(format!("no view {view_index}")))?;
        view.validate()?;
        let camera = view.camera();
        let selection = self.lod.select(
            cache,
            &camera,
            &LodSettings {
                max_pixel_error: snapshot.max_pixel_error,
            },
        );
        Ok(selection.wanted_tiles)
    }

    /// Draws view `view_index` of `snapshot` into `target` (a single-sample view of the
    /// renderer's colour format and the view's size).
    pub fn render(
        &mut self,
        cache: &TileCache,
        snapshot: &FrameSnapshot,
        view_index: usize,
        target: &wgpu::TextureView,
        options: FrameOptions,
    ) -> Result<FrameStats, RenderError> {
        let started = std::time::Instant::now();
        let view = *snapshot
            .views
            .get(view_index)
            .ok_or_else(|| RenderError::Gpu(format!("no view {view_index}")))?;
        view.validate()?;
        crate::gpu::check_frame_size(&self.gpu, view.width_px, view.height_px)?;
        self.frame += 1;
        let camera = view.camera();
        let select_started = std::time::Instant::now();
        let selection = self.lod.select(
            cache,
            &camera,
            &LodSettings {
                max_pixel_error: snapshot.max_pixel_error,
            },
        );
        let cpu_select_ms = select_started.elapsed().as_secs_f64() * 1e3;
        // Finer tiles the view resolves but the paging areas do not hold: ask for a few.
        cache.prefetch(&selection.wanted_tiles, PREFETCH_PER_FRAME);
        let nodes = &selection.nodes[..selection.nodes.len().min(MAX_NODE_RECORDS)];
        let min_morph = self.fade_in(view_index, nodes, options.fade_in_s);
        // The view's terrain, in buffers kept from frame to frame.
        let mut terrain_frame = std::mem::take(&mut self.terrain_frame);
        // The imagery's windows follow the eye; one-off frames load every window tile first.
        let imagery_stats = self.imagery.update(
            &self.gpu,
            view.eye.lat_deg,
            view.eye.lon_deg,
            options.mesh_budget == usize::MAX,
        );
        self.imagery
            .prepare_view(&self.gpu, view.eye.lat_deg, view.eye.lon_deg);
        self.terrain.imagery_frame = self.imagery.frame();
        let mesh_stats: MeshStats = self.terrain.prepare(
            &self.gpu,
            &self.lod,
            cache,
            nodes,
            &min_morph,
            camera.eye_ecef,
            if snapshot.max_pixel_error > 0.0 {
                snapshot.max_pixel_error / camera.pixels_per_tangent
            } else {
                0.0
            },
            (self.frame, snapshot.unix_time_s),
            options.mesh_budget,
            &mut terrain_frame,
        );
        // A night-vision view sees every source through the photocathode's weighting.
        let nvg = snapshot.nvg_of(view_index);
        let weighting = if nvg.is_some() {
            Weighting::Intensifier
        } else {
            Weighting::Eye
        };
        let lighting = Lighting::weighted(
            snapshot.unix_time_s,
            view.eye,
            snapshot.cloud_cover_fraction,
            &snapshot.sky,
            weighting,
        )
        .with_flash(snapshot.flash_lux * weighting.flash_factor());
        let physical_sky = snapshot.sky.model == SkyModel::Physical;
        let wire = snapshot.wireframe && self.terrain_pipelines.wire_supported;
        // A thermal sensor view: its tables for this eye and sun.
        let sensor = snapshot.sensor_of(view_index).map(|(sensor, scene)| {
            let frame = crate::sensor::sensor_frame(
                &sensor,
                scene,
                view.eye.alt_m,
                lighting.sun_elevation_deg,
                &snapshot.cloud_layers,
                camera.eye_ecef,
            );
            self.gpu
                .queue
                .write_buffer(&self.thermal, 0, bytemuck::cast_slice(&frame.buffer));
            (sensor, frame)
        });
        if nvg.is_some() {
            self.gpu.queue.write_buffer(
                &self.thermal,
                0,
                bytemuck::cast_slice(crate::sensor::nvg_buffer()),
            );
        }
        // Light points: the world's, and the resident culture's street and settlement lights
        // while they are switched on; those that light the ground near the eye, and those
        // the view's observer sees (Allard's law against the eye's threshold, or the tube's).
        let mut lights = std::mem::take(&mut self.lights_scratch);
        lights.clear();
        lights.extend_from_slice(&snapshot.lights);
        let street_on = snapshot
            .street_lights
            .unwrap_or_else(|| cig_scene::lights::street_lights_on(lighting.usno_illuminance_lux));
        if street_on && snapshot.culture && sensor.is_none() {
            // As far as Allard's law lets a street lamp seen from the side reach the observer.
            let threshold_lux = if nvg.is_some() {
                NVG_LIGHT_THRESHOLD_LXA
            } else {
                cig_environment::stars::threshold_illuminance_lux(
                    0.2 * lighting.usno_illuminance_lux / std::f64::consts::PI,
                )
            };
            let range_m = cig_scene::lights::allard_range_m(
                f64::from(cig_scene::lights::STREET_LAMP_CD),
                &snapshot.fog,
                threshold_lux,
            )
            .clamp(1_000.0, MAX_CULTURE_LIGHT_RANGE_M);
            self.culture
                .culture_lights_near(cache, &camera, range_m, &mut lights);
        }
        let local = if sensor.is_none() {
            cig_scene::lights::local_lights(
                &lights,
                camera.eye_ecef,
                snapshot.unix_time_s,
                MAX_LOCAL_LIGHTS,
            )
        } else {
            Vec::new()
        };
        let mut drawn = std::mem::take(&mut self.drawn_scratch);
        drawn.clear();
        if sensor.is_none() {
            let observer = match nvg {
                Some(_) => cig_scene::lights::Observer::Intensifier {
                    threshold_lxa: NVG_LIGHT_THRESHOLD_LXA,
                },
                // The eye adapted to the scene: a ground of albedo 0.2 under the natural light.
                None => cig_scene::lights::Observer::Eye {
                    background_cd_per_m2: 0.2 * lighting.usno_illuminance_lux
                        / std::f64::consts::PI,
                },
            };
            cig_scene::lights::drawn_lights(
                &lights,
                camera.eye_ecef,
                view.eye.alt_m,
                &camera.planes,
                snapshot.unix_time_s,
                &cig_scene::lights::LightPath {
                    fog: &snapshot.fog,
                    ground_fog: drawn_ground_fog(snapshot),
                    puffs: &snapshot.puffs,
                    puff_origin_ecef_m: snapshot.puff_origin_ecef_m,
                },
                observer,
                &mut drawn,
            );
        }
        self.lights_scratch = lights;
        let light_count = self.light_points.prepare(
            &self.gpu,
            &self.globals,
            &camera,
            &drawn,
            lighting.exposure,
            nvg.as_ref(),
        );
        self.drawn_scratch = drawn;
        // The sea, in the visible and the sensors' views alike.
        let sea_vertices = self.sea.prepare(
            &self.gpu,
            [&self.globals, &self.thermal],
            &camera,
            snapshot.sea.as_ref(),
            &snapshot.wakes,
        );
        self.write_globals(
            &camera,
            &lighting,
            snapshot,
            (options.key_background, wire, sea_vertices > 0),
            sensor.as_ref(),
            (nvg.as_ref(), &local),
        );
        self.celestial
            .prepare(&self.gpu, snapshot, view.eye, nvg.is_some());
        if !terrain_frame.records.is_empty() {
            self.gpu.queue.write_buffer(
                &self.node_records,
                0,
                bytemuck::cast_slice(&terrain_frame.records),
            );
        }
        self.terrain
            .write_indices(&self.gpu, &terrain_frame.indices);
        self.terrain.write_patches(
            &self.gpu,
            &terrain_frame.patch_vertices,
            &terrain_frame.patch_indices,
            &terrain_frame.patch_marks,
        );
        let klod_nominal = self.detail.klod_for(&camera.view);
        let klod = self
            .overload_control(view_index)
            .map_or(klod_nominal, |c| c.klod(klod_nominal));
        let point_of_interest = snapshot
            .points_of_interest_deg
            .get(view_index)
            .copied()
            .flatten();
        let draws = self.entity_draws(&camera, snapshot, klod_nominal, klod, point_of_interest);
        let instance_records: Vec<InstanceRecord> = draws.iter().map(|d| d.1).collect();
        let culture_started = std::time::Instant::now();
        // Culture is culled behind the terrain only where the terrain is drawn as the horizon
        // takes it: every wanted node at its own mesh. The drawn surface may stand its level of
        // detail's pixel error off the finest one, or (while nodes morph in from their
        // parent's shape) about twice that: a pixel more.
        let terrain_settled = mesh_stats.deferred == 0
            && mesh_stats.stand_ins == 0
            && mesh_stats.dropped == 0
            && nodes.len() == selection.nodes.len();
        let pixel_error = snapshot.max_pixel_error.max(0.0);
        let margin_px = if options.fade_in_s > 0.0 {
            1.0 + 2.0 * pixel_error
        } else {
            1.0 + pixel_error
        };
        let occlusion_margin_px = (self.culture_occlusion && terrain_settled).then_some(margin_px);
        let culture = if snapshot.culture {
            self.culture_frame(
                cache,
                &camera,
                snapshot,
                [klod, klod_nominal],
                point_of_interest,
                (options.mesh_budget == usize::MAX, occlusion_margin_px),
            )
        } else {
            CultureFrame::default()
        };
        let culture_cpu_ms = culture_started.elapsed().as_secs_f64() * 1e3;
        // Culture draws: a level's range, first instance and instance count; the culture's
        // instances follow the entities' in the instance buffer, written as they are.
        let culture_first = instance_records.len();
        let binding_records = self.gpu.device.limits().max_storage_buffer_binding_size as usize
            / std::mem::size_of::<InstanceRecord>();
        let room = MAX_CULTURE_INSTANCES
            .min(binding_records.saturating_sub(culture_first))
            .min(culture.instance_count());
        let culture_draws: Vec<(LevelRange, u32, u32)> = culture
            .draws
            .iter()
            .filter_map(|draw| {
                let range = self.culture_lods.get(draw.kind as usize)?.get(draw.level)?;
                let end = draw.instances.end.min(room);
                (draw.instances.start < end).then(|| {
                    (
                        *range,
                        (culture_first + draw.instances.start) as u32,
                        (end - draw.instances.start) as u32,
                    )
                })
            })
            .collect();
        self.reserve_instances(culture_first + room);
        if !instance_records.is_empty() {
            self.gpu.queue.write_buffer(
                &self.instances,
                0,
                bytemuck::cast_slice(&instance_records),
            );
        }
        // Each draw's instances straight from their bucket, as far as there is room.
        for draw in &culture.draws {
            let end = draw.instances.end.min(room);
            if draw.instances.start >= end {
                break;
            }
            let instances = &culture.instances_of(draw)[..end - draw.instances.start];
            self.gpu.queue.write_buffer(
                &self.instances,
                ((culture_first + draw.instances.start) * std::mem::size_of::<InstanceRecord>())
                    as u64,
                bytemuck::cast_slice::<CultureInstance, u8>(instances),
            );
        }
        let (culture_drawn, culture_occluded) = (culture.objects_drawn, culture.blocks_occluded);
        // Its room serves the next frame.
        self.culture.recycle(culture);

        let sensor_view = snapshot.sensor_of(view_index);
        let puff_count = self
            .puffs
            .prepare(&self.gpu, &camera, snapshot, sensor_view);
        let cloud_count = self.clouds.prepare(&self.gpu, &camera, snapshot);
        // Below the clouds, the puffs are nearer: clouds first. Timestamp queries are numbered
        // in the order passes need them, so the written ones are 0..queries.
        let clouds_first = cloud_count > 0 && (puff_count == 0 || self.clouds.eye_below_clouds());
        let mut queries = 2u32;
        let mut next_query = || {
            queries += 1;
            queries - 1
        };
        let puff_queries = (puff_count > 0).then(|| (next_query(), next_query()));
        let cloud_queries = (cloud_count > 0).then(|| (next_query(), next_query()));
        // Sensor views draw no lightning or rain (sensor.rs's limits).
        let (bolt_lines, particles) = if sensor.is_some() {
            (0, 0)
        } else {
            (
                self.bolts
                    .prepare(&self.gpu, &self.globals, &camera, snapshot),
                self.precipitation
                    .prepare(&self.gpu, &camera, snapshot, &lighting),
            )
        };
        let size = (view.width_px, view.height_px);
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        let mut stats = FrameStats {
            terrain_nodes: terrain_frame.nodes as u32,
            nodes_visited: selection.visited as u32,
            meshes_built: mesh_stats.built as u32,
            meshes_deferred: mesh_stats.deferred as u32,
            node_stand_ins: mesh_stats.stand_ins as u32,
            nodes_dropped: (mesh_stats.dropped + selection.nodes.len() - nodes.len()) as u32,
            tiles_resident: cache.stats().resident_tiles as u32,
            tiles_wanted: selection.wanted_tiles.len() as u32,
            imagery_tiles_uploaded: imagery_stats.tiles_uploaded as u32,
            imagery_tiles_pending: imagery_stats.tiles_pending as u32,
            cpu_select_ms,
            illuminance_lux: lighting.natural_illuminance_lux,
            exposure_ev: cig_scene::lighting::exposure_value(lighting.adapted_illuminance_lux)
                - snapshot.sky.exposure_compensation_ev,
            klod,
            klod_nominal,
            overload: "off",
            ..Default::default()
        };
        self.targets(size);
        // The frame starts with the sky-view table's pass (physical sky) or the scene pass.
        let begin = |set| wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: None,
        };
        if physical_sky {
            self.atmosphere.encode_sky_view(
                &self.gpu,
                &mut encoder,
                self.specialise.then(|| lighting.moon_lights_the_sky()),
                self.timestamps.as_ref().map(|(set, _, _)| begin(set)),
            );
            stats.draw_calls += 1;
        }
        {
            let timestamp_writes = self
                .timestamps
                .as_ref()
                .filter(|_| !physical_sky)
                .map(|(set, _, _)| begin(set));
            let switches = self.specialise.then(|| ShaderSwitches::of(snapshot));
            let terrain_pipeline = self.terrain_pipelines.get(&self.gpu, switches, wire);
            let Some(targets) = self.targets.as_ref() else {
                return Err(RenderError::Gpu("render targets missing".into()));
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.msaa_colour,
                    depth_slice: None,
                    resolve_target: Some(&targets.hdr),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        // Kept for the puff, cloud and halo passes, which read it.
                        store: if puff_count > 0
                            || cloud_count > 0
                            || self.light_points.needs_halo_pass(light_count)
                        {
                            wgpu::StoreOp::Store
                        } else {
                            wgpu::StoreOp::Discard
                        },
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes,
                ..Default::default()
            });
            pass.set_pipeline(terrain_pipeline);
            pass.set_bind_group(0, &self.terrain_bind, &[]);
            pass.set_bind_group(1, &self.atmosphere.scene_bind, &[]);
            pass.set_bind_group(2, &self.terrain.marks_bind, &[]);
            pass.set_vertex_buffer(0, self.terrain.vertex_pool.slice(..));
            if !terrain_frame.indices.is_empty() {
                pass.set_index_buffer(
                    self.terrain.index_buffer.slice(..),
                    wgpu::IndexFormat::Uint32,
                );
                pass.draw_indexed(0..terrain_frame.indices.len() as u32, 0, 0..1);
                stats.draw_calls += 1;
            }
            if let (false, Some(vertices), Some(indices)) = (
                terrain_frame.patch_indices.is_empty(),
                self.terrain.patch_vertices.as_ref(),
                self.terrain.patch_indices.as_ref(),
            ) {
                // The terrain edits' patches, in the cells the nodes leave to them.
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..terrain_frame.patch_indices.len() as u32, 0, 0..1);
                stats.draw_calls += 1;
            }
            stats.terrain_triangles =
                (terrain_frame.indices.len() + terrain_frame.patch_indices.len()) as u64 / 3;

            if !draws.is_empty() || !culture_draws.is_empty() {
                pass.set_pipeline(&self.model_pipeline);
                pass.set_bind_group(0, &self.model_bind, &[]);
                pass.set_bind_group(1, &self.atmosphere.scene_bind, &[]);
                pass.set_vertex_buffer(0, self.model_vertices.slice(..));
                pass.set_index_buffer(self.model_indices.slice(..), wgpu::IndexFormat::Uint32);
            }
            for (i, (range, _)) in draws.iter().enumerate() {
                let (first, count, base, tris) = *range;
                pass.draw_indexed(first..first + count, base, i as u32..i as u32 + 1);
                stats.model_triangles += u64::from(tris);
            }
            // A model blending two levels is drawn twice; count it once.
            stats.entities_drawn = draws.iter().filter(|d| d.1.col0[3] == 0.0).count() as u32;
            for &((first, count, base, tris), first_instance, instances) in &culture_draws {
                pass.draw_indexed(
                    first..first + count,
                    base,
                    first_instance..first_instance + instances,
                );
                stats.culture_triangles += u64::from(tris) * u64::from(instances);
            }
            stats.draw_calls += (draws.len() + culture_draws.len()) as u32;
            stats.culture_drawn = culture_drawn as u32;
            stats.culture_blocks_occluded = culture_occluded as u32;
            stats.culture_cpu_ms = culture_cpu_ms;
            if let (true, Some(bind)) = (sea_vertices > 0, self.sea.bind_group()) {
                pass.set_pipeline(&self.sea_pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.set_bind_group(1, &self.atmosphere.scene_bind, &[]);
                pass.set_index_buffer(self.sea.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..sea_vertices, 0, 0..1);
                stats.draw_calls += 1;
            }
            // The sky where no geometry was drawn (its depth test passes at the cleared far
            // plane only).
            pass.set_pipeline(&self.sky_pipeline);
            pass.set_bind_group(0, &self.sky_bind, &[]);
            pass.set_bind_group(1, &self.atmosphere.scene_bind, &[]);
            pass.set_bind_group(2, self.celestial.bind_group(), &[]);
            pass.draw(0..3, 0..1);
            stats.draw_calls += 1;
            // After the opaque geometry and the sky: lightning (additive) and rain or snow
            // (over).
            stats.draw_calls += self.bolts.draw(&mut pass, bolt_lines);
            stats.draw_calls += self.light_points.draw(&mut pass, light_count);
            stats.light_points = light_count as u32;
            stats.draw_calls += self.precipitation.draw(&mut pass, particles);
            stats.bolt_lines_drawn = bolt_lines as u32;
            stats.precipitation_particles = particles;
        }
        self.terrain_frame = terrain_frame;
        let set = self.timestamps.as_ref().map(|(set, _, _)| set);
        if clouds_first {
            let Some(targets) = self.targets.as_ref() else {
                return Err(RenderError::Gpu("render targets missing".into()));
            };
            stats.draw_calls += self.clouds.encode(
                &mut encoder,
                &targets.hdr,
                set.zip(cloud_queries).map(|(s, (b, e))| (s, b, Some(e))),
            );
        }
        if puff_count > 0 {
            let Some(targets) = self.targets.as_ref() else {
                return Err(RenderError::Gpu("render targets missing".into()));
            };
            stats.draw_calls += self.puffs.encode(
                &mut encoder,
                &targets.hdr,
                &targets.depth,
                puff_count,
                &self.atmosphere.scene_bind,
                set.zip(puff_queries).map(|(s, (b, e))| (s, b, e)),
            );
            stats.puffs_drawn = puff_count as u32;
        }
        if cloud_count > 0 && !clouds_first {
            let Some(targets) = self.targets.as_ref() else {
                return Err(RenderError::Gpu("render targets missing".into()));
            };
            stats.draw_calls += self.clouds.encode(
                &mut encoder,
                &targets.hdr,
                set.zip(cloud_queries).map(|(s, (b, e))| (s, b, Some(e))),
            );
        }
        stats.cloud_layers_drawn = cloud_count as u32;
        // A goggle's halos: in the tube, over whatever is in front of them.
        if let Some(targets) = self.targets.as_ref() {
            stats.draw_calls += self.light_points.encode_halos(
                &self.gpu,
                &mut encoder,
                &self.globals,
                (&targets.hdr, &targets.depth),
                light_count,
            );
        }
        // The eye adapts to what the view shows (not to keyed test frames, not with a fixed
        // exposure).
        // A sensor's AC coupling acts on the signal before its gain is set.
        if let (Some((view, frame)), Some(ac), Some(targets)) =
            (&sensor, self.ac_coupling.as_mut(), self.targets.as_ref())
        {
            ac.encode(
                &self.gpu,
                &mut encoder,
                (&targets.hdr_texture, &targets.hdr),
                size,
                view.ac_coupling_us,
                // The level the display shows mid-grey: the manual window's centre, else the
                // automatic gain's histogram range's.
                frame.manual.map_or(
                    0.5 * (frame.histogram_range.0 + frame.histogram_range.1),
                    |(lo, hi)| 0.5 * (lo + hi),
                ),
            );
        }
        let adapted = if let Some((_, frame)) = &sensor {
            self.adaptation.encode_sensor(
                &self.gpu,
                &mut encoder,
                size,
                crate::adaptation::SensorAdaptRequest {
                    slot: view_index,
                    range: frame.histogram_range,
                    min_span: 2.0 * frame.slope,
                    manual: frame.manual,
                    adaptation: options.adaptation,
                },
            )
        } else {
            self.adaptation.encode(
                &self.gpu,
                &mut encoder,
                size,
                AdaptRequest {
                    slot: view_index,
                    log2_key: match nvg {
                        Some(nvg) => (cig_scene::nvg::OUTPUT_KEY * nvg.gain).log2(),
                        None => cig_scene::lighting::shown_grey_log2(
                            lighting.adapted_illuminance_lux,
                            snapshot.sky.exposure_compensation_ev,
                        ) as f32,
                    },
                    // The eye's fixed exposure does not switch off a goggle's control.
                    adaptation: if nvg.is_none()
                        && (options.key_background || snapshot.sky.fixed_exposure_ev.is_some())
                    {
                        Adaptation::Off
                    } else {
                        options.adaptation
                    },
                    hold: snapshot.flash_lux > 0.0,
                    intensifier: nvg.map(|nvg| {
                        let unit = (cig_scene::lighting::LIGHTING_UNITS_PER_LUX * lighting.exposure)
                            .log2() as f32;
                        let (lowest, highest) = nvg.gain_limits();
                        crate::adaptation::IntensifierControl {
                            lowest_log2: lowest.log2() as f32 - unit,
                            highest_log2: highest.log2() as f32 - unit,
                            tau_s: nvg.tube.abc_tau_s as f32,
                        }
                    }),
                },
            )
        };
        {
            let Some(targets) = self.targets.as_ref() else {
                return Err(RenderError::Gpu("render targets missing".into()));
            };
            self.tone_map.encode(
                &mut encoder,
                &self.sky_bind,
                &targets.tone_map_bind,
                target,
                self.timestamps
                    .as_ref()
                    .map(|(set, _, _)| wgpu::RenderPassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: None,
                        end_of_pass_write_index: Some(1),
                    }),
            );
            stats.draw_calls += 1;
        }
        if let Some((set, resolve, readback)) = &self.timestamps {
            encoder.resolve_query_set(set, 0..queries, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, readback, 0, u64::from(queries) * 8);
        }
        stats.triangles = stats.terrain_triangles + stats.model_triangles + stats.culture_triangles;
        let submit_started = std::time::Instant::now();
        self.gpu.queue.submit([encoder.finish()]);
        stats.cpu_frame_ms = started.elapsed().as_secs_f64() * 1e3;
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        let wall_gpu_ms = submit_started.elapsed().as_secs_f64() * 1e3;
        if adapted {
            if let Some(factor_log2) = self.adaptation.read_factor_log2(&self.gpu) {
                stats.view_adaptation_ev = f64::from(factor_log2);
                stats.exposure_ev -= f64::from(factor_log2);
            }
        }
        let spans = PassQueries {
            count: queries,
            puff: puff_queries,
            cloud: cloud_queries,
        };
        (
            stats.gpu_ms,
            stats.puff_gpu_ms,
            stats.cloud_gpu_ms,
            stats.gpu_timed_by,
        ) = match self.read_timestamps(&spans) {
            Some((frame_ms, puff_ms, cloud_ms)) => (frame_ms, puff_ms, cloud_ms, "timestamp_query"),
            None => (wall_gpu_ms, 0.0, 0.0, "submit_to_completion"),
        };
        // The overload control takes this frame's counters for the next frame. The time from
        // submission to completion includes waits that are not the GPU's: only timestamp
        // queries count as the GPU's time (0: unknown, ignored).
        let counters = OverloadCounters {
            triangles: stats.triangles,
            models: stats.entities_drawn,
            gpu_ms: if stats.gpu_timed_by == "timestamp_query" {
                stats.gpu_ms
            } else {
                0.0
            },
        };
        if let Some(control) = self.overload_control(view_index) {
            control.update(klod_nominal, &counters);
            stats.overload = control.last_action().name();
        }
        Ok(stats)
    }

    /// (frame, puff passes, cloud pass) GPU milliseconds from the timestamp queries.
    fn read_timestamps(&self, spans: &PassQueries) -> Option<(f64, f64, f64)> {
        let (_, _, readback) = self.timestamps.as_ref()?;
        let slice = readback.slice(..);
        crate::gpu::map_for_reading(&self.gpu, &slice).ok()?;
        let ticks: Vec<u64> = {
            let data = slice.get_mapped_range().ok()?;
            let v: &[u64] = bytemuck::cast_slice(&data);
            v.iter().take(spans.count as usize).copied().collect()
        };
        readback.unmap();
        let period_ms = f64::from(self.gpu.queue.get_timestamp_period()) / 1e6;
        let span = |(begin, end): (u32, u32)| -> f64 {
            let at = |i: u32| ticks.get(i as usize).copied().unwrap_or(0);
            at(end).saturating_sub(at(begin)) as f64 * period_ms
        };
        Some((
            span((0, 1)),
            spans.puff.map_or(0.0, span),
            spans.cloud.map_or(0.0, span),
        ))
    }

    fn write_globals(
        &self,
        camera: &Camera,
        lighting: &Lighting,
        snapshot: &FrameSnapshot,
        (key_background, wire, sea_drawn): (bool, bool, bool),
        sensor: Option<&(SensorView, crate::sensor::SensorFrame)>,
        (nvg, local): (Option<&NvgView>, &[cig_scene::lights::LocalLight]),
    ) {
        let v4 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        let c4 = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
        let [tl, tr, td, tu] = camera.view.fov.tangents();
        // The horizon's dip from the eye's height above mean sea level (the geoid), where the
        // sea's horizon lies.
        let eye = camera.view.eye;
        let sea_level_m = self.sea.undulation_m(eye.lat_deg, eye.lon_deg)
            + snapshot.sea.as_ref().map_or(0.0, |sea| sea.level_m);
        let alt = (eye.alt_m - sea_level_m).max(0.0);
        let refraction_k = snapshot.refraction_k.clamp(-1.0, 0.9);
        let dip = (2.0 * alt * (1.0 - refraction_k) / cig_geo::WGS84_A_M).sqrt();
        // The database's sea posts lie at mean sea level whatever the tide: water posts up to
        // there or the sea's level (the higher) and half a metre are the sea's
        // (`cig_scene::sea::SEA_POST_TOLERANCE_M`), drawn by the sea pass instead.
        let sea_cut = sea_drawn;
        let sea_cut_rel_m = self.sea.undulation_m(eye.lat_deg, eye.lon_deg)
            + snapshot
                .sea
                .as_ref()
                .map_or(0.0, |sea| sea.level_m.max(0.0))
            + cig_scene::sea::SEA_POST_TOLERANCE_M
            - eye.alt_m;
        let fog = snapshot.fog;
        let mode = f32::from(fog_mode_index(fog.mode));
        // The detail noise lies in the database centre's tangent plane (world-fixed, the same
        // for every node): the eye's place there, in cells, modulo the noise's period.
        let [east, north] = self.detail_axes;
        let noise = |cell: f64| {
            let m = |x: f64| (x / cell).rem_euclid(256.0) as f32;
            [
                m(camera.eye_ecef.dot(east)),
                m(camera.eye_ecef.dot(north)),
                0.0,
                cell as f32,
            ]
        };
        let mut globals = Globals {
            view_proj: camera.view_projection().to_cols_array_2d(),
            // w: vertices of each terrain node's slot (the shader's slot of a vertex).
            cam_forward: v4(camera.forward, f64::from(self.terrain.vertices_per_node)),
            // w: 1 to draw the ground's detail (the unspecialised terrain pipeline reads it).
            cam_right: v4(camera.right, f64::from(u8::from(snapshot.ground_detail))),
            cam_up: v4(camera.up, 0.0),
            tangents: [tl as f32, tr as f32, td as f32, tu as f32],
            eye_up: v4(camera.local_up, dip),
            sun_dir: v4(lighting.sun_direction, lighting.sun_elevation_deg),
            sun_colour: c4(lighting.sun_colour),
            ambient: c4(lighting.ambient_colour),
            sky_zenith: c4(lighting.sky_zenith),
            sky_horizon: c4(lighting.sky_horizon),
            fog_colour: c4(lighting.fog_colour),
            fog: [
                mode,
                fog.density_per_m as f32,
                fog.start_m as f32,
                fog.end_m as f32,
            ],
            noise0: noise(NOISE_CELLS_M[0]),
            noise1: noise(NOISE_CELLS_M[1]),
            noise2: noise(NOISE_CELLS_M[2]),
            flags: [
                if wire { 1.0 } else { 0.0 },
                lighting.exposure as f32,
                if key_background { 1.0 } else { 0.0 },
                camera.pixels_per_tangent as f32,
            ],
            // w: the earth's radius at the eye (the sea, its cut and the refraction).
            fog_layer: match drawn_ground_fog(snapshot) {
                Some(layer) => [
                    (layer.top_m - camera.view.eye.alt_m) as f32,
                    layer.extinction_per_m() as f32,
                    1.0,
                    earth_radius_m(eye.lat_deg) as f32,
                ],
                _ => [0.0, 0.0, 0.0, earth_radius_m(eye.lat_deg) as f32],
            },
            moon_dir: v4(lighting.moon_direction, lighting.moon_elevation_deg),
            moon_colour: c4(lighting.moon_colour),
            sun_toa: c4(lighting.sun_toa_colour),
            // w: whether the moon lights the sky (the unspecialised sky-view pass reads it).
            moon_toa: {
                let [r, g, b] = lighting.moon_toa_colour;
                [r, g, b, f32::from(u8::from(lighting.moon_lights_the_sky()))]
            },
            atmos: [
                // The atmosphere's ground is mean sea level: the eye's height above the geoid.
                (cig_environment::AtmosphereParams::EARTH.bottom_radius_m
                    + alt.clamp(1.0, 99_000.0)) as f32,
                match snapshot.sky.model {
                    SkyModel::Physical => 0.0,
                    SkyModel::Flat => 1.0,
                },
                0.0,
                0.0,
            ],
            night_sky: c4(lighting.night_sky_colour),
            tonemap: [
                if self.colour_format.is_srgb() {
                    0.0
                } else {
                    1.0
                },
                lighting.scotopic_fraction as f32,
                lighting.natural_illuminance_lux as f32,
                // w: terrestrial refraction's coefficient (common.wgsl's `refracted`).
                refraction_k as f32,
            ],
            sky_frame_x: [0.0; 4],
            sky_frame_y: [0.0; 4],
            // w: whether the sea replaces the database's water posts at its level, and the
            // height (relative to the eye, metres) at or below which a water post is sea.
            detail_east: v4(east, if sea_cut { 1.0 } else { 0.0 }),
            detail_north: v4(north, sea_cut_rel_m),
            ..Default::default()
        };
        if let Some((view, frame)) = sensor {
            let sky = frame.sky;
            globals.sensor = [
                1.0,
                f32::from(u8::from(view.band == cig_thermal::IrBand::Mwir)),
                frame.down_radiance,
                frame.sun_irradiance,
            ];
            globals.sensor_sky0 = [sky[0], sky[1], sky[2], sky[3]];
            globals.sensor_sky1 = [sky[4], sky[5], sky[6], sky[7]];
            globals.sensor_display = [
                f32::from(u8::from(view.polarity == Polarity::BlackHot)),
                match view.display {
                    DisplayColour::White => 0.0,
                    DisplayColour::Green => 1.0,
                    DisplayColour::Black => 2.0,
                },
                view.netd_k.max(0.0) * frame.slope,
                view.fixed_pattern.max(0.0),
            ];
            globals.sensor_display2 = [
                view.blur_px.max(0.0),
                f32::from(u8::from(view.line_dropout)),
                (self.frame % 65_536) as f32,
                frame.cloud_radiance,
            ];
        }
        globals.nvg3[1] = 1.0;
        // Lights that light the surfaces near the eye: intensities as illuminance at 1 m in
        // the frame's light units (NVG-weighted on goggles).
        for (i, light) in local.iter().take(MAX_LOCAL_LIGHTS).enumerate() {
            let intensity = if nvg.is_some() {
                light.nvg_intensity_cd
            } else {
                light.intensity_cd
            };
            let [x, y, z] = light.rel_m;
            // On goggles the signal is one number (lx_A), carried grey.
            let [r, g, b] = if nvg.is_some() {
                [1.0; 3]
            } else {
                light.colour
            };
            let [ax, ay, az] = light.axis;
            let beam = light.axis != [0.0; 3];
            globals.local_lights[3 * i] = [
                x,
                y,
                z,
                (f64::from(intensity) * cig_scene::lighting::LIGHTING_UNITS_PER_LUX) as f32,
            ];
            globals.local_lights[3 * i + 1] =
                [r, g, b, if beam { light.cos_half_width } else { -2.0 }];
            globals.local_lights[3 * i + 2] = [ax, ay, az, light.back_fraction];
            globals.nvg3[2] = (i + 1) as f32;
        }
        if let Some(nvg) = nvg {
            let fov_deg = f64::from(nvg.fov_deg);
            let pixel_deg = (1.0 / camera.pixels_per_tangent).atan().to_degrees();
            let scene_unit_lxa = cig_scene::lighting::LIGHTING_UNITS_PER_LUX * lighting.exposure;
            globals.nvg = [
                1.0,
                (nvg.tube.photoelectrons_per_lxa_deg2(fov_deg) * pixel_deg * pixel_deg
                    / scene_unit_lxa) as f32,
                (nvg.tube.mcp_excess_noise - 1.0).max(0.0) as f32,
                (0.5 * fov_deg).to_radians().tan() as f32,
            ];
            let [r, g, b] = nvg.phosphor.colour();
            globals.nvg2 = [
                r,
                g,
                b,
                (nvg.tube.blur_sigma_deg(fov_deg) / pixel_deg) as f32,
            ];
            // (nvg3.z, the local lights' count, is set above.)
            globals.nvg3[0] = f32::from(u8::from(nvg.noise));
            globals.nvg3[1] = cig_environment::nvg::LightSpectrum::Flame.nvg_per_lux() as f32;
            globals.sensor_display2[2] = (self.frame % 65_536) as f32;
        }
        (globals.sky_frame_x, globals.sky_frame_y) =
            sky_frame(globals.eye_up, globals.sun_dir, globals.atmos[0]);
        (globals.atmos[2], globals.atmos[3]) = eye_densities(globals.atmos[0]);
        self.gpu
            .queue
            .write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
    }

    /// Index ranges and instance records of the entities to draw (culled, level chosen).
    #[allow(
        clippy::type_complexity,
        reason = "a private (range, record) pair list"
    )]
    fn entity_draws(
        &mut self,
        camera: &Camera,
        snapshot: &FrameSnapshot,
        klod_nominal: f64,
        klod_controlled: f64,
        point_of_interest_deg: Option<[f64; 2]>,
    ) -> Vec<((u32, u32, i32, u32), InstanceRecord)> {
        let mut out = Vec::new();
        let aim = aim_of(camera, point_of_interest_deg);
        // Entities with hot parts: their slots in the thermal buffer (sensor.rs), 1-based.
        let hot_slots: HashMap<u32, u32> = snapshot
            .thermal
            .as_ref()
            .map(|t| {
                t.entity_heat
                    .iter()
                    .take(crate::sensor::MAX_HOT_ENTITIES)
                    .enumerate()
                    .map(|(i, (id, _))| (*id, i as u32 + 1))
                    .collect()
            })
            .unwrap_or_default();
        for entity in snapshot.entities.iter().take(MAX_INSTANCES) {
            let Some(model) = self.models.get(&entity.model) else {
                continue;
            };
            let origin = entity.position.to_ecef();
            let rel = origin - camera.eye_ecef;
            let radius = f64::from(model.model.bounding_radius_m);
            // Cull by the bounding sphere: outside any plane by more than the radius.
            if camera
                .planes
                .iter()
                .any(|p| p.normal.dot(rel) < p.offset_m - radius)
            {
                continue;
            }
            let distance = rel.length().max(1.0);
            // The detail control parameter (source 004, Eq 16): K_LOD r_c / R_s, removed at
            // 98 % fade in the frame's fog, lowered away from the view's centre (the point of
            // interest). Cue-important models keep the nominal K_LOD under overload (§4.6).
            let klod = klod_for(entity.cue_important, klod_nominal, klod_controlled);
            // The global fog and the ground fog layer along the ray (f(v), §4.7).
            let layer = drawn_ground_fog(snapshot).map_or(1.0, |l| {
                l.transmittance(camera.view.eye.alt_m, entity.position.alt_m, distance)
            });
            let fade = 1.0 - snapshot.fog.factor(distance) * layer;
            let angle_deg = aim.angle_between(rel).to_degrees();
            let ne = self.detail.ne(
                klod,
                f64::from(
                    entity
                        .critical_radius_m
                        .unwrap_or_else(|| model.model.critical_radius_m()),
                ),
                distance,
                fade,
                angle_deg,
            );
            let blend = model.model.lod_blend(ne, &self.detail.table);
            if blend.coverage <= 0.0 {
                continue;
            }
            // (level, share of the pixels [from, to) in dither thresholds); a whole level
            // draws up to 2, past every threshold.
            let split = blend.finer_share * blend.coverage;
            let whole = |share: f32| if share >= 1.0 { 2.0 } else { share };
            let mut levels = vec![(blend.finer, 0.0, whole(split))];
            if let Some(coarser) = blend.coarser {
                levels.push((coarser, split, whole(blend.coverage)));
            }
            let enu = cig_geo::EnuFrame::new(Geodetic::new(
                entity.position.lat_deg,
                entity.position.lon_deg,
                entity.position.alt_m,
            ));
            let (forward, right, up) = entity.orientation.axes_enu();
            let col = |v: glam::DVec3, w: f32| {
                let e = enu.enu_vector_to_ecef(v);
                [e.x as f32, e.y as f32, e.z as f32, w]
            };
            // The thermal word (thermal.wgsl): the default material's code and the hot slot.
            let default_code = cig_scene::thermal::material_code(
                cig_scene::thermal::default_material_for_model(&entity.model),
            );
            let slot = hot_slots.get(&entity.id).copied().unwrap_or(0);
            let thermal_word = (u32::from(default_code) + 256 * slot) as f32;
            for (level, share_from, share_to) in levels {
                let Some(range) = model.lods.get(level).copied() else {
                    continue;
                };
                out.push((
                    range,
                    InstanceRecord {
                        col0: col(right, share_from),
                        col1: col(forward, share_to),
                        col2: col(up, thermal_word),
                        origin: [rel.x as f32, rel.y as f32, rel.z as f32, 0.0],
                    },
                ));
            }
        }
        out
    }

    /// The culture view `camera` draws: by the detail control parameter at `klod` (removed at
    /// 98 % fade in the frame's fog and ground fog layer, lowered toward the periphery), or,
    /// with `snapshot.culture_managed` off, everything resident at its finest level. `complete`
    /// (one-off frames) makes every tile's culture ready first instead of on the selector's
    /// thread. `occlusion_margin_px`: cull behind the terrain with this margin (`None`: not).
    fn culture_frame(
        &mut self,
        cache: &TileCache,
        camera: &Camera,
        snapshot: &FrameSnapshot,
        [klod, klod_nominal]: [f64; 2],
        point_of_interest_deg: Option<[f64; 2]>,
        (complete, occlusion_margin_px): (bool, Option<f64>),
    ) -> CultureFrame {
        let aim = aim_of(camera, point_of_interest_deg);
        let layer = drawn_ground_fog(snapshot);
        let eye_alt_m = camera.view.eye.alt_m;
        let fade = |distance_m: f64, alt_m: f64| {
            let t = layer.map_or(1.0, |l| l.transmittance(eye_alt_m, alt_m, distance_m));
            1.0 - snapshot.fog.factor(distance_m) * t
        };
        let detail = self.detail;
        let mut cue_important = [false; 9];
        for kind in &self.culture_cue_important {
            cue_important[*kind as usize] = true;
        }
        self.culture.select(
            cache,
            camera,
            &CultureSelect {
                detail: &detail,
                klod,
                klod_nominal,
                cue_important,
                aim,
                managed: snapshot.culture_managed,
                complete,
                occlusion_margin_px,
            },
            &fade,
        )
    }

    /// Makes the instance buffer hold at least `records` instance records.
    fn reserve_instances(&mut self, records: usize) {
        if records <= self.instance_capacity {
            return;
        }
        let capacity = records.next_power_of_two();
        self.instances = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (capacity * std::mem::size_of::<InstanceRecord>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.model_bind = model_bind_group(
            &self.gpu.device,
            &self.model_layout,
            [&self.globals, &self.instances, &self.thermal],
        );
        self.instance_capacity = capacity;
    }

    /// Least morph of each node: 1 when it first replaces its parent, falling to 0 over
    /// `fade_in_s` (root nodes and one-off frames: 0).
    fn fade_in(
        &mut self,
        view_index: usize,
        nodes: &[cig_scene::lod::SelectedNode],
        fade_in_s: f32,
    ) -> Vec<f32> {
        let now = std::time::Instant::now();
        let frame = self.frame;
        let mut out = Vec::with_capacity(nodes.len());
        for node in nodes {
            let entry = self
                .node_first_seen
                .entry((view_index, node.key))
                .or_insert((now, frame));
            // Not drawn last frame: it appears now.
            if entry.1 + 1 < frame {
                entry.0 = now;
            }
            entry.1 = frame;
            let least = if fade_in_s > 0.0 && node.morph_start_m.is_finite() {
                (1.0 - now.duration_since(entry.0).as_secs_f32() / fade_in_s).max(0.0)
            } else {
                0.0
            };
            out.push(least);
        }
        self.node_first_seen
            .retain(|(v, _), (_, last)| *v != view_index || *last == frame);
        out
    }

    /// The red channel of a rectangle `[x, y, width, height]` of the last frame's resolved scene
    /// (a sensor view's band radiance, W m-2 sr-1), row by row; clamped to the frame.
    pub fn read_scene_region(&self, [x, y, w, h]: [u32; 4]) -> Result<Vec<f32>, RenderError> {
        let targets = self
            .targets
            .as_ref()
            .ok_or_else(|| RenderError::Readback("no frame has been drawn".into()))?;
        let (fw, fh) = targets.size;
        let (x, y) = (x.min(fw.saturating_sub(1)), y.min(fh.saturating_sub(1)));
        let (w, h) = (w.min(fw - x).max(1), h.min(fh - y).max(1));
        // Rgba16Float: 8 bytes a pixel.
        let bytes_per_row = (w * 8).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene region"),
            size: u64::from(bytes_per_row) * u64::from(h),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scene region"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &targets.hdr_texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x, y, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(bytes_per_row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        crate::gpu::map_for_reading(&self.gpu, &slice)?;
        let mut out = Vec::with_capacity((w * h) as usize);
        {
            let data = slice
                .get_mapped_range()
                .map_err(|e| RenderError::Readback(e.to_string()))?;
            for row in data.chunks(bytes_per_row as usize).take(h as usize) {
                for px in row.chunks_exact(8).take(w as usize) {
                    out.push(f16_to_f32(u16::from_le_bytes([px[0], px[1]])));
                }
            }
        }
        buffer.unmap();
        Ok(out)
    }

    /// Sets the channel's display correction (`cig_scene::display`: warp grid and edge-blend
    /// ramps), applied by [`crate::render_image_with`] as the frame's last pass; `None` or an
    /// empty correction draws the frame as it is.
    pub fn set_display_correction(
        &mut self,
        correction: Option<cig_scene::display::DisplayCorrection>,
    ) {
        self.display = correction
            .filter(|c| !c.is_none())
            .map(|c| crate::display::DisplayPass::new(&self.gpu, c));
    }

    /// The display correction pass, when one is set.
    pub fn display_pass(&self) -> Option<&crate::display::DisplayPass> {
        self.display.as_ref()
    }

    /// Sets the overload control (source 004 Table 4, [`cig_scene::overload`]); `None` turns
    /// it off. On by default with [`OverloadSettings::default`]'s generous levels. Every
    /// view starts again at its nominal `K_LOD`.
    pub fn set_overload(
        &mut self,
        settings: Option<OverloadSettings>,
    ) -> Result<(), OverloadError> {
        if let Some(s) = &settings {
            s.validate()?;
        }
        self.overload = settings;
        self.overload_controls.clear();
        Ok(())
    }

    /// The overload control's settings (`None`: off).
    pub fn overload(&self) -> Option<&OverloadSettings> {
        self.overload.as_ref()
    }

    /// View `view_index`'s overload control (made at the nominal `K_LOD` on first use).
    fn overload_control(&mut self, view_index: usize) -> Option<&mut OverloadControl> {
        let settings = self.overload?;
        while self.overload_controls.len() <= view_index {
            self.overload_controls
                .push(OverloadControl::new(settings).ok()?);
        }
        self.overload_controls.get_mut(view_index)
    }

    /// Nodes with a mesh on the GPU.
    pub fn resident_nodes(&self) -> usize {
        self.terrain.resident_nodes()
    }

    /// The selection a frame of `view` would draw (for tests and statistics).
    pub fn select(
        &mut self,
        cache: &TileCache,
        view: &cig_scene::View,
        max_pixel_error: f64,
    ) -> cig_scene::Selection {
        self.lod
            .select(cache, &view.camera(), &LodSettings { max_pixel_error })
    }
}
