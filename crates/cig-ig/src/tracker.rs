//! A thermal sensor's centroid tracker: the hottest (or, tracking black, the coldest) blob in a
//! gate, followed from frame to frame.
//!
//! Algorithm (the classic contrast centroid tracker of FLIR sights): in the gate, the mean `m`
//! and the extreme `x` of the band radiance; the target is the pixels beyond `m + (x - m) / 2`
//! connected (4-neighbours) to the extreme pixel; its centroid, weighted by the excess over
//! the threshold, moves the gate. A blob's contrast `|x - m|` under [`MIN_CONTRAST`] of the
//! gate's mean is no target. Status, as CIGI's Sensor Response: 0 searching (no target yet:
//! the gate waits at the frame's centre), 1 tracking, 2 impending breaklock (the target touches
//! the frame's edge, or was lost for fewer than [`BREAKLOCK_FRAMES`] frames: the gate coasts),
//! 3 breaklock (lost that long, or the gate left the frame); after a breaklock the tracker
//! searches again at the centre.
//!
//! Limits: no prediction of the target's motion beyond coasting, no clutter rejection or
//! correlation (CIGI's "force correlate" and "scene" modes track like "target"), one target.

/// Sensor Response statuses.
pub const STATUS_SEARCHING: u8 = 0;
pub const STATUS_TRACKING: u8 = 1;
pub const STATUS_IMPENDING_BREAKLOCK: u8 = 2;
pub const STATUS_BREAKLOCK: u8 = 3;

/// Least contrast of a target, as a fraction of the gate's mean radiance.
pub const MIN_CONTRAST: f32 = 0.03;
/// Frames a lost target coasts before the breaklock.
pub const BREAKLOCK_FRAMES: u32 = 10;

/// A tracker's state.
#[derive(Clone, Debug, PartialEq)]
pub struct Tracker {
    /// The gate's centre, pixels (x right, y down).
    pub centre_px: [f64; 2],
    /// The gate's size, pixels.
    pub gate_px: [u32; 2],
    pub status: u8,
    lost_frames: u32,
    /// The target's centroid in the last frame it was seen, pixels.
    pub target_px: Option<[f64; 2]>,
}

/// A rectangle of the frame, pixels: x, y, width, height.
pub type Rect = [u32; 4];

impl Tracker {
    /// A tracker searching at the centre of a `frame_px` frame with a gate an eighth of its
    /// width (at least 8 pixels).
    pub fn new(frame_px: [u32; 2]) -> Tracker {
        let side = (frame_px[0] / 8).max(8).min(frame_px[0]).min(frame_px[1]);
        Tracker {
            centre_px: [f64::from(frame_px[0]) / 2.0, f64::from(frame_px[1]) / 2.0],
            gate_px: [side, side],
            status: STATUS_SEARCHING,
            lost_frames: 0,
            target_px: None,
        }
    }

    /// The gate's rectangle in a `frame_px` frame (clamped inside it).
    pub fn gate(&self, frame_px: [u32; 2]) -> Rect {
        let [w, h] = [
            self.gate_px[0].min(frame_px[0]),
            self.gate_px[1].min(frame_px[1]),
        ];
        let x = (self.centre_px[0] - f64::from(w) / 2.0)
            .round()
            .clamp(0.0, f64::from(frame_px[0] - w)) as u32;
        let y = (self.centre_px[1] - f64::from(h) / 2.0)
            .round()
            .clamp(0.0, f64::from(frame_px[1] - h)) as u32;
        [x, y, w, h]
    }

    /// Updates the track from the gate's band radiance (`values`, row by row, the rectangle
    /// [`Tracker::gate`] gave) in a `frame_px` frame; `track_black` tracks the coldest blob.
    pub fn update(&mut self, gate: Rect, values: &[f32], frame_px: [u32; 2], track_black: bool) {
        let [gx, gy, w, h] = gate;
        let n = (w * h) as usize;
        let found = if values.len() == n && n > 0 {
            blob(values, w as usize, h as usize, track_black)
        } else {
            None
        };
        match found {
            Some((cx, cy, touches_edge)) => {
                let target = [f64::from(gx) + cx, f64::from(gy) + cy];
                self.centre_px = target;
                self.target_px = Some(target);
                self.lost_frames = 0;
                let at_frame_edge = touches_edge.frame_edge(gate, frame_px);
                self.status = if at_frame_edge {
                    STATUS_IMPENDING_BREAKLOCK
                } else {
                    STATUS_TRACKING
                };
            }
            None => match self.status {
                STATUS_TRACKING | STATUS_IMPENDING_BREAKLOCK => {
                    self.lost_frames += 1;
                    self.status = if self.lost_frames >= BREAKLOCK_FRAMES {
                        STATUS_BREAKLOCK
                    } else {
                        STATUS_IMPENDING_BREAKLOCK
                    };
                }
                STATUS_BREAKLOCK => {
                    *self = Tracker {
                        gate_px: self.gate_px,
                        ..Tracker::new(frame_px)
                    };
                }
                _ => {}
            },
        }
    }
}

/// Which sides of the gate the blob touches.
#[derive(Clone, Copy, Debug, Default)]
struct Touches {
    left: bool,
    right: bool,
    top: bool,
    bottom: bool,
}

impl Touches {
    /// Whether a touched side of the gate is also the frame's edge.
    fn frame_edge(self, [x, y, w, h]: Rect, frame_px: [u32; 2]) -> bool {
        (self.left && x == 0)
            || (self.top && y == 0)
            || (self.right && x + w >= frame_px[0])
            || (self.bottom && y + h >= frame_px[1])
    }
}

