//! The periscope's reticle drawn over a finished frame: a horizontal line graduated in
//! degrees (`cig_sea::periscope::reticle_ticks`, the stadimeter's scale: a masthead's
//! subtended angle is read off it), a short vertical line at the centre, and the true bearing
//! of the line of sight as three digits above the centre.
//!
//! Limits: drawn in black on the frame's pixels (no anti-aliasing, no illumination of the
//! graticule at night); the digits are a 5 x 7 bitmap font scaled to the frame.

/// 5 x 7 bitmaps of the digits 0-9, one row a byte (bit 4 the left column).
const DIGITS: [[u8; 7]; 10] = [
    [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
    [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
    [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
    [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
    [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
    [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
    [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
    [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
    [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
    [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
];

/// The graticule's colour (RGBA).
const INK: [u8; 4] = [0, 0, 0, 255];

/// An RGBA frame to draw on.
pub struct Canvas<'a> {
    pub rgba: &'a mut [u8],
    pub width: u32,
    pub height: u32,
}

impl Canvas<'_> {
    fn fill(&mut self, x0: i64, y0: i64, x1: i64, y1: i64) {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        for y in y0.max(0)..y1.min(h) {
            for x in x0.max(0)..x1.min(w) {
                // Inside the frame: both are non-negative and below its size.
                let i = ((y * w + x) * 4) as usize;
                if let Some(px) = self.rgba.get_mut(i..i + 4) {
                    px.copy_from_slice(&INK);
                }
            }
        }
    }
}

/// Draws the reticle of a view `fov_deg` wide (horizontal) whose line of sight bears
/// `bearing_deg` true. Frames too small for it (under 32 pixels) are left alone.
pub fn draw_periscope_reticle(canvas: &mut Canvas<'_>, fov_deg: f64, bearing_deg: f64) {
    if canvas.width < 32 || canvas.height < 32 {
        return;
    }
    let (w, h) = (i64::from(canvas.width), i64::from(canvas.height));
    let (cx, cy) = (w / 2, h / 2);
    let line = (h / 400).max(1);
    let half_tan = (fov_deg.to_radians() * 0.5).tan();
    // The horizontal line and the centre's vertical one.
    canvas.fill(0, cy - line / 2, w, cy - line / 2 + line);
    canvas.fill(cx - line / 2, cy - h / 6, cx - line / 2 + line, cy + h / 6);
    let ticks = cig_sea::periscope::reticle_ticks(fov_deg).unwrap_or_default();
    for tick in ticks {
        let x =
            cx + (tick.angle_deg.to_radians().tan() / half_tan * (w as f64) * 0.5).round() as i64;
        let length = if tick.major { h / 30 } else { h / 60 }.max(2);
        canvas.fill(x - line / 2, cy - length, x - line / 2 + line, cy + length);
    }
    // The bearing, three digits above the centre.
    let scale = (h / 120).max(1);
    let bearing = bearing_deg.rem_euclid(360.0).round() as u32 % 360;
    let digits = [bearing / 100, bearing / 10 % 10, bearing % 10];
    let glyph_w = 6 * scale;
    let left = cx - (3 * glyph_w) / 2;
    let top = cy - h / 6 - 9 * scale;
    for (k, d) in digits.iter().enumerate() {
        let Some(rows) = DIGITS.get(*d as usize) else {
            continue;
        };
        for (r, bits) in rows.iter().enumerate() {
            for c in 0..5 {
                if bits & (0x10 >> c) != 0 {
                    let x = left + k as i64 * glyph_w + c * scale;
                    let y = top + r as i64 * scale;
                    canvas.fill(x, y, x + scale, y + scale);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink_at(rgba: &[u8], width: u32, x: u32, y: u32) -> bool {
        let i = ((y * width + x) * 4) as usize;
        rgba[i..i + 3] == [0, 0, 0]
    }

    #[test]
    fn ticks_fall_at_their_angles_and_the_bearing_is_written() {
        let (w, h) = (800u32, 600u32);
        let mut rgba = vec![255u8; (w * h * 4) as usize];
        draw_periscope_reticle(
            &mut Canvas {
                rgba: &mut rgba,
                width: w,
                height: h,
            },
            8.0,
            295.0,
        );
        // The centre line, and a tick 1 degree right of the centre (8-degree field: 0.2
        // degree steps, a major one every degree).
        assert!(ink_at(&rgba, w, 10, h / 2));
        let x = (400.0 + 1f64.to_radians().tan() / 4f64.to_radians().tan() * 400.0).round() as u32;
        assert!(ink_at(&rgba, w, x, h / 2 - 15));
        assert!(!ink_at(&rgba, w, x + 3, h / 2 - 15));
        // Ink above the centre where the digits are, none in the corners.
        let inked = (0..w * h)
            .filter(|i| ink_at(&rgba, w, i % w, i / w))
            .count();
        assert!(inked > 1000);
        assert!(!ink_at(&rgba, w, 5, 5));
        // A tiny frame is left alone.
        let mut small = vec![255u8; 16 * 16 * 4];
        draw_periscope_reticle(
            &mut Canvas {
                rgba: &mut small,
                width: 16,
                height: 16,
            },
            8.0,
            0.0,
        );
        assert!(small.iter().all(|&v| v == 255));
    }
}
