// Cloud layers (see clouds.rs): a full-screen pass that marches each view ray's segment inside
// every layer's slab, limited by the scene's depth, and darkens terrain in the clouds' shade.
// Drawn at half resolution into a float target: rgb the clouds' pre-exposed in-scattered
// radiance, alpha what the scene behind keeps (transmittance times shade); `fs_composite`
// upsamples it onto the frame with blending `src + dst * src_alpha`.

struct CloudLayerGpu {
    // x, y: the eye's noise coordinates (texels); z: base relative to the eye (m); w: thickness.
    place: vec4<f32>,
    // x: texels per metre east, y: texels per metre north, z: extinction (1/m), w: coverage.
    params: vec4<f32>,
    // x: 1 heaped, 0 sheet; y: width of the cover ramp; z: channel; w: unused.
    shape: vec4<f32>,
};

struct Clouds {
    // Local east at the eye (ECEF); w: layer count.
    east: vec4<f32>,
    // Local north at the eye (ECEF); w: farthest distance marched (m).
    north: vec4<f32>,
    layers: array<CloudLayerGpu, 4>,
};

@group(0) @binding(1) var<uniform> c: Clouds;
@group(0) @binding(2) var noise: texture_2d<f32>;
@group(0) @binding(3) var noise_sampler: sampler;
@group(0) @binding(4) var scene_depth: texture_multisampled_2d<f32>;

const EARTH_R: f32 = 6371000.0;
// Samples per layer: one per half thickness of path, 3 to 8.
const MIN_STEPS: f32 = 3.0;
const MAX_STEPS: f32 = 8.0;

struct CloudOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> CloudOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: CloudOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    out.ndc = xy;
    return out;
}

// Cover strength of noise value u (clouds.rs `cover_strength`).
fn cover(u: f32, coverage: f32, width: f32) -> f32 {
    let threshold = 1.0 - coverage;
    if (width <= 1e-6) {
        return select(0.0, 1.0, u >= threshold);
    }
    return clamp((u - threshold) / width, 0.0, 1.0);
}

// Height strength of a heaped column (clouds.rs `heap_height`).
fn heap_height(u: f32, coverage: f32) -> f32 {
    return clamp((u - (1.0 - coverage)) / max(coverage, 1e-6), 0.0, 1.0);
}

// Extinction for noise value u at zn in the slab (clouds.rs `profile_per_m`).
fn profile(layer: CloudLayerGpu, u: f32, zn: f32) -> f32 {
    let w = cover(u, layer.params.w, layer.shape.y);
    if (zn < 0.0 || zn > 1.0 || w <= 0.0) {
        return 0.0;
    }
    var fill: f32;
    if (layer.shape.x > 0.5) {
        fill = clamp((sqrt(heap_height(u, layer.params.w)) - zn) * 10.0, 0.0, 1.0);
    } else {
        fill = clamp(min(zn, 1.0 - zn) * 10.0, 0.0, 1.0);
    }
    return layer.params.z * w * fill;
}

// Fraction of the slab's thickness a column of noise value u fills (the profile's integral).
fn column_fill(layer: CloudLayerGpu, u: f32) -> f32 {
    if (layer.shape.x > 0.5) {
        let top = sqrt(heap_height(u, layer.params.w));
        if (top >= 0.1) {
            return top - 0.05;
        }
        return 5.0 * top * top;
    }
    return 0.9;
}

// The layer's uniform noise value over an eye-relative point.
fn noise_at(index: i32, layer: CloudLayerGpu, rel: vec3<f32>) -> f32 {
    let coords = layer.place.xy + vec2<f32>(
        dot(rel, c.east.xyz) * layer.params.x,
        dot(rel, c.north.xyz) * layer.params.y,
    );
    let texel = textureSampleLevel(noise, noise_sampler, coords / 256.0, 0.0);
    return texel[index];
}

// Roots (smaller, larger) of height_above_eye(dir * s) = h along a ray rising `dz`: the
// parabola s dz - s^2 (1 - dz^2) / 2R = h; z is 1 when they exist.
fn height_roots(dz: f32, h: f32) -> vec3<f32> {
    let a = max((1.0 - dz * dz) / (2.0 * EARTH_R), 1e-12);
    let b = -dz;
    let d = b * b - 4.0 * a * h;
    if (d < 0.0) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    var sgn = 1.0;
    if (b < 0.0) {
        sgn = -1.0;
    }
    let q = -0.5 * (b + sgn * sqrt(d));
    var r1 = q / a;
    var r2 = h / q;
    if (abs(q) < 1e-20) {
        r2 = 0.0;
    }
    return vec3<f32>(min(r1, r2), max(r1, r2), 1.0);
}

