//! Streaming reader of orthoimagery GeoTIFFs: the header, georeference and colour layout read
//! once, the pixels decoded chunk row by chunk row (a strip, or a row of tiles) into a small
//! cache of RGBA8 rows, so an image far larger than memory is read through a window.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use cig_geo::utm::{geodetic_to_utm, utm_to_geodetic};
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::{ColorType, TiffError};

use super::ImageryError;
use crate::import::geotiff::{describe, has_tiff_magic, read_georeference, Crs, Georeference};

/// Most bytes one decoded chunk row (a strip, or a row of tiles, as RGBA8) may take.
pub const MAX_CHUNK_ROW_BYTES: u64 = 256 << 20;
/// Most pixels along an image side.
pub const MAX_IMAGE_SIDE: u32 = 1 << 20;
/// Decoded chunk rows an image keeps beyond the current window, in bytes.
const CACHE_BYTES: usize = 192 << 20;

/// The colour bands of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bands {
    Gray,
    GrayAlpha,
    Rgb,
    Rgba,
}

impl Bands {
    fn samples(self) -> usize {
        match self {
            Bands::Gray => 1,
            Bands::GrayAlpha => 2,
            Bands::Rgb => 3,
            Bands::Rgba => 4,
        }
    }
    fn colour_samples(self) -> usize {
        match self {
            Bands::Gray | Bands::GrayAlpha => 1,
            Bands::Rgb | Bands::Rgba => 3,
        }
    }
    fn has_alpha(self) -> bool {
        matches!(self, Bands::GrayAlpha | Bands::Rgba)
    }
}

/// What the extra (last) band of a grey-alpha or RGBA image means (TIFF ExtraSamples).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Extra {
    /// Unassociated alpha (ExtraSamples 2, or no tag).
    Alpha,
    /// Premultiplied alpha (ExtraSamples 1).
    Premultiplied,
    /// Unspecified data (ExtraSamples 0): ignored.
    Ignored,
}

/// How samples become bytes.
#[derive(Clone, Copy, Debug)]
struct Conversion {
    bands: Bands,
    extra: Extra,
    sixteen: bool,
    white_is_zero: bool,
    /// Raw colour sample value that maps to 255 (16-bit images; 255 for 8-bit).
    full_scale: u32,
    nodata: Option<f64>,
}

impl Conversion {
    /// Converts `pixels` pixels of raw samples (`get(i)` the i-th sample) into RGBA8.
    fn convert(&self, pixels: usize, get: impl Fn(usize) -> u32, out: &mut [u8]) {
        let spp = self.bands.samples();
        let colour = self.bands.colour_samples();
        let max_raw: u32 = if self.sixteen { 65535 } else { 255 };
        let scale = |raw: u32| -> u8 {
            let v = if self.white_is_zero {
                max_raw - raw
            } else {
                raw
            };
            if self.sixteen {
                let s = (u64::from(v) * 255 + u64::from(self.full_scale) / 2)
                    / u64::from(self.full_scale.max(1));
                s.min(255) as u8
            } else {
                v as u8
            }
        };
        for p in 0..pixels {
            let base = p * spp;
            let mut px = [0u8; 4];
            if let Some(nodata) = self.nodata {
                if (0..colour).all(|b| f64::from(get(base + b)) == nodata) {
                    out[p * 4..p * 4 + 4].copy_from_slice(&px);
                    continue;
                }
            }
            if colour == 1 {
                let g = scale(get(base));
                px = [g, g, g, 255];
            } else {
                px = [
                    scale(get(base)),
                    scale(get(base + 1)),
                    scale(get(base + 2)),
                    255,
                ];
            }
            if self.bands.has_alpha() && self.extra != Extra::Ignored {
                let raw = get(base + colour);
                let a = if self.sixteen {
                    (raw >> 8) as u8
                } else {
                    raw as u8
                };
                px[3] = a;
                if self.extra == Extra::Premultiplied && a > 0 {
                    for c in &mut px[..3] {
                        *c = ((u32::from(*c) * 255 + u32::from(a) / 2) / u32::from(a)).min(255)
                            as u8;
                    }
                }
                if a == 0 {
                    px = [0; 4];
                }
            }
            out[p * 4..p * 4 + 4].copy_from_slice(&px);
        }
    }
}

