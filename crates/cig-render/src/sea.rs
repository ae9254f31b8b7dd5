//! The sea surface: a polar grid of rings around the eye on the round earth, displaced by the
//! wave cascades' grids (`cig_scene::sea::SeaDraw`, computed on the CPU so that the height
//! queries and the picture are one surface) and shaded with Fresnel reflection of cig's sky,
//! the sun's glitter, the light the water body scatters up, and whitecaps.
//!
//! Algorithm: Tessendorf's FFT ocean drawn as a radial grid (rings spaced geometrically from
//! under the eye to past the horizon, so triangles keep a near-constant size on screen). Each
//! cascade is a repeating texture array layer with mipmaps made on the CPU; a vertex reads the
//! level whose texels match the grid's spacing there. Slopes are LEAN-mapped (Olano and Baker
//! 2010): the textures hold the slopes and their squares, so a pixel's filtered texels give the
//! mean slope and the variance of the slopes it covers; that variance, plus what no cascade
//! resolves (Cox and Munk's total less the grids'), widens the glitter's slope distribution.
//! Far off, where the waves are finer than a pixel, the sea therefore turns into the smooth
//! glitter pattern of its slope statistics instead of aliasing into shimmering noise. Sun glint
//! after Cox and Munk: `π L = π E F p(slope) / (4 μ_v μ_n⁴)`, with Schlick's Fresnel (water,
//! F0 = 0.02). Up to [`MAX_EXPLICIT_WAVES`] of the host's explicit waves are added as Gerstner
//! waves (their phases worked out at the eye in double precision), and up to [`MAX_WAKES`]
//! ships' wakes as foam. In a thermal sensor's view the water emits at its temperature with
//! water's infrared Fresnel emissivity (n = 1.22) and mirrors the sky's band radiance. The
//! terrain's pipelines built for a frame with a sea leave the database's water posts at sea
//! level to it (`terrain.wgsl`'s `is_sea`), so the waves show there.
//!
//! Limits: the sea lies at mean sea level plus the scene's level everywhere, the geoid taken at
//! the eye for the whole view (where it differs by more than half a metre the cut leaves the
//! posts drawn); the earth's curvature is its Gaussian radius at the eye (the posts' true
//! curvature differs by up to 0.35 % with direction: half a metre at about 40 km); no
//! refraction of what lies below the surface, no shadows on the water; a wake's turbulent foam
//! follows its stern's last two minutes in chords 5 s apart for the first 40 s and about 20 s
//! apart after, and goes on straight beyond (the bow wave and the Kelvin arms lie on the
//! present course).

use crate::gpu::Gpu;
use crate::pass::uniform_entry;
use cig_scene::sea::SeaDraw;
use cig_scene::Camera;
use cig_terrain::database::GeoidLookup;

/// Rings of the grid, from under the eye to its far edge.
const RINGS: u32 = 192;
/// Segments around each ring.
const SEGMENTS: u32 = 256;
/// Cascades the pass draws at most (texture array layers).
pub const MAX_CASCADES: usize = 4;

/// The most explicit waves (CIGI Wave Control) drawn: the highest.
pub const MAX_EXPLICIT_WAVES: usize = 8;

/// The most areas the drawn explicit waves are confined to (one per wave at most).
pub const MAX_WAVE_AREAS: usize = MAX_EXPLICIT_WAVES;