// The nearest part of the ray (s >= 0) inside the slab between heights lo and hi above the eye.
fn slab_segment(dz: f32, lo: f32, hi: f32) -> vec2<f32> {
    let bottom = height_roots(dz, lo);
    if (bottom.z < 0.5) {
        return vec2<f32>(0.0, -1.0);
    }
    let start = max(bottom.x, 0.0);
    let end = bottom.y;
    if (end <= start) {
        return vec2<f32>(0.0, -1.0);
    }
    let top = height_roots(dz, hi);
    if (top.z < 0.5 || top.y <= start || top.x >= end) {
        return vec2<f32>(start, end);
    }
    if (top.x > start) {
        return vec2<f32>(start, min(end, top.x));
    }
    return vec2<f32>(max(start, top.y), end);
}

fn henyey_greenstein(cos_theta: f32, g_: f32) -> f32 {
    // Normalised so that isotropic scattering is 1 (the phase function times 4 pi).
    let d = 1.0 + g_ * g_ - 2.0 * g_ * cos_theta;
    return (1.0 - g_ * g_) / (d * sqrt(d));
}

fn luminance(c_: vec3<f32>) -> f32 {
    return dot(c_, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// A uniform value in [0, 1) from a pixel (the PCG hash of M. Jarzynski and M. Olano, "Hash
// Functions for GPU Rendering", JCGT 2020, on both coordinates).
fn pixel_hash(p: vec2<u32>) -> f32 {
    var v = p.x * 1664525u + p.y * 747796405u + 1013904223u;
    v = v * 747796405u + 2891336453u;
    var w = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    w = (w >> 22u) ^ w;
    return f32(w >> 8u) / 16777216.0;
}

@fragment
fn fs_main(in: CloudOut) -> @location(0) vec4<f32> {
    // This pass runs at half resolution: the scene pixel under the centre of this one.
    let pixel = min(vec2<i32>(in.clip.xy * 2.0), vec2<i32>(textureDimensions(scene_depth)) - 1);
    let t = g.tangents;
    let x_tan = mix(-t.x, t.y, in.ndc.x * 0.5 + 0.5);
    let y_tan = mix(-t.z, t.w, in.ndc.y * 0.5 + 0.5);
    let dir = normalize(g.cam_forward.xyz + g.cam_right.xyz * x_tan + g.cam_up.xyz * y_tan);
    let up = g.eye_up.xyz;
    let dz = dot(dir, up);
    let depth = textureLoad(scene_depth, pixel, 0).x;
    var scene_m = 1e12;
    if (depth > 0.0) {
        // Reversed-Z infinite projection: depth = near / distance along the view axis.
        scene_m = NEAR_PLANE_M / depth / max(dot(dir, g.cam_forward.xyz), 1e-4);
    }
    let far_m = c.north.w;
    let count = i32(c.east.w + 0.5);
    let sun = g.sun_dir.xyz;
    let sun_up = dot(sun, up);
    let cos_sun = dot(dir, sun);
    let phase = 0.6 * henyey_greenstein(cos_sun, 0.6) + 0.4 * henyey_greenstein(cos_sun, -0.2);
    // The moon is a second light, as in `lit` (common.wgsl): the same phase and self-shadow.
    let moon = g.moon_dir.xyz;
    let moon_up = dot(moon, up);
    let moon_lit = luminance(g.moon_colour.rgb) > 0.0 && moon_up > -0.05;
    let cos_moon = dot(dir, moon);
    let moon_phase = 0.6 * henyey_greenstein(cos_moon, 0.6) + 0.4 * henyey_greenstein(cos_moon, -0.2);

    // Each pixel's samples start at its own fraction of a step, from a hash of the pixel (white
    // noise, so no periodic dot or checker pattern: interleaved gradient noise showed one at
    // half resolution): the slices of a fixed-step march become fine grain instead of bands,
    // which the composite's filter smooths.
    let jitter = pixel_hash(vec2<u32>(in.clip.xy));
    var transmittance = 1.0;
    var radiance = vec3<f32>(0.0);
    var distance_sum = 0.0;
    var weight_sum = 0.0;
    // Layers come lowest first: a rising ray meets them in that order, a falling one in the
    // reverse order (front-to-back compositing needs the nearer layer first).
    for (var j = 0; j < count; j++) {
        let i = select(count - 1 - j, j, dz >= 0.0);
        let layer = c.layers[i];
        let seg = slab_segment(dz, layer.place.z, layer.place.z + layer.place.w);
        let s0 = seg.x;
        let s1 = min(seg.y, min(scene_m, far_m));
        if (s1 <= s0 || transmittance < 0.01) {
            continue;
        }
        let steps = i32(clamp(ceil(2.0 * (s1 - s0) / layer.place.w), MIN_STEPS, MAX_STEPS));
        let ds = (s1 - s0) / f32(steps);
        for (var k = 0; k < steps; k++) {
            if (transmittance < 0.01) {
                break;
            }
            let s = s0 + (f32(k) + jitter) * ds;
            let rel = dir * s;
            let zn = (height_above_eye(rel) - layer.place.z) / layer.place.w;
            let sigma = profile(layer, noise_at(i, layer, rel), zn);
            if (sigma <= 0.0) {
                continue;
            }
            // Self-shadow: the sun's light crosses the cloud above the part of the step that
            // is seen (the step's start plus the mean free path, at most half the step), so a
            // long step's brightness does not depend on where its sample fell; a floor stands
            // in for multiple scattering.
            let seen = s0 + f32(k) * ds + min(1.0 / sigma, 0.5 * ds);
            let zn_seen = clamp((height_above_eye(dir * seen) - layer.place.z) / layer.place.w, 0.0, 1.0);
            let to_top_m = (1.0 - zn_seen) * layer.place.w / max(sun_up, 0.1);
            let direct = max(exp(-sigma * to_top_m), 0.25 * exp(-0.1 * sigma * to_top_m));
            var light = g.sun_colour.rgb * phase * direct + g.ambient.rgb * (0.7 + 0.3 * zn_seen);
            var sigma_seen = sigma;
            if (g.sensor.x > 0.5) {
                // A thermal sensor: the cloud's droplets absorb and emit at its temperature
                // (sensor.rs), with 0.7 of their visible extinction.
                light = vec3<f32>(g.sensor_display2.w);
                sigma_seen = 0.7 * sigma;
            } else if (moon_lit) {
                let to_top_moon_m = (1.0 - zn_seen) * layer.place.w / max(moon_up, 0.1);
                let moon_direct = max(exp(-sigma * to_top_moon_m), 0.25 * exp(-0.1 * sigma * to_top_moon_m));
                light += g.moon_colour.rgb * moon_phase * moon_direct;
            }
            let a = 1.0 - exp(-sigma_seen * ds);
            radiance += transmittance * a * light;
            distance_sum += transmittance * a * s;
            weight_sum += transmittance * a;
            transmittance *= 1.0 - a;
        }
    }
    // Clouds are fogged as the terrain is, at their mean distance, and fade out before the
    // farthest distance marched.
    var keep = 1.0;
    var fogged = radiance;
    if (weight_sum > 1e-6) {
        let mean_m = distance_sum / weight_sum;
        let f = fog_factor(mean_m);
        if (g.sensor.x < 0.5) {
            fogged = f * radiance + (1.0 - f) * (1.0 - transmittance) * g.fog_colour.rgb;
        }
        keep = 1.0 - smoothstep(0.7 * far_m, far_m, mean_m);
    }
    var behind = 1.0 - keep * (1.0 - transmittance);
    if (g.sensor.x > 0.5) {
        // Band radiance, not light: no exposure, no shade (the surfaces' temperatures already
        // have the cloud cover's shade).
        return vec4<f32>(fogged * keep, behind);
    }

    // Shade on the ground: the sun's ray from the terrain point crosses each layer above it at
    // mid-height; the slant column there dims the sun's share of the pixel's light.
    if (depth > 0.0 && sun_up > 0.01) {
        let point = dir * scene_m;
        let point_h = height_above_eye(point);
        var shade = 1.0;
        for (var i = 0; i < count; i++) {
            let layer = c.layers[i];
            let rise = layer.place.z + 0.5 * layer.place.w - point_h;
            if (rise <= 0.0) {
                continue;
            }
            let q = point + sun * (rise / sun_up);
            let u = noise_at(i, layer, q);
            let w = cover(u, layer.params.w, layer.shape.y);
            let tau = layer.params.z * w * column_fill(layer, u) * layer.place.w / sun_up;
            shade *= exp(-tau);
        }
        let direct = luminance(g.sun_colour.rgb) * sun_up;
        let share = direct / max(direct + luminance(g.ambient.rgb), 1e-6);
        behind *= mix(1.0, shade, share * fog_factor(scene_m));
    }
    return vec4<f32>(exposed(fogged * keep), behind);
}