/// The target blob's weighted centroid in the gate (pixel centres at +0.5) and the gate sides it
/// touches; `None` when the gate holds no target.
fn blob(values: &[f32], w: usize, h: usize, track_black: bool) -> Option<(f64, f64, Touches)> {
    let sign = if track_black { -1.0 } else { 1.0 };
    let v = |i: usize| sign * values[i];
    let mean = values.iter().map(|x| f64::from(*x)).sum::<f64>() / values.len() as f64;
    let (peak, peak_value) = (0..values.len())
        .map(|i| (i, v(i)))
        .filter(|(_, x)| x.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let signed_mean = sign * mean as f32;
    let contrast = peak_value - signed_mean;
    if contrast.is_nan() || contrast <= MIN_CONTRAST * (mean.abs() as f32).max(1e-6) {
        return None;
    }
    let threshold = signed_mean + 0.5 * contrast;
    // Flood fill from the peak over the pixels beyond the threshold.
    let mut inside = vec![false; values.len()];
    let mut stack = vec![peak];
    inside[peak] = true;
    let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
    let mut touches = Touches::default();
    while let Some(i) = stack.pop() {
        let (x, y) = (i % w, i / w);
        let weight = f64::from(v(i) - threshold);
        sx += weight * (x as f64 + 0.5);
        sy += weight * (y as f64 + 0.5);
        sw += weight;
        touches.left |= x == 0;
        touches.right |= x + 1 == w;
        touches.top |= y == 0;
        touches.bottom |= y + 1 == h;
        let mut visit = |j: usize| {
            if !inside[j] && v(j) > threshold {
                inside[j] = true;
                stack.push(j);
            }
        };
        if x > 0 {
            visit(i - 1);
        }
        if x + 1 < w {
            visit(i + 1);
        }
        if y > 0 {
            visit(i - w);
        }
        if y + 1 < h {
            visit(i + w);
        }
    }
    (sw > 0.0).then(|| (sx / sw, sy / sw, touches))
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRAME: [u32; 2] = [160, 120];

    /// A frame at 20 (W m-2 sr-1) with a hot 5 x 5 square at `at` (pixels), cut to the gate.
    fn gate_values(gate: Rect, at: Option<[f64; 2]>) -> Vec<f32> {
        let [gx, gy, w, h] = gate;
        let mut out = Vec::new();
        for y in gy..gy + h {
            for x in gx..gx + w {
                let hot = at.is_some_and(|[cx, cy]| {
                    (f64::from(x) + 0.5 - cx).abs() < 2.5 && (f64::from(y) + 0.5 - cy).abs() < 2.5
                });
                out.push(if hot {
                    40.0
                } else {
                    20.0 + 0.1 * ((x * 7 + y * 3) % 5) as f32
                });
            }
        }
        out
    }

    #[test]
    fn holds_a_moving_hot_target_and_breaks_lock_when_it_leaves_the_frame() {
        let mut t = Tracker::new(FRAME);
        let mut at = [80.0, 60.0];
        let mut statuses = Vec::new();
        for _ in 0..80 {
            let gate = t.gate(FRAME);
            let inside = at[0] < f64::from(FRAME[0]) + 3.0;
            t.update(gate, &gate_values(gate, inside.then_some(at)), FRAME, false);
            statuses.push(t.status);
            if t.status == STATUS_TRACKING {
                let c = t.target_px.expect("target");
                assert!(
                    (c[0] - at[0]).abs() < 0.6 && (c[1] - at[1]).abs() < 0.6,
                    "{c:?} vs {at:?}"
                );
            }
            // Moves right 2 px a frame, a little down.
            at = [at[0] + 2.0, at[1] + 0.3];
        }
        assert_eq!(statuses[0], STATUS_TRACKING);
        assert!(statuses.contains(&STATUS_IMPENDING_BREAKLOCK));
        assert!(statuses.contains(&STATUS_BREAKLOCK), "{statuses:?}");
        // Tracking until the target reaches the frame's edge (frame 38 or so).
        assert!(
            statuses[..35].iter().all(|s| *s == STATUS_TRACKING),
            "{statuses:?}"
        );
        // After the breaklock it searches again at the centre.
        assert_eq!(*statuses.last().expect("some"), STATUS_SEARCHING);
    }

    #[test]
    fn tracks_black_on_a_cold_target_and_ignores_flat_gates() {
        let mut t = Tracker::new(FRAME);
        let gate = t.gate(FRAME);
        let flat = vec![20.0; (gate[2] * gate[3]) as usize];
        t.update(gate, &flat, FRAME, false);
        assert_eq!(t.status, STATUS_SEARCHING);
        let mut cold = flat.clone();
        let w = gate[2] as usize;
        for y in 8..12 {
            for x in 3..7 {
                cold[y * w + x] = 10.0;
            }
        }
        t.update(gate, &cold, FRAME, false);
        assert_eq!(
            t.status, STATUS_SEARCHING,
            "a cold blob is no target tracking white"
        );
        t.update(gate, &cold, FRAME, true);
        assert_eq!(t.status, STATUS_TRACKING);
        let c = t.target_px.expect("target");
        assert!((c[0] - (f64::from(gate[0]) + 5.0)).abs() < 0.01, "{c:?}");
        // A wrong-sized patch is no target.
        t.update(gate, &flat[..3], FRAME, true);
        assert_eq!(t.status, STATUS_IMPENDING_BREAKLOCK);
    }
}
