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
};

const BINS: u32 = 64u;
const LOG2_MIN: f32 = -20.0;
const BIN_WIDTH: f32 = 0.5;

@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> bins: array<atomic<u32>, 64>;
@group(0) @binding(2) var<uniform> params: AdaptParams;
// Per view slot: x adapted log2 factor, y target log2 factor, z trimmed mean log2 luminance,
// w 1 once adapted.
@group(0) @binding(3) var<storage, read_write> state: array<vec4<f32>, 16>;

var<workgroup> local_bins: array<atomic<u32>, 64>;

fn bin_of(c: vec3<f32>) -> u32 {
    let y = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
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
        atomicAdd(&local_bins[bin_of(c)], 1u);
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
    if (dt >= 0.0 && params.shares.w > 0.5 && previous.w > 0.5) {
        // Lower factor: the view got brighter (light adaptation, fast); else dark adaptation.
        let tau = select(params.slot.z, params.slot.y, target_log2 < previous.x);
        adapted = previous.x + (target_log2 - previous.x) * (1.0 - exp(-dt / max(tau, 1e-3)));
    }
    state[slot] = vec4<f32>(adapted, target_log2, mean, 1.0);
}