type TiffDecoder = Decoder<BufReader<File>>;

/// Decoded chunk rows, most recently used last.
struct Cache {
    rows: HashMap<u32, (Arc<Vec<u8>>, u64)>,
    clock: u64,
    bytes: usize,
}

/// One orthoimage, open for reading.
pub struct ImageSource {
    path: PathBuf,
    width: u32,
    height: u32,
    bits: u8,
    conversion: Conversion,
    georef: Georeference,
    /// Chunk size (width, height) and chunks across.
    chunk_w: u32,
    chunk_h: u32,
    tiled: bool,
    /// Footprint, degrees: (south, west, north, east).
    footprint: (f64, f64, f64, f64),
    /// Pixel size, metres (north-south, east-west).
    pixel_m: (f64, f64),
    decoder: Mutex<TiffDecoder>,
    cache: Mutex<Cache>,
}

/// A band of decoded rows of one image, RGBA8.
pub struct Window {
    first_row: u32,
    chunk_h: u32,
    width: u32,
    height: u32,
    chunks: Vec<Arc<Vec<u8>>>,
}

impl Window {
    /// (width, height) of the image, pixels.
    pub fn image_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The RGBA8 bytes of image row `row`, when the window holds it.
    #[inline]
    pub fn row(&self, row: u32) -> Option<&[u8]> {
        let rel = row.checked_sub(self.first_row)?;
        if row >= self.height {
            return None;
        }
        let chunk = self.chunks.get((rel / self.chunk_h) as usize)?;
        let w = self.width as usize * 4;
        let at = (rel % self.chunk_h) as usize * w;
        chunk.get(at..at + w)
    }

    #[inline]
    fn pixel(&self, col: u32, row: u32) -> [u8; 4] {
        if row < self.first_row || row >= self.height || col >= self.width {
            return [0; 4];
        }
        let rel = row - self.first_row;
        let Some(chunk) = self.chunks.get((rel / self.chunk_h) as usize) else {
            return [0; 4];
        };
        let at = (((rel % self.chunk_h) as usize) * self.width as usize + col as usize) * 4;
        match chunk.get(at..at + 4) {
            Some(p) => [p[0], p[1], p[2], p[3]],
            None => [0; 4],
        }
    }

    /// Alpha-weighted bilinear sample at fractional pixel coordinates (pixel centres at whole
    /// numbers); transparent beyond the pixels' areas.
    #[inline]
    pub fn sample(&self, col: f64, row: f64) -> [f32; 4] {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        if !(col >= -0.5 && col <= w - 0.5 && row >= -0.5 && row <= h - 0.5) {
            return [0.0; 4];
        }
        let col = col.clamp(0.0, w - 1.0);
        let row = row.clamp(0.0, h - 1.0);
        let c0 = (col.floor() as u32).min(self.width.saturating_sub(2));
        let r0 = (row.floor() as u32).min(self.height.saturating_sub(2));
        let fx = (col - f64::from(c0)).clamp(0.0, 1.0) as f32;
        let fy = (row - f64::from(r0)).clamp(0.0, 1.0) as f32;
        let c1 = (c0 + 1).min(self.width - 1);
        let r1 = (r0 + 1).min(self.height - 1);
        alpha_weighted_bilinear(
            [
                &self.pixel(c0, r0),
                &self.pixel(c1, r0),
                &self.pixel(c0, r1),
                &self.pixel(c1, r1),
            ],
            fx,
            fy,
        )
    }
}

