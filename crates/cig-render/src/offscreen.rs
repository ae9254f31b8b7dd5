//! Off-screen frames: render a view into a texture and read its pixels back.

use crate::gpu::RenderError;
use crate::renderer::{serde_like::FrameStats, FrameOptions, Renderer, FRAME_FORMAT};
use cig_scene::FrameSnapshot;
use cig_terrain::TileCache;

/// A colour target of the frame format that frames can be drawn into without reading them
/// back (benchmarks time the drawing alone).
pub struct OffscreenTarget {
    _texture: wgpu::Texture,
    view: wgpu::TextureView,
}

impl OffscreenTarget {
    /// A target of `size` pixels in [`FRAME_FORMAT`].
    pub fn new(gpu: &crate::Gpu, size: (u32, u32)) -> OffscreenTarget {
        let texture = crate::gpu::render_target(
            &gpu.device,
            "off-screen target",
            size,
            FRAME_FORMAT,
            1,
            wgpu::TextureUsages::empty(),
            &[],
        );
        let view = texture.create_view(&Default::default());
        OffscreenTarget {
            _texture: texture,
            view,
        }
    }

    /// What [`Renderer::render`] draws into.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }
}

/// An RGBA8 (sRGB) image, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Image {
    /// Pixels where any channel differs from `other`'s by more than `tolerance`.
    pub fn pixels_differing(&self, other: &Image, tolerance: u8) -> usize {
        self.rgba
            .chunks_exact(4)
            .zip(other.rgba.chunks_exact(4))
            .filter(|(a, b)| {
                a.iter()
                    .zip(b.iter())
                    .any(|(x, y)| x.abs_diff(*y) > tolerance)
            })
            .count()
    }
}

/// Loads, in the calling thread, every tile the view's selection still wants, until the
/// selection is complete (at most `max_rounds` rounds): what a one-off frame needs.
pub fn load_for_view(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    view_index: usize,
    max_rounds: usize,
) -> Result<usize, RenderError> {
    let mut loaded = 0;
    for _ in 0..max_rounds {
        let missing = renderer.missing_tiles(cache, snapshot, view_index)?;
        if missing.is_empty() {
            break;
        }
        let before = loaded;
        for key in missing {
            // A tile that fails is logged by the cache and drawn from its parent.
            if cache.load_now(key).is_ok() {
                loaded += 1;
            }
        }
        if loaded == before {
            break;
        }
    }
    Ok(loaded)
}

/// Renders one view to an image.
pub fn render_image(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    view_index: usize,
) -> Result<(Image, FrameStats), RenderError> {
    render_image_with(
        renderer,
        cache,
        snapshot,
        view_index,
        FrameOptions {
            mesh_budget: usize::MAX,
            key_background: false,
            fade_in_s: 0.0,
            adaptation: crate::adaptation::Adaptation::Settled,
        },
    )
}

/// [`render_image`] with explicit frame options.
pub fn render_image_with(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    view_index: usize,
    options: FrameOptions,
) -> Result<(Image, FrameStats), RenderError> {
    let view = snapshot
        .views
        .get(view_index)
        .ok_or_else(|| RenderError::Gpu(format!("no view {view_index}")))?;
    view.validate()?;
    crate::gpu::check_frame_size(renderer.gpu(), view.width_px, view.height_px)?;
    let (width, height) = (view.width_px, view.height_px);
    let gpu = renderer.gpu().clone();
    let plain = [crate::display::DISPLAY_VIEW_FORMAT];
    let texture = crate::gpu::render_target(
        &gpu.device,
        "frame",
        (width, height),
        FRAME_FORMAT,
        1,
        wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
        &plain,
    );
    let target = texture.create_view(&Default::default());
    let stats = renderer.render(cache, snapshot, view_index, &target, options)?;
    let Some(display) = renderer.display_pass() else {
        return Ok((read_rgba(&gpu, &texture)?, stats));
    };
    // The display correction: the frame, warped and blended, into the display's frame.
    let shown = crate::gpu::render_target(
        &gpu.device,
        "display frame",
        (width, height),
        FRAME_FORMAT,
        1,
        wgpu::TextureUsages::COPY_SRC,
        &plain,
    );
    let as_plain = |t: &wgpu::Texture| {
        t.create_view(&wgpu::TextureViewDescriptor {
            format: Some(crate::display::DISPLAY_VIEW_FORMAT),
            ..Default::default()
        })
    };
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("display correction"),
        });
    display.record(
        &gpu,
        &mut encoder,
        &as_plain(&texture),
        (width, height),
        &as_plain(&shown),
        (width, height),
    );
    gpu.queue.submit([encoder.finish()]);
    Ok((read_rgba(&gpu, &shown)?, stats))
}

/// Reads an 8-bit RGBA or BGRA texture back as RGBA rows from the top.
pub fn read_rgba(gpu: &crate::gpu::Gpu, texture: &wgpu::Texture) -> Result<Image, RenderError> {
    let (width, height) = (texture.width(), texture.height());
    let swap_red_blue = match texture.format().remove_srgb_suffix() {
        wgpu::TextureFormat::Rgba8Unorm => false,
        wgpu::TextureFormat::Bgra8Unorm => true,
        other => {
            return Err(RenderError::Readback(format!(
                "screenshots of {other:?} frames are not supported (8-bit RGBA or BGRA only)"
            )))
        }
    };
    let bytes_per_row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("frame readback"),
        size: u64::from(bytes_per_row) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame readback"),
        });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_row),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    crate::gpu::map_for_reading(gpu, &slice)?;
    let row_bytes = width as usize * 4;
    let mut rgba = Vec::with_capacity(row_bytes * height as usize);
    {
        let data = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        for row in data.chunks(bytes_per_row as usize).take(height as usize) {
            let pixels = row.get(..row_bytes).ok_or_else(|| {
                RenderError::Readback("the read-back buffer is shorter than the frame".into())
            })?;
            rgba.extend_from_slice(pixels);
        }
    }
    buffer.unmap();
    if swap_red_blue {
        for pixel in rgba.chunks_exact_mut(4) {
            pixel.swap(0, 2);
        }
    }
    Ok(Image {
        width,
        height,
        rgba,
    })
}
