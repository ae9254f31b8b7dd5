//! Cloud layers: a deterministic, wind-advected density field shared by the renderer and the
//! CPU (shade, cover fraction, tests).
//!
//! Algorithm: each layer is a horizontal slab from `base_m` to `base_m + thickness_m` (metres
//! above mean sea level, the meteorological and CIGI convention; the renderer's copy in the
//! frame snapshot is re-based on the ellipsoid by the world). Over the slab lies a tileable
//! fractal value-noise field (five octaves of periodic value noise with smoothstep interpolation
//! on a `NOISE_SIZE`² grid, lattice values from a ChaCha8 generator seeded by the layer's
//! seed), rank-transformed so its values are uniform in [0, 1] and stored as 8-bit texels: the
//! renderer uploads exactly these texels, and both sides read them with the same bilinear
//! filter, so the GPU and the CPU see the same clouds. A point's noise coordinates are its
//! east/north metres from a world-fixed origin (equirectangular about [`CloudOrigin`]) minus
//! the wind's displacement `velocity * t`, divided by the kind's tile size: the pattern drifts
//! with the wind and is stable in the world (the NPS thesis's clouds never moved, source 000
//! chapter VII). The cover strength `w` is 0 where the uniform noise value `u < 1 - coverage`
//! and ramps to 1 over `EDGE`, so the covered area fraction is `coverage` (exact for the texel
//! values). Inside the slab the kind's vertical profile shapes it: heaped kinds (cumulus ...)
//! fill the slab from its base up to `sqrt(h)` of its thickness, `h = (u - (1 - coverage)) /
//! coverage` (domes, tallest where the noise peaks), sheet kinds (stratus ...) fill all of it
//! with soft top and bottom; the extinction coefficient is the kind's times `w`.
//! Optical depth along a segment is integrated numerically (midpoint rule, steps under half a
//! texel and a sixteenth of the slab), the sun's transmittance to a ground point is
//! `exp(-optical depth along the sun ray)`, and the sky's cloud cover for the natural
//! illuminance combines layers as independent: `1 - prod(1 - coverage)`.
//!
//! Sources: value noise and fractal sums (Perlin 1985; Ebert et al., "Texturing and Modeling",
//! 3rd ed., chapter 2); extinction in cloud from the visibility inside it (Koschmieder, e.g.
//! 30-100 m in cumulus, 1-2 km in cirrus: WMO International Cloud Atlas descriptions); layer
//! cloud types as CIGI 3.3 ICD Weather Control's Cloud Type table.
//!
//! Limits: the field is two-dimensional (a column's cover strength is one value; no
//! overhangs or turrets), the tile repeats every `tile_m` of the kind (8-40 km), the CPU model
//! is flat (no earth curvature; the renderer adds it), and the equirectangular plane stretches
//! east-west by `cos(origin latitude) / cos(latitude)` far from the origin. Kinds differ only
//! in scale, extinction and profile; the shapes are statistical, not cloud physics.

use crate::EnvironmentError;
use glam::DVec3;
use rand::{Rng, SeedableRng};

/// Side of the square, tileable noise texture, texels.
pub const NOISE_SIZE: usize = 256;
/// Width of the cover strength's ramp in noise value (soft cloud edges).
pub const EDGE: f64 = 0.1;
/// Most cloud layers a frame draws (CIGI has three; one spare).
pub const MAX_CLOUD_LAYERS: usize = 4;
/// Lowest and highest layer base, metres above MSL.
pub const BASE_RANGE_M: (f64, f64) = (-500.0, 25_000.0);
/// Thickest layer, metres.
pub const MAX_THICKNESS_M: f64 = 15_000.0;
/// Fastest wind a layer drifts in, m/s.
pub const MAX_WIND_SPEED_MPS: f64 = 150.0;
/// Mean earth radius of the equirectangular plane, metres.
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// How a kind fills its slab vertically.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CloudShape {
    /// Heaped: from the base up to `w^0.5` of the thickness (cumuliform).
    Heap,
    /// A sheet filling the whole slab, soft at top and bottom (stratiform).
    Sheet,
}

/// Cloud type, in the order of CIGI's Weather Control Cloud Type field (1-10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CloudKind {
    Altocumulus,
    Altostratus,
    Cirrocumulus,
    Cirrostratus,
    Cirrus,
    Cumulonimbus,
    #[default]
    Cumulus,
    Nimbostratus,
    Stratocumulus,
    Stratus,
}

/// Per-kind parameters of the field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KindParams {
    /// Extinction coefficient where the cover strength is 1, 1/m (3.912 / visibility inside).
    pub extinction_per_m: f64,
    pub shape: CloudShape,
    /// Size of one noise tile on the ground, metres (cell size is `tile_m / NOISE_SIZE`).
    pub tile_m: f64,
}