impl ImageSource {
    /// Opens an image: header, colour layout, georeference; a 16-bit image is read once to
    /// find the value its 99.9th percentile maps to 255.
    pub fn open(path: &Path) -> Result<ImageSource, ImageryError> {
        catch_unwind(AssertUnwindSafe(|| ImageSource::open_inner(path))).unwrap_or_else(|_| {
            Err(ImageryError::Corrupt {
                reason: "the TIFF decoder failed on malformed data".to_string(),
                path: path.to_path_buf(),
            })
        })
    }

    fn open_inner(path: &Path) -> Result<ImageSource, ImageryError> {
        let corrupt = |e: TiffError| ImageryError::Corrupt {
            reason: describe(e),
            path: path.to_path_buf(),
        };
        let unsupported = |reason: String| ImageryError::Unsupported {
            reason,
            path: path.to_path_buf(),
        };
        let io = |e: std::io::Error| ImageryError::Io {
            reason: e.to_string(),
            path: path.to_path_buf(),
        };
        let mut file = File::open(path).map_err(io)?;
        let mut head = [0u8; 4];
        let got = file.read(&mut head).map_err(io)?;
        if !has_tiff_magic(&head[..got]) {
            return Err(ImageryError::NotTiff(path.to_path_buf()));
        }
        file.rewind().map_err(io)?;
        let mut limits = Limits::default();
        limits.decoding_buffer_size = 2 * MAX_CHUNK_ROW_BYTES as usize;
        limits.intermediate_buffer_size = 2 * MAX_CHUNK_ROW_BYTES as usize;
        limits.ifd_value_size = 64 << 20;
        let mut decoder = Decoder::new(BufReader::with_capacity(1 << 20, file))
            .map_err(corrupt)?
            .with_limits(limits);
        let (width, height) = decoder.dimensions().map_err(corrupt)?;
        if width == 0 || height == 0 {
            return Err(ImageryError::Corrupt {
                reason: format!("empty image of {width} x {height} pixels"),
                path: path.to_path_buf(),
            });
        }
        if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(ImageryError::TooLarge {
                reason: format!("{width} x {height} pixels is over {MAX_IMAGE_SIDE} pixels a side"),
                path: path.to_path_buf(),
            });
        }
        let colortype = decoder.colortype().map_err(|e| match e {
            TiffError::UnsupportedError(u) => unsupported(format!("colour layout: {u}")),
            other => corrupt(other),
        })?;
        let (bands, bits) = match colortype {
            ColorType::Gray(b) => (Bands::Gray, b),
            ColorType::GrayA(b) => (Bands::GrayAlpha, b),
            ColorType::RGB(b) => (Bands::Rgb, b),
            ColorType::RGBA(b) => (Bands::Rgba, b),
            other => {
                return Err(unsupported(format!(
                    "colour layout {other:?} (read: 8- or 16-bit grey, grey-alpha, RGB, RGBA)"
                )))
            }
        };
        let sample_format = decoder
            .find_tag_unsigned_vec::<u16>(Tag::SampleFormat)
            .map_err(corrupt)?
            .unwrap_or_default();
        if sample_format.iter().any(|&f| f != 1) || !(bits == 8 || bits == 16) {
            let kind = match sample_format.first() {
                Some(3) => "floating-point",
                Some(2) => "signed",
                _ => "unsigned",
            };
            return Err(unsupported(format!(
                "{bits}-bit {kind} samples (read: 8- or 16-bit unsigned)"
            )));
        }
        let planar = decoder
            .find_tag_unsigned::<u16>(Tag::PlanarConfiguration)
            .map_err(corrupt)?
            .unwrap_or(1);
        if planar != 1 && bands.samples() > 1 {
            return Err(unsupported(
                "separate colour planes (PlanarConfiguration 2)".to_string(),
            ));
        }
        let white_is_zero = decoder
            .find_tag_unsigned::<u16>(Tag::PhotometricInterpretation)
            .map_err(corrupt)?
            == Some(0);
        let extra = match decoder
            .find_tag_unsigned_vec::<u16>(Tag::ExtraSamples)
            .map_err(corrupt)?
            .and_then(|v| v.first().copied())
        {
            None | Some(2) => Extra::Alpha,
            Some(1) => Extra::Premultiplied,
            Some(_) => Extra::Ignored,
        };
        let georef = read_georeference(&mut decoder, path)?;
        let nodata = match decoder.find_tag(Tag::GdalNodata).map_err(corrupt)? {
            None => None,
            Some(value) => {
                let text = value.into_string().map_err(corrupt)?;
                let text = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
                Some(text.parse::<f64>().map_err(|_| ImageryError::Corrupt {
                    reason: format!("GDAL_NODATA value \"{text}\" is not a number"),
                    path: path.to_path_buf(),
                })?)
            }
        };
        let tiled = decoder.get_chunk_type() == ChunkType::Tile;
        let (chunk_w, chunk_h) = if tiled {
            decoder.chunk_dimensions()
        } else {
            (width, decoder.chunk_dimensions().1.clamp(1, height))
        };
        if chunk_w == 0 || chunk_h == 0 {
            return Err(ImageryError::Corrupt {
                reason: "chunks of zero pixels".to_string(),
                path: path.to_path_buf(),
            });
        }
        let row_bytes = u64::from(width.div_ceil(chunk_w) * chunk_w) * u64::from(chunk_h) * 4;
        if row_bytes > MAX_CHUNK_ROW_BYTES {
            return Err(ImageryError::TooLarge {
                reason: format!(
                    "a {} of {chunk_h} rows decodes to {} MB, over the {} MB limit; re-tile the \
                     image, e.g. gdal_translate -co TILED=YES",
                    if tiled { "row of tiles" } else { "strip" },
                    row_bytes >> 20,
                    MAX_CHUNK_ROW_BYTES >> 20
                ),
                path: path.to_path_buf(),
            });
        }
        let (footprint, pixel_m) = footprint(&georef, width, height);
        if !(footprint.0.is_finite()
            && footprint.2.is_finite()
            && footprint.1.is_finite()
            && footprint.3.is_finite()
            && footprint.0 >= -90.0 - 1e-6
            && footprint.2 <= 90.0 + 1e-6
            && pixel_m.0 > 0.0
            && pixel_m.1 > 0.0)
        {
            return Err(ImageryError::Georeference {
                reason: format!(
                    "footprint {:?} degrees (south, west, north, east) is not on the globe",
                    footprint
                ),
                path: path.to_path_buf(),
            });
        }
        let mut source = ImageSource {
            path: path.to_path_buf(),
            width,
            height,
            bits,
            conversion: Conversion {
                bands,
                extra,
                sixteen: bits == 16,
                white_is_zero,
                full_scale: 255,
                nodata,
            },
            georef,
            chunk_w,
            chunk_h,
            tiled,
            footprint,
            pixel_m,
            decoder: Mutex::new(decoder),
            cache: Mutex::new(Cache {
                rows: HashMap::new(),
                clock: 0,
                bytes: 0,
            }),
        };
        if bits == 16 {
            source.conversion.full_scale = source.percentile_999()?;
        }
        Ok(source)
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// (width, height) in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Footprint in degrees: (south, west, north, east), pixel areas included.
    pub fn footprint_deg(&self) -> (f64, f64, f64, f64) {
        self.footprint
    }

