// Eye adaptation (see adaptation.rs): a histogram of the resolved scene's log2 luminance, then
// one invocation turns it into the view's adapted exposure factor.

struct AdaptParams {
    // x: log2 of the key the view's mean should show (pre-exposed units), y: seconds since the
    // view's last frame (< 0: settle at once), z: lowest and w: highest log2 factor allowed.
    key: vec4<f32>,
    // x: view slot, y: time constant toward light (s), z: toward dark (s), w: log2 of the
    // highest pre-exposed luminance the brightest share may reach (below the tone map's knee).
    slot: vec4<f32>,
    // x: low and y: high fraction of the trimmed mean, z: the bright share's fraction, w: 1 when
    // the state of this slot is valid (a frame was adapted before).
    shares: vec4<f32>,
    // x: 1 for a thermal sensor view (the histogram bins its band radiance, sensor_bin_of);
    // y: 1 for a night-vision view (the red channel's signal, not luminance).
    mode: vec4<f32>,
};

const BINS: u32 = 64u;
const LOG2_MIN: f32 = -20.0;
const BIN_WIDTH: f32 = 0.5;

@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> bins: array<atomic<u32>, 64>;
@group(0) @binding(2) var<uniform> params: AdaptParams;
// Per view slot: x adapted log2 factor, y target log2 factor, z trimmed mean log2 luminance,
// w 1 once adapted by the eye (3 by an intensifier's control, 2 a thermal sensor's window).
@group(0) @binding(3) var<storage, read_write> state: array<vec4<f32>, 16>;

var<workgroup> local_bins: array<atomic<u32>, 64>;
// A sensor view's histogram range (x, y) and equalisation weight (z), then the equalised grey
// at each bin's top (64 values in 16 vec4s).
@group(0) @binding(4) var<storage, read_write> equalised: array<vec4<f32>, 17>;

fn bin_of(c: vec3<f32>) -> u32 {
    // A night-vision view (mode.y 1) holds its signal in the red channel.
    let y = select(dot(c, vec3<f32>(0.2126, 0.7152, 0.0722)), c.r, params.mode.y > 0.5);
    // NaN and negative values count as black.
    let l = log2(max(select(y, 0.0, y != y), 1e-12));
    return u32(clamp(floor((l - LOG2_MIN) / BIN_WIDTH), 0.0, f32(BINS - 1u)));
}

// Every second pixel in each direction (a quarter of the frame) is enough for a mean.
@compute @workgroup_size(16, 16)
fn histogram(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    if (li < BINS) {
        atomicStore(&local_bins[li], 0u);
    }
    workgroupBarrier();
    let dims = textureDimensions(scene);
    let p = gid.xy * 2u;
    if (p.x < dims.x && p.y < dims.y) {
        let c = textureLoad(scene, vec2<i32>(p), 0).rgb;
        atomicAdd(&local_bins[select(bin_of(c), sensor_bin_of(c.r), params.mode.x > 0.5)], 1u);
    }
    workgroupBarrier();
    if (li < BINS) {
        let n = atomicLoad(&local_bins[li]);
        if (n > 0u) {
            atomicAdd(&bins[li], n);
        }
    }
}

fn bin_centre(i: u32) -> f32 {
    return LOG2_MIN + (f32(i) + 0.5) * BIN_WIDTH;
}

@compute @workgroup_size(1)
fn adapt() {
    var total = 0u;
    for (var i = 0u; i < BINS; i++) {
        total += atomicLoad(&bins[i]);
    }
    let slot = u32(params.slot.x);
    if (total == 0u) {
        return;
    }
    let n = f32(total);
    let lo = params.shares.x * n;
    let hi = params.shares.y * n;
    let bright_at = params.shares.z * n;
    // The trimmed mean of log2 luminance between the low and high shares (the sun's disc and
    // the darkest shadows do not count), and the luminance below which the bright share lies.
    var below = 0.0;
    var sum = 0.0;
    var weight = 0.0;
    var bright = bin_centre(BINS - 1u);
    var bright_found = false;
    for (var i = 0u; i < BINS; i++) {
        let count = f32(atomicLoad(&bins[i]));
        let take = max(0.0, min(below + count, hi) - max(below, lo));
        sum += take * bin_centre(i);
        weight += take;
        if (!bright_found && below + count >= bright_at) {
            bright = bin_centre(i) + 0.5 * BIN_WIDTH;
            bright_found = true;
        }
        below += count;
    }
    let mean = sum / max(weight, 1.0);
    // Bring the mean to the key, unless that would push the bright share past the knee; always
    // within the bounds set by the natural illuminance.
    let target_log2 = clamp(
        min(params.key.x - mean, params.slot.w - bright),
        params.key.z,
        params.key.w,
    );
    var adapted = target_log2;
    let dt = params.key.y;
    let previous = state[slot];
    // (A state of w 2 is a sensor view's gain window, of w 3 an intensifier's control: the eye
    // (w 1) and the tube never follow each other's state.)
    let tag = select(1.0, 3.0, params.mode.y > 0.5);
    if (dt >= 0.0 && params.shares.w > 0.5 && abs(previous.w - tag) < 0.5) {
        // Lower factor: the view got brighter (light adaptation, fast); else dark adaptation.
        let tau = select(params.slot.z, params.slot.y, target_log2 < previous.x);
        adapted = previous.x + (target_log2 - previous.x) * (1.0 - exp(-dt / max(tau, 1e-3)));
    }
    state[slot] = vec4<f32>(adapted, target_log2, mean, tag);
}

