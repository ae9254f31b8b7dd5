// The frame's tone map: pre-exposed linear radiance (the HDR scene target), times the eye's
// adaptation to the view, to display values.
// Below 10 lux the colour shifts toward the scotopic blue-grey (rods see no colour; the
// blue-shift of H. W. Jensen et al., "A Night Rendering", 2000); then the ACES filmic curve
// (K. Narkowicz's fit, 2015) per channel; the sRGB curve is applied here when the target is
// not an sRGB format (the hardware encodes sRGB targets).

@group(1) @binding(0) var scene: texture_2d<f32>;
// The eye's adaptation to the view (adaptation.rs): x the log2 factor on the pre-exposed scene.
struct Adapted {
    // x the log2 factor (visible); a sensor view's gain window (low, high) radiance.
    state: vec4<f32>,
    // A sensor view's histogram range (x, y) and equalisation weight (z).
    range: vec4<f32>,
    // The equalised grey at each of the 64 bins' tops.
    equalised: array<vec4<f32>, 16>,
};
@group(1) @binding(1) var<uniform> adaptation: Adapted;

struct ToneOut {
    @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> ToneOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: ToneOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    return out;
}

fn aces(x: vec3<f32>) -> vec3<f32> {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

fn srgb_decode(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

// A hash of two integers to [0, 1) (PCG-style mixing).
fn sensor_hash(a: u32, b: u32) -> f32 {
    var h = a * 747796405u + b * 2891336453u + 277803737u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    return f32(h) / 4294967296.0;
}

// Band radiance of a pixel, clamped inside the frame (NaN as 0).
fn sensor_radiance(p: vec2<i32>) -> f32 {
    let dims = vec2<i32>(textureDimensions(scene));
    let l = textureLoad(scene, clamp(p, vec2<i32>(0), dims - 1), 0).r;
    return select(l, 0.0, l != l);
}

// The thermal sensor's display (sensor.rs, cig_scene::thermal): optics blur, line dropout,
// temporal and fixed-pattern noise of the detector, then the gain window (automatic,
// adaptation.rs, or manual) to grey, the polarity and the display's colour. Returns display
// values (0..1, sRGB-encoded grey).
fn sensor_display(pixel: vec2<f32>) -> vec3<f32> {
    var p = vec2<i32>(pixel);
    let frame = u32(g.sensor_display2.z);
    // A dropped line repeats the line above.
    if (g.sensor_display2.y > 0.5 && p.y > 0 && sensor_hash(u32(p.y), frame) < 0.015) {
        p.y -= 1;
    }
    let sigma = g.sensor_display2.x;
    var l = sensor_radiance(p);
    if (sigma > 0.05) {
        var sum = 0.0;
        var weight = 0.0;
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let w = exp(-f32(dx * dx + dy * dy) / (2.0 * sigma * sigma));
                sum += w * sensor_radiance(p + vec2<i32>(dx, dy));
                weight += w;
            }
        }
        l = sum / weight;
    }
    // Temporal noise: a near-Gaussian from four uniforms; fixed pattern: per column and pixel.
    let px = u32(p.x) + 65536u * u32(p.y);
    let u = sensor_hash(px, frame * 4u) + sensor_hash(px, frame * 4u + 1u)
        + sensor_hash(px, frame * 4u + 2u) + sensor_hash(px, frame * 4u + 3u) - 2.0;
    let fixed_pattern = (0.7 * (sensor_hash(u32(p.x), 99991u) - 0.5)
        + 0.3 * (sensor_hash(px, 77773u) - 0.5)) * 3.46;
    l += g.sensor_display.z * (u * 1.732 + g.sensor_display.w * fixed_pattern);
    let lo = adaptation.state.x;
    let hi = max(adaptation.state.y, lo + 1e-6);
    var grey = clamp((l - lo) / (hi - lo), 0.0, 1.0);
    // Plateau histogram equalisation, blended in (adaptation.rs): linear between bins' tops.
    let weight = adaptation.range.z;
    if (weight > 0.0) {
        let x = clamp((l - adaptation.range.x) / max(adaptation.range.y - adaptation.range.x, 1e-6), 0.0, 1.0) * 64.0;
        let i = min(u32(floor(x)), 63u);
        var before = 0.0;
        if (i > 0u) {
            before = adaptation.equalised[(i - 1u) / 4u][(i - 1u) % 4u];
        }
        let top = adaptation.equalised[i / 4u][i % 4u];
        grey = mix(grey, mix(before, top, x - f32(i)), weight);
    }
    if (g.sensor_display.x > 0.5) {
        grey = 1.0 - grey;
    }
    if (g.sensor_display.y > 0.5 && g.sensor_display.y < 1.5) {
        // A green phosphor (P43-like).
        return vec3<f32>(0.28, 1.0, 0.38) * grey;
    }
    return vec3<f32>(grey);
}