/// The most ships' wakes drawn: the nearest.
pub const MAX_WAKES: usize = 8;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SeaUniform {
    /// ECEF east at the eye; w: rings.
    east: [f32; 4],
    /// ECEF north at the eye; w: segments.
    north: [f32; 4],
    /// x: the sea's level relative to the eye (m, negative below it), y: the earth's radius
    /// (m), z: the grid's far radius (m), w: its first ring's radius (m).
    params: [f32; 4],
    /// The eye's east (xy) and north (zw) in the sea plane's axes (the meridians converge).
    axes: [f32; 4],
    /// Per cascade: the eye's place in the tile (fraction, east and north), the tile (m) and
    /// its texel (m).
    cascades: [[f32; 4]; MAX_CASCADES],
    /// x: unresolved slope variance, y: the whitecaps' Jacobian, z: cascades, w: mip levels.
    shade: [f32; 4],
    /// The water body's colour; w: explicit waves drawn.
    water: [f32; 4],
    /// Per explicit wave: its direction in the sea plane's axes (xy), wave number (z), its
    /// phase at the point under the eye (w, wrapped); then its amplitude and horizontal
    /// displacement amplitude (xy).
    waves: [[f32; 4]; 2 * MAX_EXPLICIT_WAVES],
    /// x: the water's surface temperature (K), for a thermal sensor's view; y: wakes drawn;
    /// z: wave areas drawn.
    thermal: [f32; 4],
    /// Per wave area (`cig_sea::surface::WaveArea`): its centre relative to the eye in the sea
    /// plane's axes (xy) and half sizes (zw); then the cosine and sine of its rotation, its
    /// corner radius and its transition band (m).
    areas: [[f32; 4]; 2 * MAX_WAVE_AREAS],
    /// Per wave area, 1 a region's, 2 an entity's.
    area_kinds: [[f32; 4]; MAX_WAVE_AREAS / 4],
    /// Per wake: the stern's place relative to the eye (east, north, metres) and the unit
    /// course (east, north); then speed (m/s), length and beam (m), the arms' half-angle
    /// (radians); then the foam made (0..1), its e-folding time (s).
    wakes: [[f32; 4]; 3 * MAX_WAKES],
    /// Per wake, [`WAKE_POINTS`] points of its turbulent wake's centreline from the stern
    /// astern: place relative to the eye (east, north, metres), the foam's age (s) and the
    /// wake's width (m) there; the last carries the track on straight to where the foam is
    /// gone.
    wake_tracks: [[f32; 4]; WAKE_POINTS * MAX_WAKES],
}

/// Points of a wake's centreline in the uniform: the stern, its past places, the straight end.
const WAKE_POINTS: usize = cig_scene::sea::WAKE_TRACK_POINTS + 2;

/// A wake's centreline as the uniform holds it (`SeaUniform::wake_tracks`).
type WakeLine = [[f32; 4]; WAKE_POINTS];

// sea.wgsl indexes a wake's centreline by 14 and holds 8 wakes' of them.
const _: () = assert!(WAKE_POINTS == 14 && WAKE_POINTS * MAX_WAKES == 112);

/// The straight end of a wake's centreline reaches this many foam e-folding times past its
/// last place (under 2 % of the foam is left there).
const WAKE_END_E_FOLDINGS: f64 = 4.0;

/// The sea's GPU state: three texture arrays (displacement, LEAN slopes, displacement
/// gradient), one layer per cascade, rebuilt when the cascades' size changes.
pub(crate) struct SeaPass {
    pub(crate) layout: wgpu::BindGroupLayout,
    /// The grid's triangles: two per quad of ring and segment, made once.
    pub(crate) indices: wgpu::Buffer,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    textures: Option<SeaTextures>,
    scratch: MipScratch,
    geoid: GeoidLookup,
    /// The sea whose grids the textures hold.
    uploaded: Option<std::sync::Arc<SeaDraw>>,
}

/// The mip chains' memory, kept from frame to frame: every level of one layer after another
/// (f32), and one level as the texture's f16 bits.
#[derive(Default)]
struct MipScratch {
    chain: Vec<[f32; 4]>,
    half: Vec<[u16; 4]>,
}

struct SeaTextures {
    size: u32,
    layers: u32,
    mips: u32,
    displacement: wgpu::Texture,
    slopes: wgpu::Texture,
    gradient: wgpu::Texture,
    bind: wgpu::BindGroup,
}

fn array_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    crate::pass::texture_entry_of(binding, wgpu::TextureViewDimension::D2Array)
}