impl CloudKind {
    /// Every kind, in CIGI order.
    pub const ALL: [CloudKind; 10] = [
        CloudKind::Altocumulus,
        CloudKind::Altostratus,
        CloudKind::Cirrocumulus,
        CloudKind::Cirrostratus,
        CloudKind::Cirrus,
        CloudKind::Cumulonimbus,
        CloudKind::Cumulus,
        CloudKind::Nimbostratus,
        CloudKind::Stratocumulus,
        CloudKind::Stratus,
    ];

    /// The field's parameters of this kind.
    pub fn params(self) -> KindParams {
        use CloudShape::{Heap, Sheet};
        let (visibility_m, shape, tile_m) = match self {
            CloudKind::Cumulus => (60.0, Heap, 8_000.0),
            CloudKind::Cumulonimbus => (40.0, Heap, 24_000.0),
            CloudKind::Stratocumulus => (90.0, Heap, 6_000.0),
            CloudKind::Altocumulus => (120.0, Heap, 4_000.0),
            CloudKind::Cirrocumulus => (1_200.0, Heap, 3_000.0),
            CloudKind::Stratus => (120.0, Sheet, 30_000.0),
            CloudKind::Nimbostratus => (70.0, Sheet, 40_000.0),
            CloudKind::Altostratus => (400.0, Sheet, 30_000.0),
            CloudKind::Cirrostratus => (3_000.0, Sheet, 40_000.0),
            CloudKind::Cirrus => (2_000.0, Sheet, 20_000.0),
        };
        KindParams {
            extinction_per_m: 3.912 / visibility_m,
            shape,
            tile_m,
        }
    }

    /// The kind of CIGI's Cloud Type value: `None` for 0 (none); 11-15 (IG defined) are drawn
    /// as cumulus.
    pub fn from_cigi(cloud_type: u8) -> Option<CloudKind> {
        match cloud_type {
            0 => None,
            n @ 1..=10 => CloudKind::ALL.get(usize::from(n - 1)).copied(),
            _ => Some(CloudKind::Cumulus),
        }
    }

    /// The kind's name as the scenario file and the command line write it.
    pub fn name(self) -> &'static str {
        match self {
            CloudKind::Altocumulus => "altocumulus",
            CloudKind::Altostratus => "altostratus",
            CloudKind::Cirrocumulus => "cirrocumulus",
            CloudKind::Cirrostratus => "cirrostratus",
            CloudKind::Cirrus => "cirrus",
            CloudKind::Cumulonimbus => "cumulonimbus",
            CloudKind::Cumulus => "cumulus",
            CloudKind::Nimbostratus => "nimbostratus",
            CloudKind::Stratocumulus => "stratocumulus",
            CloudKind::Stratus => "stratus",
        }
    }

    /// Parses a kind's name (case-insensitive).
    pub fn from_name(name: &str) -> Option<CloudKind> {
        let lower = name.trim().to_ascii_lowercase();
        CloudKind::ALL.into_iter().find(|k| k.name() == lower)
    }
}

/// One cloud layer.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CloudLayer {
    /// Height of the base, metres above mean sea level (in `FrameSnapshot::cloud_layers`:
    /// above the WGS84 ellipsoid).
    pub base_m: f64,
    /// Thickness, metres (> 0).
    pub thickness_m: f64,
    /// Covered fraction of the sky, 0..=1.
    pub coverage: f64,
    pub kind: CloudKind,
    /// Wind speed at the layer, m/s.
    pub wind_speed_mps: f64,
    /// Direction the wind blows from, degrees from true north through east.
    pub wind_from_deg: f64,
    /// Seed of the layer's noise.
    pub seed: u64,
    /// How far the pattern had drifted when the wind last changed (none: it has drifted at
    /// this wind since the epoch of Unix time).
    #[serde(default)]
    pub drift: CloudDrift,
}

/// The pattern's drift at an instant: the displacement is `offset_m + velocity (t - epoch)`,
/// so a change of the wind turns the drift at that instant instead of moving the whole
/// pattern by the new velocity times all the time since 1970.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CloudDrift {
    /// When the wind last changed, seconds since 1970 UTC.
    pub epoch_unix_s: f64,
    /// Displacement (east, north) of the pattern at the epoch, metres.
    pub offset_m: [f64; 2],
}

fn invalid(text: String) -> EnvironmentError {
    EnvironmentError::InvalidSetting(text)
}

impl CloudLayer {
    /// A layer with no wind and seed 1.
    pub fn new(base_m: f64, thickness_m: f64, coverage: f64, kind: CloudKind) -> CloudLayer {
        CloudLayer {
            base_m,
            thickness_m,
            coverage,
            kind,
            wind_speed_mps: 0.0,
            wind_from_deg: 0.0,
            seed: 1,
            drift: CloudDrift::default(),
        }
    }