    /// Pixel size in metres (north-south, east-west).
    pub fn pixel_m(&self) -> (f64, f64) {
        self.pixel_m
    }

    /// The raw 16-bit value that maps to 255 (`None` for 8-bit images).
    pub fn full_scale(&self) -> Option<u32> {
        (self.bits == 16).then_some(self.conversion.full_scale)
    }

    /// The coordinate system, as an EPSG name.
    pub fn crs_name(&self) -> String {
        match self.georef.crs {
            Crs::Geographic => "EPSG:4326".to_string(),
            Crs::Utm { epsg, .. } => format!("EPSG:{epsg}"),
        }
    }

    /// One line for the manifest: file, size, layout, CRS, pixel size.
    pub fn describe(&self) -> String {
        let bands = match self.conversion.bands {
            Bands::Gray => "grey",
            Bands::GrayAlpha => "grey+alpha",
            Bands::Rgb => "RGB",
            Bands::Rgba => "RGBA",
        };
        format!(
            "GeoTIFF {} {} x {} px {bands} {}-bit {} pixel {:.3} x {:.3} m",
            self.path.display(),
            self.width,
            self.height,
            self.bits,
            self.crs_name(),
            self.pixel_m.1,
            self.pixel_m.0
        )
    }

    /// Fractional pixel coordinates (col, row), pixel centres at whole numbers, of a point.
    pub fn pixel_of(&self, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
        let (x, y) = match self.georef.crs {
            Crs::Geographic => (lon_deg, lat_deg),
            Crs::Utm { zone, .. } => geodetic_to_utm(zone, lat_deg, lon_deg),
        };
        self.model_to_pixel(x, y)
    }