impl SeaPass {
    pub(crate) fn new(gpu: &Gpu, geoid: GeoidLookup) -> SeaPass {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sea"),
            entries: &[
                uniform_entry(0),
                uniform_entry(1),
                array_entry(2),
                array_entry(3),
                array_entry(4),
                crate::pass::sampler_entry(5),
                crate::pass::storage_entry(9),
            ],
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sea"),
            size: std::mem::size_of::<SeaUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sea"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: 1,
            ..Default::default()
        });
        let mut grid = Vec::with_capacity((RINGS * SEGMENTS * 6) as usize);
        let vertex = |ring: u32, segment: u32| ring * (SEGMENTS + 1) + segment;
        for ring in 0..RINGS {
            for segment in 0..SEGMENTS {
                let (a, b) = (vertex(ring, segment), vertex(ring + 1, segment));
                let (c, d) = (vertex(ring + 1, segment + 1), vertex(ring, segment + 1));
                grid.extend_from_slice(&[a, b, c, a, c, d]);
            }
        }
        let indices = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("sea grid"),
                contents: bytemuck::cast_slice(&grid),
                usage: wgpu::BufferUsages::INDEX,
            },
        );
        SeaPass {
            layout,
            indices,
            uniform,
            sampler,
            textures: None,
            scratch: MipScratch::default(),
            geoid,
            uploaded: None,
        }
    }

    /// Uploads the frame's sea for `camera`; returns the indices to draw (0: nothing).
    /// `buffers`: the globals and the thermal tables (a sensor view's sea).
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        buffers: [&wgpu::Buffer; 2],
        camera: &Camera,
        sea: Option<&std::sync::Arc<SeaDraw>>,
        wakes: &[cig_scene::sea::WakeDraw],
    ) -> u32 {
        let Some(sea_arc) = sea else {
            return 0;
        };
        let sea: &SeaDraw = sea_arc;
        let cascades = &sea.cascades[..sea.cascades.len().min(MAX_CASCADES)];
        let Some(size) = cascades.first().map(|c| c.size) else {
            return 0;
        };
        if size < 2 || cascades.iter().any(|c| c.size != size) {
            tracing::warn!("the sea's cascades differ in size: not drawn");
            return 0;
        }
        let size = size as u32;
        let layers = cascades.len() as u32;
        if self
            .textures
            .as_ref()
            .is_none_or(|t| t.size != size || t.layers != layers)
        {
            self.textures = Some(self.make_textures(gpu, buffers, size, layers));
            self.uploaded = None;
        }
        let Some(textures) = self.textures.as_ref() else {
            return 0;
        };
        // The grids go up once per sea: the frame's other views reuse them.
        let uploaded = self
            .uploaded
            .as_ref()
            .is_some_and(|last| std::sync::Arc::ptr_eq(last, sea_arc));
        self.uploaded = Some(std::sync::Arc::clone(sea_arc));
        let scratch = &mut self.scratch;
        for (layer, grid) in (0u32..).zip(cascades).filter(|_| !uploaded) {
            let mut upload = |texture, texels: &mut dyn Iterator<Item = [f32; 4]>| {
                scratch.upload(gpu, texture, layer, size, textures.mips, texels);
            };
            upload(
                &textures.displacement,
                &mut grid
                    .height_displacement
                    .iter()
                    .map(|t| [t[0], t[1], t[2], 0.0]),
            );
            upload(
                &textures.slopes,
                &mut grid
                    .slopes
                    .iter()
                    .map(|s| [s[0], s[1], s[0] * s[0], s[1] * s[1]]),
            );
            upload(
                &textures.gradient,
                &mut grid
                    .displacement_gradient
                    .iter()
                    .map(|d| [d[0], d[1], d[2], 0.0]),
            );
        }
        // The point under the eye in the sea's plane, the eye's axes there, and the sea's level
        // relative to the eye.
        let eye = camera.view.eye;
        let sea_level_m = self.geoid.undulation_m(eye.lat_deg, eye.lon_deg) + sea.level_m;
        let plane = cig_geo::EnuFrame::new(sea.origin);
        let [eye_x, eye_y] = cig_scene::sea::sea_plane_xy(&plane, eye.lat_deg, eye.lon_deg);
        let here = cig_geo::EnuFrame::new(eye);
        let east = here.enu_vector_to_ecef(glam::DVec3::X);
        let north = here.enu_vector_to_ecef(glam::DVec3::Y);
        // Projected, not normalised: the eye's axes shorten by the cosine of its distance from
        // the origin over the earth's radius, as the plane's coordinates of its ground do.
        let axis = |v: glam::DVec3| {
            let p = plane.ecef_vector_to_enu(v).truncate();
            [p.x as f32, p.y as f32]
        };
        let ([ex, ey], [nx, ny]) = (axis(east), axis(north));
        let height_m = (eye.alt_m - sea_level_m).max(0.5);
        // The earth's radius the terrain's sea cut and the refraction use too.
        let radius_m = crate::renderer::earth_radius_m(eye.lat_deg);
        let far_m = ((2.0 * radius_m * height_m).sqrt() * 1.5 + 2_000.0).min(400_000.0);
        let mut uniform = SeaUniform {
            east: [east.x as f32, east.y as f32, east.z as f32, RINGS as f32],
            north: [
                north.x as f32,
                north.y as f32,
                north.z as f32,
                SEGMENTS as f32,
            ],
            params: [
                (sea_level_m - eye.alt_m) as f32,
                radius_m as f32,
                far_m as f32,
                (0.25 * height_m).clamp(0.05, 2.0) as f32,
            ],
            axes: [ex, ey, nx, ny],
            shade: [
                // Cascades past the textures' layers count as unresolved slopes.
                (sea.unresolved_slope_variance
                    + sea.cascades[cascades.len()..]
                        .iter()
                        .map(cig_scene::sea::slope_variance)
                        .sum::<f64>()) as f32,
                sea.whitecap_jacobian as f32,
                layers as f32,
                textures.mips as f32,
            ],
            water: [sea.water_rgb[0], sea.water_rgb[1], sea.water_rgb[2], 0.0],
            thermal: [(sea.water_temperature_c + 273.15) as f32, 0.0, 0.0, 0.0],
            ..bytemuck::Zeroable::zeroed()
        };
        // The wave areas nearest the eye (all of them cover the sea's precedence, as on the
        // CPU, up to MAX_WAVE_AREAS), and the highest explicit waves that reach the drawn sea,
        // their phases worked out at the eye in double precision.
        let area_distance = |a: &cig_scene::sea::WaveArea| {
            let d = (a.centre_m[0] - eye_x).hypot(a.centre_m[1] - eye_y);
            d - a.half_size_m[0].hypot(a.half_size_m[1]) - a.corner_radius_m - a.band_m()
        };
        let mut near_areas: Vec<usize> = (0..sea.wave_areas.len())
            .filter(|i| area_distance(&sea.wave_areas[*i]) < far_m)
            .collect();
        near_areas.sort_by(|a, b| {
            area_distance(&sea.wave_areas[*a]).total_cmp(&area_distance(&sea.wave_areas[*b]))
        });
        near_areas.truncate(MAX_WAVE_AREAS);
        for (slot, a) in near_areas.iter().map(|i| &sea.wave_areas[*i]).enumerate() {
            let (sin, cos) = a.rotation_deg.to_radians().sin_cos();
            uniform.areas[2 * slot] = [
                (a.centre_m[0] - eye_x) as f32,
                (a.centre_m[1] - eye_y) as f32,
                a.half_size_m[0] as f32,
                a.half_size_m[1] as f32,
            ];
            uniform.areas[2 * slot + 1] = [
                cos as f32,
                sin as f32,
                a.corner_radius_m as f32,
                a.band_m() as f32,
            ];
            uniform.area_kinds[slot / 4][slot % 4] = match a.kind {
                cig_scene::sea::AreaKind::Region => 1.0,
                cig_scene::sea::AreaKind::Entity => 2.0,
            };
        }
        uniform.thermal[2] = near_areas.len() as f32;
        // Each wave with its area's slot plus one (0: everywhere); a wave whose area is not
        // near is not drawn.
        let mut explicit: Vec<_> = sea
            .explicit_waves
            .iter()
            .zip(sea.explicit_areas.iter().chain(std::iter::repeat(&None)))
            .filter_map(|(wave, area)| match area {
                None => Some((wave, 0.0)),
                Some(i) => near_areas
                    .iter()
                    .position(|n| n == i)
                    .map(|slot| (wave, (slot + 1) as f32)),
            })
            .collect();
        explicit.sort_by(|a, b| b.0.amplitude_m.total_cmp(&a.0.amplitude_m));
        explicit.truncate(MAX_EXPLICIT_WAVES);
        uniform.water[3] = explicit.len() as f32;
        for (slots, (wave, area_slot)) in uniform.waves.chunks_exact_mut(2).zip(explicit) {
            let [dx, dy] = wave.direction;
            let phase = wave.k_rad_m * (dx * eye_x + dy * eye_y) - wave.omega_rad_s * sea.time_s
                + wave.phase_rad;
            slots[0] = [
                dx as f32,
                dy as f32,
                wave.k_rad_m as f32,
                phase.rem_euclid(std::f64::consts::TAU) as f32,
            ];
            slots[1] = [
                wave.amplitude_m as f32,
                wave.displacement_m as f32,
                area_slot,
                0.0,
            ];
        }
        // The nearest wakes, their sterns relative to the eye in its east and north, and
        // their centrelines astern along the sterns' past places.
        let mut near: Vec<(f64, [[f32; 4]; 3], WakeLine)> = wakes
            .iter()
            .map(|w| {
                let centre = here.geodetic_to_enu(w.position);
                let (s, c) = w.heading_deg.to_radians().sin_cos();
                let stern = [
                    centre.x - s * 0.5 * w.length_m,
                    centre.y - c * 0.5 * w.length_m,
                ];
                let (line, points) = wake_centreline(&here, w, stern, [s, c]);
                (
                    stern[0].hypot(stern[1]),
                    [
                        [stern[0] as f32, stern[1] as f32, s as f32, c as f32],
                        [
                            w.speed_mps as f32,
                            w.length_m as f32,
                            w.beam_m as f32,
                            w.arm_half_angle_deg.to_radians() as f32,
                        ],
                        [
                            w.foam_generation as f32,
                            w.foam_e_folding_s as f32,
                            points as f32,
                            0.0,
                        ],
                    ],
                    line,
                )
            })
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(MAX_WAKES);
        uniform.thermal[1] = near.len() as f32;
        for ((slots, line_slots), (_, wake, line)) in uniform
            .wakes
            .chunks_exact_mut(3)
            .zip(uniform.wake_tracks.chunks_exact_mut(WAKE_POINTS))
            .zip(near)
        {
            slots.copy_from_slice(&wake);
            line_slots.copy_from_slice(&line);
        }
        for (slot, grid) in uniform.cascades.iter_mut().zip(cascades) {
            let frac = |x: f64| (x / grid.tile_m).rem_euclid(1.0) as f32;
            *slot = [
                frac(eye_x),
                frac(eye_y),
                grid.tile_m as f32,
                (grid.tile_m / f64::from(size)) as f32,
            ];
        }
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        RINGS * SEGMENTS * 6
    }

    /// The geoid's height above the ellipsoid here (the database's grid), metres.
    pub(crate) fn undulation_m(&self, lat_deg: f64, lon_deg: f64) -> f64 {
        self.geoid.undulation_m(lat_deg, lon_deg)
    }

    pub(crate) fn bind_group(&self) -> Option<&wgpu::BindGroup> {
        self.textures.as_ref().map(|t| &t.bind)
    }

    fn make_textures(
        &self,
        gpu: &Gpu,
        [globals, thermal]: [&wgpu::Buffer; 2],
        size: u32,
        layers: u32,
    ) -> SeaTextures {
        let mips = size.ilog2() + 1;
        let make = |label| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size,
                    height: size,
                    depth_or_array_layers: layers,
                },
                mip_level_count: mips,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        };
        let displacement = make("sea displacement");
        let slopes = make("sea slopes");
        let gradient = make("sea gradient");
        let view = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sea"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&view(&displacement)),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&view(&slopes)),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&view(&gradient)),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 9,
                    resource: thermal.as_entire_binding(),
                },
            ],
        });
        SeaTextures {
            size,
            layers,
            mips,
            displacement,
            slopes,
            gradient,
            bind,
        }
    }
}