    /// Checks every value.
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidSetting`] naming the first value out of range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        let (lo, hi) = BASE_RANGE_M;
        if !(self.base_m.is_finite() && (lo..=hi).contains(&self.base_m)) {
            return Err(invalid(format!(
                "cloud base {} m is outside [{lo}, {hi}] m",
                self.base_m
            )));
        }
        if !(self.thickness_m.is_finite()
            && self.thickness_m > 0.0
            && self.thickness_m <= MAX_THICKNESS_M)
        {
            return Err(invalid(format!(
                "cloud thickness {} m is outside (0, {MAX_THICKNESS_M}] m",
                self.thickness_m
            )));
        }
        if !(self.coverage.is_finite() && (0.0..=1.0).contains(&self.coverage)) {
            return Err(invalid(format!(
                "cloud coverage {} is outside [0, 1]",
                self.coverage
            )));
        }
        if !(self.wind_speed_mps.is_finite()
            && (0.0..=MAX_WIND_SPEED_MPS).contains(&self.wind_speed_mps))
        {
            return Err(invalid(format!(
                "cloud wind speed {} m/s is outside [0, {MAX_WIND_SPEED_MPS}] m/s",
                self.wind_speed_mps
            )));
        }
        if !self.wind_from_deg.is_finite() {
            return Err(invalid(format!(
                "cloud wind direction {} is not a number of degrees",
                self.wind_from_deg
            )));
        }
        Ok(())
    }

    /// The layer with every value brought into range (values from the network), and a
    /// description of each change (empty when it was valid). Non-finite values become the
    /// nearest sensible default (base 1000 m, thickness 500 m, no cover, no wind).
    pub fn clamped(&self) -> (CloudLayer, Vec<String>) {
        let mut notes = Vec::new();
        let mut fix = |name: &str, value: f64, lo: f64, hi: f64, default: f64| -> f64 {
            let fixed = if value.is_finite() {
                value.clamp(lo, hi)
            } else {
                default
            };
            if fixed != value {
                notes.push(format!("cloud {name} {value} clamped to {fixed}"));
            }
            fixed
        };
        let (lo, hi) = BASE_RANGE_M;
        let layer = CloudLayer {
            base_m: fix("base (m)", self.base_m, lo, hi, 1000.0),
            thickness_m: fix(
                "thickness (m)",
                self.thickness_m,
                1.0,
                MAX_THICKNESS_M,
                500.0,
            ),
            coverage: fix("coverage", self.coverage, 0.0, 1.0, 0.0),
            wind_speed_mps: fix(
                "wind speed (m/s)",
                self.wind_speed_mps,
                0.0,
                MAX_WIND_SPEED_MPS,
                0.0,
            ),
            wind_from_deg: if self.wind_from_deg.is_finite() {
                self.wind_from_deg.rem_euclid(360.0)
            } else {
                notes.push(format!(
                    "cloud wind direction {} clamped to 0",
                    self.wind_from_deg
                ));
                0.0
            },
            ..*self
        };
        (layer, notes)
    }

    /// Top of the layer, metres (same reference as the base).
    pub fn top_m(&self) -> f64 {
        self.base_m + self.thickness_m
    }

    /// The wind's velocity at the layer, (east, north) m/s (it blows toward `from + 180`).
    pub fn wind_velocity_mps(&self) -> (f64, f64) {
        let (s, c) = self.wind_from_deg.to_radians().sin_cos();
        (-self.wind_speed_mps * s, -self.wind_speed_mps * c)
    }

    /// Noise-texture coordinates (texels, in `[0, NOISE_SIZE)`) of a point `east_m`, `north_m`
    /// of the plane at time `t_s`: the position minus the wind's displacement, over the
    /// kind's tile. Computed in f64 so large times and distances keep their precision.
    pub fn noise_coords(&self, east_m: f64, north_m: f64, t_s: f64) -> (f64, f64) {
        let (de, dn) = self.displacement_m(t_s);
        let per_m = NOISE_SIZE as f64 / self.kind.params().tile_m;
        let size = NOISE_SIZE as f64;
        (
            ((east_m - de) * per_m).rem_euclid(size),
            ((north_m - dn) * per_m).rem_euclid(size),
        )
    }

    /// The pattern's displacement (east, north) at time `t_s`, metres.
    pub fn displacement_m(&self, t_s: f64) -> (f64, f64) {
        let (ve, vn) = self.wind_velocity_mps();
        let dt = t_s - self.drift.epoch_unix_s;
        (
            self.drift.offset_m[0] + ve * dt,
            self.drift.offset_m[1] + vn * dt,
        )
    }

    /// This layer following `previous` (the same layer a frame earlier) at time `t_s`: the
    /// drift carries on from where `previous` had taken the pattern, so a change of the wind
    /// turns the drift without a jump.
    pub fn continuing(self, previous: &CloudLayer, t_s: f64) -> CloudLayer {
        let drift = if previous.wind_velocity_mps() == self.wind_velocity_mps() {
            previous.drift
        } else {
            let (e, n) = previous.displacement_m(t_s);
            CloudDrift {
                epoch_unix_s: t_s,
                offset_m: [e, n],
            }
        };
        CloudLayer { drift, ..self }
    }

    /// Density profile over the slab: the extinction coefficient, 1/m, for the noise value
    /// `u` at `zn` (0 at the base, 1 at the top): the cover strength `w` times the kind's
    /// extinction where the profile fills the slab. A heaped kind's column rises to
    /// `sqrt(h)` of the slab, `h` the noise value's height above the cover threshold over the
    /// coverage (domes, highest where the noise is); a sheet fills the slab, soft at its top
    /// and bottom.
    pub fn profile_per_m(&self, u: f64, zn: f64) -> f64 {
        let w = cover_strength(u, self.coverage);
        if !(0.0..=1.0).contains(&zn) || w <= 0.0 {
            return 0.0;
        }
        let params = self.kind.params();
        let fill = match params.shape {
            CloudShape::Heap => {
                ((heap_height(u, self.coverage).sqrt() - zn) * 10.0).clamp(0.0, 1.0)
            }
            CloudShape::Sheet => (zn.min(1.0 - zn) * 10.0).clamp(0.0, 1.0),
        };
        params.extinction_per_m * w * fill
    }
}

/// Height strength of a heaped column (0..1): how far the noise value lies above the cover
/// threshold, over the coverage.
pub fn heap_height(u: f64, coverage: f64) -> f64 {
    ((u - (1.0 - coverage)) / coverage.max(1e-6)).clamp(0.0, 1.0)
}

/// Cover strength for a uniform noise value `u` and a coverage: 0 where `u < 1 - coverage`,
/// rising to 1 over [`EDGE`] (narrower near full cover, so an overcast has no holes).
pub fn cover_strength(u: f64, coverage: f64) -> f64 {
    let threshold = 1.0 - coverage;
    let width = EDGE.min(threshold);
    if width <= 1e-9 {
        return if u >= threshold { 1.0 } else { 0.0 };
    }
    ((u - threshold) / width).clamp(0.0, 1.0)
}

/// Fraction of the sky covered by the layers (as independent): `1 - prod(1 - coverage)`; the
/// natural illuminance's sky-condition input.
pub fn cloud_cover_fraction(layers: &[CloudLayer]) -> f64 {
    let clear: f64 = layers
        .iter()
        .map(|l| 1.0 - l.coverage.clamp(0.0, 1.0))
        .product();
    (1.0 - clear).clamp(0.0, 1.0)
}

/// The world-fixed origin of the clouds' horizontal plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CloudOrigin {
    pub lat_deg: f64,
    pub lon_deg: f64,
}

impl CloudOrigin {
    /// Equirectangular (east, north) metres of a latitude and longitude from the origin.
    pub fn plane_m(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let dlon = (lon_deg - self.lon_deg + 180.0).rem_euclid(360.0) - 180.0;
        let east = dlon.to_radians() * EARTH_RADIUS_M * self.lat_deg.to_radians().cos();
        let north = (lat_deg - self.lat_deg).to_radians() * EARTH_RADIUS_M;
        (east, north)
    }

    /// How many plane metres east one true metre east is at a latitude (the equirectangular
    /// stretch, `cos(origin latitude) / cos(latitude)`).
    pub fn east_stretch(&self, lat_deg: f64) -> f64 {
        self.lat_deg.to_radians().cos() / lat_deg.to_radians().cos().max(1e-3)
    }
}

/// A layer's tileable noise: `NOISE_SIZE`² texels of uniformly distributed 8-bit values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CloudNoise {
    seed: u64,
    texels: Vec<u8>,
}

fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

impl CloudNoise {
    /// The noise of a seed (deterministic on every machine: integer lattice from ChaCha8,
    /// f32 sums, an integer rank transform).
    pub fn new(seed: u64) -> CloudNoise {
        let n = NOISE_SIZE;
        let mut sum = vec![0f32; n * n];
        let mut amplitude = 1.0f32;
        // Lattice periods 4, 8, 16, 32, 64 across the tile.
        for octave in 0..5u32 {
            let period = 4usize << octave;
            let cell = n / period;
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(u64::from(octave)),
            );
            let lattice: Vec<f32> = (0..period * period)
                .map(|_| f32::from(rng.gen::<u16>()) / 65535.0)
                .collect();
            let at = |i: usize, j: usize| -> f32 {
                lattice
                    .get((j % period) * period + (i % period))
                    .copied()
                    .unwrap_or(0.0)
            };
            for y in 0..n {
                let (j, fy) = (y / cell, smooth((y % cell) as f32 / cell as f32));
                for x in 0..n {
                    let (i, fx) = (x / cell, smooth((x % cell) as f32 / cell as f32));
                    let a = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
                    let b = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
                    if let Some(s) = sum.get_mut(y * n + x) {
                        *s += amplitude * (a + (b - a) * fy);
                    }
                }
            }
            amplitude *= 0.5;
        }
        // Rank transform: the k-th smallest of N values becomes floor(256 k / N).
        let mut order: Vec<usize> = (0..n * n).collect();
        order.sort_by(|&a, &b| {
            let va = sum.get(a).copied().unwrap_or(0.0);
            let vb = sum.get(b).copied().unwrap_or(0.0);
            va.total_cmp(&vb).then(a.cmp(&b))
        });
        let mut texels = vec![0u8; n * n];
        for (rank, index) in order.into_iter().enumerate() {
            if let Some(t) = texels.get_mut(index) {
                *t = (rank * 256 / (n * n)) as u8;
            }
        }
        CloudNoise { seed, texels }
    }

    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The texels, row by row (row = north coordinate, column = east), for upload.
    pub fn texels(&self) -> &[u8] {
        &self.texels
    }

    fn texel(&self, x: i64, y: i64) -> f64 {
        let n = NOISE_SIZE as i64;
        let index = (y.rem_euclid(n) * n + x.rem_euclid(n)) as usize;
        f64::from(self.texels.get(index).copied().unwrap_or(0)) / 255.0
    }

    /// The noise at texel coordinates (`x` east, `y` north), bilinear with wrap-around as a
    /// GPU's linear sampler with repeat addressing reads it: value in [0, 1].
    pub fn sample(&self, x: f64, y: f64) -> f64 {
        let (px, py) = (x - 0.5, y - 0.5);
        let (x0, y0) = (px.floor(), py.floor());
        let (fx, fy) = (px - x0, py - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let a = self.texel(i, j) * (1.0 - fx) + self.texel(i + 1, j) * fx;
        let b = self.texel(i, j + 1) * (1.0 - fx) + self.texel(i + 1, j + 1) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// Cloud layers with their noise, on a plane of east/north metres around a fixed origin
/// (heights in the layers' reference, flat).
#[derive(Clone, Debug)]
pub struct CloudField {
    layers: Vec<(CloudLayer, CloudNoise)>,
}

/// A point of the clouds' plane: metres east and north of the origin, height in the layers'
/// reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanePoint {
    pub east_m: f64,
    pub north_m: f64,
    pub height_m: f64,
}

impl PlanePoint {
    pub fn new(east_m: f64, north_m: f64, height_m: f64) -> PlanePoint {
        PlanePoint {
            east_m,
            north_m,
            height_m,
        }
    }

    fn as_vec(self) -> DVec3 {
        DVec3::new(self.east_m, self.north_m, self.height_m)
    }

    fn from_vec(v: DVec3) -> PlanePoint {
        PlanePoint::new(v.x, v.y, v.z)
    }
}

impl CloudField {
    /// Validates the layers (at most [`MAX_CLOUD_LAYERS`]) and makes their noise.
    ///
    /// # Errors
    /// [`EnvironmentError::InvalidSetting`] for a bad layer or too many.
    pub fn new(layers: &[CloudLayer]) -> Result<CloudField, EnvironmentError> {
        if layers.len() > MAX_CLOUD_LAYERS {
            return Err(invalid(format!(
                "{} cloud layers; at most {MAX_CLOUD_LAYERS}",
                layers.len()
            )));
        }
        let mut out = Vec::with_capacity(layers.len());
        for (i, layer) in layers.iter().enumerate() {
            layer
                .validate()
                .map_err(|e| invalid(format!("cloud layer {}: {e}", i + 1)))?;
            out.push((*layer, CloudNoise::new(layer.seed)));
        }
        Ok(CloudField { layers: out })
    }

    pub fn layers(&self) -> impl Iterator<Item = &CloudLayer> {
        self.layers.iter().map(|(l, _)| l)
    }

    /// The uniform noise value (0..1) of layer `index` over a plane point at a time; 0 for no
    /// layer.
    pub fn noise_at(&self, index: usize, east_m: f64, north_m: f64, t_s: f64) -> f64 {
        let Some((layer, noise)) = self.layers.get(index) else {
            return 0.0;
        };
        let (x, y) = layer.noise_coords(east_m, north_m, t_s);
        noise.sample(x, y)
    }

    /// Cover strength (0..1) of layer `index` over a plane point at a time; 0 for no layer.
    pub fn cover_at(&self, index: usize, east_m: f64, north_m: f64, t_s: f64) -> f64 {
        self.layers.get(index).map_or(0.0, |(layer, _)| {
            cover_strength(self.noise_at(index, east_m, north_m, t_s), layer.coverage)
        })
    }

    /// Extinction coefficient of all layers at a point and time, 1/m.
    pub fn density_at(&self, p: PlanePoint, t_s: f64) -> f64 {
        let mut sum = 0.0;
        for (i, (layer, _)) in self.layers.iter().enumerate() {
            let zn = (p.height_m - layer.base_m) / layer.thickness_m;
            if !(0.0..=1.0).contains(&zn) {
                continue;
            }
            let u = self.noise_at(i, p.east_m, p.north_m, t_s);
            sum += layer.profile_per_m(u, zn);
        }
        sum
    }

    /// Optical depth of the clouds along the straight segment from `a` to `b` at time `t_s`
    /// (midpoint rule inside each layer's slab; zero outside every slab).
    pub fn optical_depth_along(&self, a: PlanePoint, b: PlanePoint, t_s: f64) -> f64 {
        let (va, vb) = (a.as_vec(), b.as_vec());
        let d = vb - va;
        let length = d.length();
        if !(length.is_finite() && length > 0.0) {
            return 0.0;
        }
        let mut tau = 0.0;
        for (i, (layer, _)) in self.layers.iter().enumerate() {
            // Part of the segment (0..1) inside the slab.
            let (lo, hi) = if d.z.abs() < 1e-12 {
                if va.z >= layer.base_m && va.z <= layer.top_m() {
                    (0.0, 1.0)
                } else {
                    continue;
                }
            } else {
                let s0 = (layer.base_m - va.z) / d.z;
                let s1 = (layer.top_m() - va.z) / d.z;
                (s0.min(s1).max(0.0), s0.max(s1).min(1.0))
            };
            if hi <= lo {
                continue;
            }
            let texel_m = layer.kind.params().tile_m / NOISE_SIZE as f64;
            let step_m = (texel_m * 0.5).min(layer.thickness_m / 16.0).max(0.5);
            let inside_m = (hi - lo) * length;
            let steps = ((inside_m / step_m).ceil() as usize).clamp(1, 8192);
            let ds = (hi - lo) / steps as f64;
            for k in 0..steps {
                let p = va + d * (lo + (k as f64 + 0.5) * ds);
                let zn = ((p.z - layer.base_m) / layer.thickness_m).clamp(0.0, 1.0);
                let u = self.noise_at(i, p.x, p.y, t_s);
                tau += layer.profile_per_m(u, zn) * ds * length;
            }
        }
        tau
    }

    /// Transmittance of the sun's direct light to a point through the layers:
    /// `exp(-optical depth)` along the ray toward `sun_direction` (east, north, up; any
    /// length) up to the top of the highest layer; 0 with the sun below the horizon.
    pub fn shade_factor(&self, ground: PlanePoint, sun_direction: DVec3, t_s: f64) -> f64 {
        let dir = sun_direction.normalize_or_zero();
        if dir.z <= 1e-6 {
            return 0.0;
        }
        let top = self
            .layers()
            .map(CloudLayer::top_m)
            .fold(f64::MIN, f64::max);
        if top <= ground.height_m {
            return 1.0;
        }
        let end = ground.as_vec() + dir * ((top - ground.height_m) / dir.z + 1.0);
        (-self.optical_depth_along(ground, PlanePoint::from_vec(end), t_s)).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn covered_fraction(field: &CloudField, t_s: f64) -> f64 {
        // Sample a 2-tile square on a grid incommensurate with the texels.
        let tile = field.layers[0].0.kind.params().tile_m;
        let n = 300;
        let mut covered = 0;
        for j in 0..n {
            for i in 0..n {
                let e = (i as f64 + 0.37) / n as f64 * 2.0 * tile;
                let no = (j as f64 + 0.61) / n as f64 * 2.0 * tile;
                if field.cover_at(0, e, no, t_s) > 0.0 {
                    covered += 1;
                }
            }
        }
        covered as f64 / (n * n) as f64
    }

    #[test]
    fn a_change_of_wind_turns_the_drift_without_a_jump() {
        let before = CloudLayer {
            wind_speed_mps: 10.0,
            wind_from_deg: 270.0,
            ..CloudLayer::new(1500.0, 500.0, 0.5, CloudKind::Cumulus)
        };
        let t0 = 1.8e9;
        let after = CloudLayer {
            wind_speed_mps: 10.5,
            wind_from_deg: 280.0,
            ..before
        }
        .continuing(&before, t0);
        // At the change the pattern is where it was; a minute later it has moved by the new
        // wind's minute only.
        assert_eq!(after.displacement_m(t0), before.displacement_m(t0));
        let (e0, n0) = after.displacement_m(t0);
        let (e1, n1) = after.displacement_m(t0 + 60.0);
        let (ve, vn) = after.wind_velocity_mps();
        assert!((e1 - e0 - 60.0 * ve).abs() < 1e-3 && (n1 - n0 - 60.0 * vn).abs() < 1e-3);
        // Without the continuation, the new wind times all the time since 1970 moves it by
        // thousands of kilometres.
        let jump = {
            let fresh = CloudLayer {
                drift: CloudDrift::default(),
                ..after
            };
            let (e, n) = fresh.displacement_m(t0);
            ((e - e0).powi(2) + (n - n0).powi(2)).sqrt()
        };
        assert!(jump > 1.0e6, "{jump}");
        // The next frame's layer (as the host or scenario states it, with no drift) at the
        // same wind keeps the drift it had.
        let next = CloudLayer {
            drift: CloudDrift::default(),
            ..after
        }
        .continuing(&after, t0 + 5.0);
        assert_eq!(next.drift, after.drift);
    }

    #[test]
    fn covered_area_matches_the_coverage() {
        for coverage in [0.1, 0.3, 0.5, 0.8] {
            let field =
                CloudField::new(&[CloudLayer::new(1000.0, 500.0, coverage, CloudKind::Cumulus)])
                    .unwrap();
            let f = covered_fraction(&field, 0.0);
            assert!(
                (f - coverage).abs() < 0.03,
                "coverage {coverage}: covered {f}"
            );
        }
        let overcast =
            CloudField::new(&[CloudLayer::new(1000.0, 500.0, 1.0, CloudKind::Stratus)]).unwrap();
        assert_eq!(covered_fraction(&overcast, 0.0), 1.0);
        let clear =
            CloudField::new(&[CloudLayer::new(1000.0, 500.0, 0.0, CloudKind::Stratus)]).unwrap();
        assert_eq!(covered_fraction(&clear, 0.0), 0.0);
    }

    #[test]
    fn noise_is_uniform_deterministic_and_seeded() {
        let a = CloudNoise::new(7);
        assert_eq!(a, CloudNoise::new(7));
        assert_ne!(a.texels(), CloudNoise::new(8).texels());
        let mut histogram = [0usize; 256];
        for &t in a.texels() {
            histogram[usize::from(t)] += 1;
        }
        assert!(histogram
            .iter()
            .all(|&h| h == NOISE_SIZE * NOISE_SIZE / 256));
        // The texel grid is a smooth field: neighbours are close on average.
        let n = NOISE_SIZE;
        let mean_step: f64 = (0..n * n - 1)
            .map(|i| (f64::from(a.texels()[i]) - f64::from(a.texels()[i + 1])).abs())
            .sum::<f64>()
            / (n * n) as f64;
        assert!(mean_step < 40.0, "mean neighbour step {mean_step}");
    }

    #[test]
    fn sampling_wraps_around_the_tile() {
        let noise = CloudNoise::new(3);
        let s = NOISE_SIZE as f64;
        for (x, y) in [(0.2, 0.9), (17.5, 200.25), (255.9, 0.1)] {
            assert!((noise.sample(x, y) - noise.sample(x + s, y - s)).abs() < 1e-12);
        }
        // At a texel centre the sample is the texel.
        assert_eq!(
            noise.sample(10.5, 20.5),
            f64::from(noise.texels()[20 * 256 + 10]) / 255.0
        );
    }

    fn windy(kind: CloudKind, speed: f64, from: f64) -> CloudLayer {
        CloudLayer {
            wind_speed_mps: speed,
            wind_from_deg: from,
            seed: 11,
            ..CloudLayer::new(1500.0, 800.0, 0.5, kind)
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn the_field_drifts_with_the_wind(
            speed in 0.0f64..60.0, from in 0.0f64..360.0,
            e in -20_000.0f64..20_000.0, n in -20_000.0f64..20_000.0,
            t in 0.0f64..2.0e9, dt in 0.0f64..600.0, h in 1500.0f64..2300.0,
        ) {
            let layer = windy(CloudKind::Cumulus, speed, from);
            let field = CloudField::new(&[layer]).unwrap();
            let (ve, vn) = layer.wind_velocity_mps();
            let before = field.density_at(PlanePoint::new(e, n, h), t);
            let after = field.density_at(PlanePoint::new(e + ve * dt, n + vn * dt, h), t + dt);
            prop_assert!((before - after).abs() < 1e-6 * layer.kind.params().extinction_per_m,
                "{before} vs {after}");
        }
    }

    #[test]
    fn the_wind_blows_from_its_direction() {
        let (ve, vn) = windy(CloudKind::Cumulus, 10.0, 270.0).wind_velocity_mps();
        assert!(
            (ve - 10.0).abs() < 1e-9 && vn.abs() < 1e-9,
            "west wind blows east"
        );
        let (ve, vn) = windy(CloudKind::Cumulus, 10.0, 0.0).wind_velocity_mps();
        assert!(
            ve.abs() < 1e-9 && (vn + 10.0).abs() < 1e-9,
            "north wind blows south"
        );
    }

    #[test]
    fn optical_depth_is_zero_outside_the_slab_and_positive_through_cloud() {
        let layer = CloudLayer::new(2000.0, 1000.0, 1.0, CloudKind::Stratus);
        let field = CloudField::new(&[layer]).unwrap();
        let below = field.optical_depth_along(
            PlanePoint::new(0.0, 0.0, 100.0),
            PlanePoint::new(5000.0, 300.0, 1999.0),
            0.0,
        );
        let above = field.optical_depth_along(
            PlanePoint::new(0.0, 0.0, 3001.0),
            PlanePoint::new(-4000.0, 0.0, 9000.0),
            0.0,
        );
        assert_eq!((below, above), (0.0, 0.0));
        let through = field.optical_depth_along(
            PlanePoint::new(0.0, 0.0, 0.0),
            PlanePoint::new(0.0, 0.0, 4000.0),
            0.0,
        );
        // A full sheet: extinction times 0.9 of the thickness.
        let expected = layer.kind.params().extinction_per_m * 0.9 * 1000.0;
        assert!(
            (through / expected - 1.0).abs() < 0.02,
            "{through} vs {expected}"
        );
    }

    #[test]
    fn shade_is_deeper_under_a_cloud_than_in_a_gap() {
        let layer = CloudLayer {
            seed: 5,
            ..CloudLayer::new(1000.0, 600.0, 0.5, CloudKind::Cumulus)
        };
        let field = CloudField::new(&[layer]).unwrap();
        let sun = DVec3::new(0.3, 0.2, 1.0);
        // Find a point under the middle of a cloud and one under a gap.
        let mut shaded = None;
        let mut lit = None;
        for k in 0..4000 {
            let p = PlanePoint::new(k as f64 * 37.0, (k % 61) as f64 * 53.0, 0.0);
            let s = field.shade_factor(p, sun, 0.0);
            if s < 0.01 && shaded.is_none() {
                shaded = Some(s);
            }
            if s > 0.999 && lit.is_none() {
                lit = Some(s);
            }
        }
        assert!(shaded.is_some() && lit.is_some(), "{shaded:?} {lit:?}");
        let clear = CloudField::new(&[]).unwrap();
        assert_eq!(
            clear.shade_factor(PlanePoint::new(0.0, 0.0, 0.0), sun, 0.0),
            1.0
        );
        assert_eq!(
            field.shade_factor(PlanePoint::new(0.0, 0.0, 0.0), -sun, 0.0),
            0.0,
            "sun below the horizon"
        );
    }

    #[test]
    fn cover_fraction_combines_layers_as_independent() {
        assert_eq!(cloud_cover_fraction(&[]), 0.0);
        let a = CloudLayer::new(1000.0, 500.0, 0.5, CloudKind::Cumulus);
        let b = CloudLayer::new(6000.0, 500.0, 0.5, CloudKind::Altostratus);
        assert!((cloud_cover_fraction(&[a, b]) - 0.75).abs() < 1e-12);
        let overcast = CloudLayer { coverage: 1.0, ..a };
        assert_eq!(cloud_cover_fraction(&[overcast, b]), 1.0);
    }

    #[test]
    fn bad_values_are_refused_with_the_value_named() {
        let good = CloudLayer::new(1000.0, 500.0, 0.5, CloudKind::Cumulus);
        assert!(good.validate().is_ok());
        let cases = [
            (
                CloudLayer {
                    base_m: f64::NAN,
                    ..good
                },
                "base",
            ),
            (
                CloudLayer {
                    base_m: 40_000.0,
                    ..good
                },
                "base",
            ),
            (
                CloudLayer {
                    thickness_m: 0.0,
                    ..good
                },
                "thickness",
            ),
            (
                CloudLayer {
                    coverage: 1.5,
                    ..good
                },
                "coverage",
            ),
            (
                CloudLayer {
                    coverage: -0.1,
                    ..good
                },
                "coverage",
            ),
            (
                CloudLayer {
                    wind_speed_mps: -1.0,
                    ..good
                },
                "wind speed",
            ),
            (
                CloudLayer {
                    wind_from_deg: f64::INFINITY,
                    ..good
                },
                "wind direction",
            ),
        ];
        for (layer, word) in cases {
            let e = layer.validate().unwrap_err().to_string();
            assert!(e.contains(word) && !e.contains('\n'), "{e}");
            let (fixed, notes) = layer.clamped();
            assert!(fixed.validate().is_ok(), "{fixed:?}");
            assert!(!notes.is_empty());
        }
        assert!(good.clamped().1.is_empty());
        assert!(CloudField::new(&[good; 5]).is_err());
        let e = CloudField::new(&[
            good,
            CloudLayer {
                coverage: 2.0,
                ..good
            },
        ])
        .unwrap_err();
        assert!(e.to_string().contains("cloud layer 2"), "{e}");
    }

    #[test]
    fn cigi_cloud_types_and_names() {
        assert_eq!(CloudKind::from_cigi(0), None);
        assert_eq!(CloudKind::from_cigi(1), Some(CloudKind::Altocumulus));
        assert_eq!(CloudKind::from_cigi(7), Some(CloudKind::Cumulus));
        assert_eq!(CloudKind::from_cigi(10), Some(CloudKind::Stratus));
        assert_eq!(CloudKind::from_cigi(15), Some(CloudKind::Cumulus));
        for k in CloudKind::ALL {
            assert_eq!(CloudKind::from_name(k.name()), Some(k));
        }
        assert_eq!(CloudKind::from_name(" Stratus "), Some(CloudKind::Stratus));
        assert_eq!(CloudKind::from_name("fog"), None);
    }

    #[test]
    fn origin_plane_is_metres_from_the_origin() {
        let o = CloudOrigin {
            lat_deg: 51.0,
            lon_deg: -1.0,
        };
        let (e, n) = o.plane_m(51.01, -1.0);
        assert!(e.abs() < 1e-9 && (n - 1111.95).abs() < 0.1, "{e} {n}");
        let (e, _) = o.plane_m(51.0, -0.99);
        assert!((e - 1111.95 * 51f64.to_radians().cos()).abs() < 0.1, "{e}");
        let across = CloudOrigin {
            lat_deg: 0.0,
            lon_deg: 179.9,
        };
        assert!(
            across.plane_m(0.0, -179.9).0 > 0.0,
            "wraps across the antimeridian"
        );
    }
}