    /// Whether a point projection is linear in latitude and longitude (geographic images).
    pub fn is_geographic(&self) -> bool {
        matches!(self.georef.crs, Crs::Geographic)
    }

    fn model_to_pixel(&self, x: f64, y: f64) -> (f64, f64) {
        let a = self.georef.affine;
        ((x - a.x0) / a.dx, (y - a.y0) / a.dy)
    }

    /// The decoded rows `rows` (clamped to the image), as a window. Chunk rows are decoded on
    /// demand and kept in a small cache.
    pub fn window(&self, first: u32, last: u32) -> Result<Window, ImageryError> {
        let last = last.min(self.height - 1);
        let first = first.min(last);
        let (c0, c1) = (first / self.chunk_h, last / self.chunk_h);
        let mut chunks = Vec::with_capacity((c1 - c0 + 1) as usize);
        let mut cache = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
        cache.clock += 1;
        let now = cache.clock;
        for c in c0..=c1 {
            if let Some((data, used)) = cache.rows.get_mut(&c) {
                *used = now;
                chunks.push(Arc::clone(data));
                continue;
            }
            let data = Arc::new(self.decode_chunk_row(c)?);
            cache.bytes += data.len();
            cache.rows.insert(c, (Arc::clone(&data), now));
            chunks.push(data);
        }
        // Evict the least recently used rows outside this window beyond the budget.
        while cache.bytes > CACHE_BYTES {
            let oldest = cache
                .rows
                .iter()
                .filter(|(_, (_, used))| *used != now)
                .min_by_key(|(_, (_, used))| *used)
                .map(|(k, _)| *k);
            let Some(k) = oldest else { break };
            if let Some((data, _)) = cache.rows.remove(&k) {
                cache.bytes -= data.len();
            }
        }
        Ok(Window {
            first_row: c0 * self.chunk_h,
            chunk_h: self.chunk_h,
            width: self.width,
            height: self.height,
            chunks,
        })
    }

    /// Drops every cached row.
    pub fn release(&self) {
        let mut cache = self.cache.lock().unwrap_or_else(PoisonError::into_inner);
        cache.rows.clear();
        cache.bytes = 0;
    }

    /// Decodes chunk row `c` (a strip, or a row of tiles) into `chunk_h` RGBA8 rows of the
    /// image's width (rows past the image's end left transparent).
    fn decode_chunk_row(&self, c: u32) -> Result<Vec<u8>, ImageryError> {
        let width = self.width as usize;
        let mut out = vec![0u8; width * self.chunk_h as usize * 4];
        let across = if self.tiled {
            self.width.div_ceil(self.chunk_w)
        } else {
            1
        };
        let mut decoder = self.decoder.lock().unwrap_or_else(PoisonError::into_inner);
        for t in 0..across {
            let index = c * across + t;
            let (data, dw, dh) = self.read_chunk(&mut decoder, index)?;
            let x0 = (t * self.chunk_w) as usize;
            let dw = dw.min(width.saturating_sub(x0));
            let rows = dh.min(self.chunk_h as usize);
            for r in 0..rows {
                let dst = &mut out[(r * width + x0) * 4..(r * width + x0 + dw) * 4];
                let spp = self.conversion.bands.samples();
                let offset = r * data.stride * spp;
                self.convert_into(&data, offset, dw, dst);
            }
        }
        Ok(out)
    }