impl MipScratch {
    /// Uploads one layer of `size` x `size` texels and its mip chain (2 x 2 box averages of
    /// the periodic grid) into `texture`.
    fn upload(
        &mut self,
        gpu: &Gpu,
        texture: &wgpu::Texture,
        layer: u32,
        size: u32,
        mips: u32,
        texels: &mut dyn Iterator<Item = [f32; 4]>,
    ) {
        self.chain.clear();
        self.chain.extend(texels);
        let (mut start, mut side) = (0usize, size as usize);
        for level in 0..mips {
            let Some(texels) = self.chain.get(start..start + side * side) else {
                return;
            };
            self.half.clear();
            self.half.extend(
                texels
                    .iter()
                    .map(|t| t.map(|v| half::f16::from_f32(v).to_bits())),
            );
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: level,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&self.half),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(side as u32 * 8),
                    rows_per_image: None,
                },
                wgpu::Extent3d {
                    width: side as u32,
                    height: side as u32,
                    depth_or_array_layers: 1,
                },
            );
            if side == 1 {
                break;
            }
            let next = side / 2;
            for i in 0..next * next {
                let (x, y) = (2 * (i % next), 2 * (i / next));
                let mut average = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = self.chain[start + (y + dy) * side + x + dx];
                    for (a, v) in average.iter_mut().zip(t) {
                        *a += 0.25 * v;
                    }
                }
                self.chain.push(average);
            }
            start += side * side;
            side = next;
        }
    }
}