// The thermal sensor's automatic gain (adaptation.rs's encode_sensor): the histogram of band
// radiance (params.mode.x 1), linear between params.key.x and params.key.y, then the window between its
// params.shares.x and params.shares.y shares, at least params.key.w wide, approached with the
// time constant params.slot.y (params.key.z: seconds since the view's last frame; < 0 settles
// at once). The state is (low, high, 0, 2).

fn sensor_bin_of(l: f32) -> u32 {
    let x = (select(l, 0.0, l != l) - params.key.x) / max(params.key.y - params.key.x, 1e-6);
    return u32(clamp(floor(x * f32(BINS)), 0.0, f32(BINS - 1u)));
}

// The radiance below which `share` of the pixels lie (linear inside the bin).
fn sensor_percentile(share: f32, total: f32) -> f32 {
    let want = share * total;
    var below = 0.0;
    let width = (params.key.y - params.key.x) / f32(BINS);
    for (var i = 0u; i < BINS; i++) {
        let count = f32(atomicLoad(&bins[i]));
        if (below + count >= want && count > 0.0) {
            return params.key.x + (f32(i) + (want - below) / count) * width;
        }
        below += count;
    }
    return params.key.y;
}

@compute @workgroup_size(1)
fn sensor_adapt() {
    var total = 0u;
    for (var i = 0u; i < BINS; i++) {
        total += atomicLoad(&bins[i]);
    }
    let slot = u32(params.slot.x);
    if (total == 0u) {
        // Nothing to equalise: no equalisation (not the previous view's curve).
        equalised[0] = vec4<f32>(params.key.x, params.key.y, 0.0, 0.0);
        return;
    }
    var lo = sensor_percentile(params.shares.x, f32(total));
    var hi = sensor_percentile(params.shares.y, f32(total));
    let span = max(hi - lo, params.key.w);
    let mid = 0.5 * (lo + hi);
    lo = mid - 0.5 * span;
    hi = mid + 0.5 * span;
    var window = vec2<f32>(lo, hi);
    let dt = params.key.z;
    let previous = state[slot];
    if (dt >= 0.0 && params.shares.w > 0.5 && abs(previous.w - 2.0) < 0.5) {
        window = previous.xy + (window - previous.xy) * (1.0 - exp(-dt / max(params.slot.y, 1e-3)));
    }
    state[slot] = vec4<f32>(window, 0.0, 2.0);
    // Plateau equalisation: each bin counts at most twice the mean bin, so a large uniform
    // area (the sky, a fire) does not take the grey levels; the cumulative share at each bin's
    // top is the grey there.
    let plateau = max(2.0 * f32(total) / f32(BINS), 1.0);
    var clipped_total = 0.0;
    for (var i = 0u; i < BINS; i++) {
        clipped_total += min(f32(atomicLoad(&bins[i])), plateau);
    }
    equalised[0] = vec4<f32>(params.key.x, params.key.y, params.slot.z, 0.0);
    var below = 0.0;
    for (var v = 0u; v < 16u; v++) {
        var out = vec4<f32>(0.0);
        for (var k = 0u; k < 4u; k++) {
            below += min(f32(atomicLoad(&bins[v * 4u + k])), plateau);
            out[k] = below / max(clipped_total, 1.0);
        }
        equalised[v + 1u] = out;
    }
}