    fn convert_into(&self, data: &Chunk, offset: usize, pixels: usize, dst: &mut [u8]) {
        match &data.samples {
            DecodingResult::U8(v) => {
                let v = &v[offset..];
                self.conversion
                    .convert(pixels, |i| u32::from(v.get(i).copied().unwrap_or(0)), dst)
            }
            DecodingResult::U16(v) => {
                let v = &v[offset..];
                self.conversion
                    .convert(pixels, |i| u32::from(v.get(i).copied().unwrap_or(0)), dst)
            }
            _ => {}
        }
    }

    /// Reads one chunk; its samples, data width and rows.
    fn read_chunk(
        &self,
        decoder: &mut TiffDecoder,
        index: u32,
    ) -> Result<(Chunk, usize, usize), ImageryError> {
        let corrupt = |reason: String| ImageryError::Corrupt {
            reason,
            path: self.path.clone(),
        };
        // A decoder bug on hostile data must not bring the import down.
        let samples = catch_unwind(AssertUnwindSafe(|| decoder.read_chunk(index)))
            .map_err(|_| corrupt(format!("chunk {index}: the TIFF decoder failed")))?
            .map_err(|e| corrupt(format!("chunk {index}: {}", describe(e))))?;
        let (cw, ch) = self.chunk_data_dims(index);
        let len = match &samples {
            DecodingResult::U8(v) => v.len(),
            DecodingResult::U16(v) => v.len(),
            _ => return Err(corrupt(format!("chunk {index}: unexpected sample type"))),
        };
        let spp = self.conversion.bands.samples();
        if len < cw * ch * spp {
            return Err(corrupt(format!(
                "chunk {index} holds {len} samples, expected {}",
                cw * ch * spp
            )));
        }
        Ok((
            Chunk {
                samples,
                stride: cw,
            },
            cw,
            ch,
        ))
    }

    /// Width and rows of a chunk's data (the image's edge cuts the last ones).
    fn chunk_data_dims(&self, index: u32) -> (usize, usize) {
        if self.tiled {
            let across = self.width.div_ceil(self.chunk_w);
            let (tx, ty) = (index % across, index / across);
            let w = self.chunk_w.min(self.width - tx * self.chunk_w);
            let h = self
                .chunk_h
                .min(self.height.saturating_sub(ty * self.chunk_h));
            (w as usize, h as usize)
        } else {
            let h = self
                .chunk_h
                .min(self.height.saturating_sub(index * self.chunk_h));
            (self.width as usize, h as usize)
        }
    }

    /// The raw colour value at the 99.9th percentile of a 16-bit image (nodata and transparent
    /// pixels left out); 65535 when that is 0.
    fn percentile_999(&self) -> Result<u32, ImageryError> {
        let mut histogram = vec![0u64; 65536];
        let chunks = if self.tiled {
            self.width.div_ceil(self.chunk_w) * self.height.div_ceil(self.chunk_h)
        } else {
            self.height.div_ceil(self.chunk_h)
        };
        let bands = self.conversion.bands;
        let (spp, colour) = (bands.samples(), bands.colour_samples());
        let alpha = bands.has_alpha() && self.conversion.extra != Extra::Ignored;
        let mut decoder = self.decoder.lock().unwrap_or_else(PoisonError::into_inner);
        for index in 0..chunks {
            let (chunk, cw, ch) = self.read_chunk(&mut decoder, index)?;
            let DecodingResult::U16(v) = &chunk.samples else {
                continue;
            };
            for px in v.chunks_exact(spp).take(cw * ch) {
                if alpha && px[colour] == 0 {
                    continue;
                }
                if let Some(nodata) = self.conversion.nodata {
                    if px[..colour].iter().all(|&s| f64::from(s) == nodata) {
                        continue;
                    }
                }
                for &s in &px[..colour] {
                    let s = if self.conversion.white_is_zero {
                        65535 - s
                    } else {
                        s
                    };
                    histogram[usize::from(s)] += 1;
                }
            }
        }
        let total: u64 = histogram.iter().sum();
        let target = total - total / 1000;
        let mut seen = 0u64;
        let mut value = 0u32;
        for (v, n) in histogram.iter().enumerate() {
            seen += n;
            if seen >= target.max(1) {
                value = v as u32;
                break;
            }
        }
        Ok(if value == 0 { 65535 } else { value })
    }
}