/// A wake's turbulent centreline for the shader, relative to the eye (`here`): the stern now
/// (age 0), the stern's past places newer than where the foam is gone, then a straight end
/// along the last piece (or astern along the course, `course` its sine and cosine, when there
/// is no track) out to [`WAKE_END_E_FOLDINGS`] foam e-folding times. The points used.
fn wake_centreline(
    here: &cig_geo::EnuFrame,
    wake: &cig_scene::sea::WakeDraw,
    stern: [f64; 2],
    course: [f64; 2],
) -> (WakeLine, usize) {
    let mut points: Vec<([f64; 2], f64)> = vec![(stern, 0.0)];
    for &(place, age_s) in &wake.track {
        let at = here.geodetic_to_enu(place);
        let (last, last_age) = points[points.len() - 1];
        // Past places at the stern's own (the newest just taken) or not older add nothing.
        if age_s > last_age && (at.x - last[0]).hypot(at.y - last[1]) > 0.5 {
            points.push(([at.x, at.y], age_s));
        }
        if points.len() == WAKE_POINTS - 1 {
            break;
        }
    }
    let (last, last_age) = points[points.len() - 1];
    let direction = match points.len() {
        1 => [-course[0], -course[1]],
        n => {
            let (before, _) = points[n - 2];
            let d = [last[0] - before[0], last[1] - before[1]];
            let length = d[0].hypot(d[1]).max(1e-9);
            [d[0] / length, d[1] / length]
        }
    };
    let end_s = WAKE_END_E_FOLDINGS * wake.foam_e_folding_s;
    let reach_m = wake.speed_mps.max(0.5) * end_s;
    points.push((
        [
            last[0] + direction[0] * reach_m,
            last[1] + direction[1] * reach_m,
        ],
        last_age + end_s,
    ));
    // The turbulent wake is a beam wide at the stern and widens as s^(1/5) along it.
    let mut line: WakeLine = [[0.0; 4]; WAKE_POINTS];
    let mut along_m = 0.0;
    let mut previous = stern;
    for (slot, (at, age_s)) in line.iter_mut().zip(&points) {
        along_m += (at[0] - previous[0]).hypot(at[1] - previous[1]);
        previous = *at;
        let beam_m = wake.beam_m.max(0.1);
        let width_m = beam_m * (along_m / beam_m).max(1.0).powf(0.2);
        *slot = [at[0] as f32, at[1] as f32, *age_s as f32, width_m as f32];
    }
    (line, points.len())
}