// A near-Gaussian (mean 0, sigma 1) from four uniforms of a pixel and a frame.
fn nvg_normal(px: u32, seed: u32) -> f32 {
    let u = sensor_hash(px, seed * 4u) + sensor_hash(px, seed * 4u + 1u)
        + sensor_hash(px, seed * 4u + 2u) + sensor_hash(px, seed * 4u + 3u) - 2.0;
    return u * 1.732;
}

// A Poisson count of mean `mean`: Knuth's product of uniforms below 4 (at most 20 draws), the
// rounded normal law above.
fn nvg_poisson(mean: f32, px: u32, frame: u32) -> f32 {
    if (mean >= 4.0) {
        return max(floor(mean + sqrt(mean) * nvg_normal(px, frame * 2u) + 0.5), 0.0);
    }
    let limit = exp(-mean);
    var p = 1.0;
    var k = 0.0;
    for (var i = 0u; i < 20u; i++) {
        p *= sensor_hash(px, frame * 64u + i + 7u);
        if (p <= limit) {
            break;
        }
        k += 1.0;
    }
    return k;
}

// The night-vision display (cig_scene::nvg): the tube's blur, the photoelectrons a pixel
// catches this frame (Poisson) and the microchannel plate's gain spread, the automatic
// brightness control's gain (adaptation.rs), the phosphor's saturation and colour, and the
// goggle's circular field in a black surround. Returns display values (linear).
fn nvg_display(pixel: vec2<f32>) -> vec3<f32> {
    let p = vec2<i32>(pixel);
    let frame = u32(g.sensor_display2.z);
    let sigma = g.nvg2.w;
    var v = min(sensor_radiance(p), 65504.0);
    if (sigma > 0.3) {
        var sum = 0.0;
        var weight = 0.0;
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let w = exp(-f32(dx * dx + dy * dy) / (2.0 * sigma * sigma));
                sum += w * min(sensor_radiance(p + vec2<i32>(dx, dy)), 65504.0);
                weight += w;
            }
        }
        v = sum / weight;
    }
    if (g.nvg3.x > 0.5) {
        let px = u32(p.x) + 65536u * u32(p.y);
        let per_unit = max(g.nvg.y, 1e-20);
        let electrons = nvg_poisson(v * per_unit, px, frame);
        let signal = max(electrons + sqrt(electrons * g.nvg.z) * nvg_normal(px, frame * 2u + 1u), 0.0);
        v = signal / per_unit;
    }
    let b = v * exp2(adaptation.state.x);
    var out = 1.0 - exp(-b);
    // The goggle's circular field: the pixel's angle from the view's axis.
    let dims = vec2<f32>(textureDimensions(scene));
    let t = g.tangents;
    let x_tan = mix(-t.x, t.y, pixel.x / dims.x);
    let y_tan = mix(t.w, -t.z, pixel.y / dims.y);
    let r_tan = length(vec2<f32>(x_tan, y_tan));
    let inside = clamp((g.nvg.w - r_tan) * g.flags.w + 0.5, 0.0, 1.0);
    // The tube's edge is a little dimmer than its centre.
    let edge = r_tan / max(g.nvg.w, 1e-6);
    out *= inside * (1.0 - 0.12 * edge * edge);
    return g.nvg2.xyz * out;
}

@fragment
fn fs_main(in: ToneOut) -> @location(0) vec4<f32> {
    if (g.nvg.x > 0.5) {
        var shown = nvg_display(in.clip.xy);
        if (g.tonemap.x > 0.5) {
            shown = srgb_encode(shown);
        }
        return vec4<f32>(shown, 1.0);
    }
    if (g.sensor.x > 0.5) {
        // Display values straight to the target (decoded where the hardware encodes sRGB).
        var shown = sensor_display(in.clip.xy);
        if (g.tonemap.x < 0.5) {
            shown = srgb_decode(shown);
        }
        return vec4<f32>(shown, 1.0);
    }
    var c = textureLoad(scene, vec2<i32>(in.clip.xy), 0).rgb;
    // A NaN or infinity from any pass becomes black or the brightest value, on every GPU.
    c = select(c, vec3<f32>(0.0), c != c);
    c = clamp(c, vec3<f32>(0.0), vec3<f32>(65504.0));
    var out: vec3<f32>;
    if (g.flags.z > 0.5) {
        // Keyed test frames: linear radiance, clamped.
        out = min(c, vec3<f32>(1.0));
    } else {
        c *= exp2(adaptation.state.x);
        let s = g.tonemap.y;
        if (s > 0.0) {
            // Rod response over the sRGB primaries (peak near 507 nm), shown blue-grey.
            let rods = dot(c, vec3<f32>(0.06, 0.55, 0.39));
            c = mix(c, rods * vec3<f32>(0.80, 0.95, 1.30), s);
        }
        out = aces(c);
    }
    if (g.tonemap.x > 0.5) {
        out = srgb_encode(out);
    }
    return vec4<f32>(out, 1.0);
}