struct Chunk {
    samples: DecodingResult,
    /// Pixels per row of the decoded data.
    stride: usize,
}

/// The footprint (south, west, north, east) in degrees, pixel areas included, and the pixel
/// size in metres (north-south, east-west) at the footprint's centre.
fn footprint(georef: &Georeference, width: u32, height: u32) -> ((f64, f64, f64, f64), (f64, f64)) {
    let a = georef.affine;
    // Pixel-area corners: half a pixel beyond the outer pixel centres.
    let xs = [a.x0 - 0.5 * a.dx, a.x0 + (f64::from(width) - 0.5) * a.dx];
    let ys = [a.y0 - 0.5 * a.dy, a.y0 + (f64::from(height) - 0.5) * a.dy];
    let (x_lo, x_hi) = (xs[0].min(xs[1]), xs[0].max(xs[1]));
    let (y_lo, y_hi) = (ys[0].min(ys[1]), ys[0].max(ys[1]));
    match georef.crs {
        Crs::Geographic => {
            let centre = 0.5 * (y_lo + y_hi);
            let (north_m, east_m) = cig_geo::metres_per_degree(centre);
            (
                (y_lo, x_lo, y_hi, x_hi),
                (a.dy.abs() * north_m, a.dx.abs() * east_m),
            )
        }
        Crs::Utm { zone, .. } => {
            const STEPS: usize = 64;
            let mut b = (
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            );
            if !(x_lo > -2.0e6 && x_hi < 3.0e6 && y_lo > -1.0e7 && y_hi < 2.0e7) {
                return ((f64::NAN, f64::NAN, f64::NAN, f64::NAN), (0.0, 0.0));
            }
            for step in 0..=STEPS {
                let t = step as f64 / STEPS as f64;
                let (x, y) = (x_lo + t * (x_hi - x_lo), y_lo + t * (y_hi - y_lo));
                for (e, n) in [(x, y_lo), (x, y_hi), (x_lo, y), (x_hi, y)] {
                    let (lat, lon) = utm_to_geodetic(zone, e, n);
                    b = (b.0.min(lat), b.1.min(lon), b.2.max(lat), b.3.max(lon));
                }
            }
            (b, (a.dy.abs(), a.dx.abs()))
        }
    }
}

/// Alpha-weighted bilinear blend of four RGBA8 texels (top-left, top-right, bottom-left,
/// bottom-right) at fractions `fx`, `fy`: straight colour 0-255, alpha 0-1; transparent where
/// all four are.
#[inline]
pub(crate) fn alpha_weighted_bilinear(p: [&[u8]; 4], fx: f32, fy: f32) -> [f32; 4] {
    let weights = [
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    ];
    let mut acc = [0.0f32; 4];
    for (px, w) in p.iter().zip(weights) {
        let wa = w * f32::from(px[3]);
        acc[0] += wa * f32::from(px[0]);
        acc[1] += wa * f32::from(px[1]);
        acc[2] += wa * f32::from(px[2]);
        acc[3] += wa;
    }
    if acc[3] <= 0.0 {
        return [0.0; 4];
    }
    [
        acc[0] / acc[3],
        acc[1] / acc[3],
        acc[2] / acc[3],
        acc[3] / 255.0,
    ]
}
