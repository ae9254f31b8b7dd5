// The sea surface (sea.rs): a polar grid around the eye displaced by the wave cascades and
// shaded with Fresnel reflection of the sky, LEAN-mapped sun glitter, the water body and foam.

struct SeaUniform {
    east: vec4<f32>,
    north: vec4<f32>,
    params: vec4<f32>,
    // The eye's east (xy) and north (zw) in the sea plane's axes.
    axes: vec4<f32>,
    cascades: array<vec4<f32>, 4>,
    shade: vec4<f32>,
    water: vec4<f32>,
};

@group(0) @binding(1) var<uniform> sea: SeaUniform;
@group(0) @binding(2) var sea_displacement: texture_2d_array<f32>;
@group(0) @binding(3) var sea_slopes: texture_2d_array<f32>;
@group(0) @binding(4) var sea_gradient: texture_2d_array<f32>;
@group(0) @binding(5) var sea_sampler: sampler;

struct SeaOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    // The undisplaced place in the sea's plane relative to the eye (east, north), metres.
    @location(1) local: vec2<f32>,
};

fn ring_radius(i: u32) -> f32 {
    if (i == 0u) {
        return 0.0;
    }
    let rings = sea.east.w;
    let t = (f32(i) - 1.0) / max(rings - 1.0, 1.0);
    return sea.params.w * pow(sea.params.z / sea.params.w, t);
}

// A vector in the eye's east and north expressed in the sea plane's axes.
fn to_plane(v: vec2<f32>) -> vec2<f32> {
    return v.x * sea.axes.xy + v.y * sea.axes.zw;
}

// A vector in the sea plane's axes expressed in the eye's east and north.
fn from_plane(v: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(dot(v, sea.axes.xy), dot(v, sea.axes.zw));
}

// Texture coordinates of cascade `c` at `local` (eye east and north, metres): the grid's
// point i lies at i texels, the texel's centre half a texel further.
fn cascade_uv(c: u32, local: vec2<f32>) -> vec2<f32> {
    let k = sea.cascades[c];
    return k.xy + (to_plane(local) + vec2<f32>(0.5 * k.w)) / k.z;
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> SeaOut {
    // Vertices row by row: (segments + 1) a ring, the last repeating the first's azimuth.
    let segments = u32(sea.north.w);
    let ring = index / (segments + 1u);
    let segment = index % (segments + 1u);
    let r = ring_radius(ring);
    let azimuth = 6.2831853 * f32(segment) / f32(segments);
    let local = r * vec2<f32>(cos(azimuth), sin(azimuth));
    // The grid's spacing here: the level whose texels match it.
    let spacing = max(ring_radius(ring + 1u) - r, r * 6.2831853 / f32(segments));
    var d = vec3<f32>(0.0);
    let count = u32(sea.shade.z);
    for (var c = 0u; c < count; c++) {
        let lod = clamp(log2(max(spacing, 1e-3) / sea.cascades[c].w), 0.0, sea.shade.w - 1.0);
        d += textureSampleLevel(sea_displacement, sea_sampler, cascade_uv(c, local), c, lod).xyz;
    }
    let p = local + from_plane(d.yz);
    // The round earth: the surface drops below the eye's horizontal plane by d^2 / 2R.
    let drop = dot(p, p) / (2.0 * sea.params.y);
    let up = g.eye_up.xyz;
    let rel = sea.east.xyz * p.x + sea.north.xyz * p.y + up * (sea.params.x + d.x - drop);
    var out: SeaOut;
    out.clip = g.view_proj * vec4<f32>(rel, 1.0);
    out.rel = rel;
    out.local = local;
    return out;
}

// The sky (pre-exposed) reflected along `dir`, never below the horizon.
fn reflected_sky(dir: vec3<f32>) -> vec3<f32> {
    let up = g.eye_up.xyz;
    let lifted = normalize(dir + up * max(0.01 - dot(dir, up), 0.0));
    if (physical_sky()) {
        return sky_radiance(lifted);
    }
    let t = clamp(dot(lifted, up), 0.0, 1.0);
    return exposed(mix(g.sky_horizon.rgb, g.sky_zenith.rgb, sqrt(t)));
}

// Schlick's Fresnel reflectance of water (F0 = 0.02).
fn fresnel(cos_theta: f32) -> f32 {
    let m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    let m2 = m * m;
    return 0.02 + 0.98 * m2 * m2 * m;
}

// Glint of a light of illuminance `e` (towards `l`) on slopes of mean `n` and mean square
// slope `s2` (both axes), seen along `v`: Cox and Munk's π L = π E F p / (4 μv μn^4).
fn glint(e: vec3<f32>, l: vec3<f32>, v: vec3<f32>, n: vec3<f32>, s2: f32) -> vec3<f32> {
    let up = g.eye_up.xyz;
    if (dot(l, up) <= 0.0) {
        return vec3<f32>(0.0);
    }
    let h = normalize(l + v);
    let mu_n = max(dot(h, n), 1e-3);
    let tan2 = (1.0 - mu_n * mu_n) / (mu_n * mu_n);
    let mu_v = max(dot(v, n), 0.02);
    let p_pi = exp(-tan2 / s2) / s2;
    return e * (fresnel(dot(v, h)) * p_pi / (4.0 * mu_v * mu_n * mu_n * mu_n * mu_n));
}

@fragment
fn fs_main(in: SeaOut) -> @location(0) vec4<f32> {
    let count = u32(sea.shade.z);
    var slope = vec2<f32>(0.0);
    var variance = sea.shade.x;
    var grad = vec3<f32>(0.0);
    for (var c = 0u; c < count; c++) {
        let uv = cascade_uv(c, in.local);
        let s = textureSample(sea_slopes, sea_sampler, uv, c);
        slope += from_plane(s.xy);
        variance += max(s.z - s.x * s.x, 0.0) + max(s.w - s.y * s.y, 0.0);
        grad += textureSample(sea_gradient, sea_sampler, uv, c).xyz;
    }
    let up = g.eye_up.xyz;
    let n = normalize(up - sea.east.xyz * slope.x - sea.north.xyz * slope.y);
    let distance_m = max(length(in.rel), 1e-3);
    let v = -in.rel / distance_m;
    let cos_v = max(dot(n, v), 0.0);
    let f = fresnel(cos_v);
    let r = reflect(-v, n);
    // Whitecaps where the surface's Jacobian folds.
    let jacobian = (1.0 + grad.x) * (1.0 + grad.y) - grad.z * grad.z;
    let foam = 1.0 - smoothstep(sea.shade.y - 0.2, sea.shade.y + 0.05, jacobian);
    let s2 = max(variance, 1e-4);
    let light = glint(g.sun_colour.rgb, g.sun_dir.xyz, v, n, s2)
        + glint(g.moon_colour.rgb, g.moon_dir.xyz, v, n, s2);
    // The water body: light scattered up from below, leaving through the surface.
    let body = lit_at(sea.water.rgb, up, in.rel) * (1.0 - f);
    let foam_colour = lit_at(vec3<f32>(0.75), n, in.rel);
    let surface = exposed(mix(light + body, foam_colour, foam)) + reflected_sky(r) * (f * (1.0 - foam));
    return vec4<f32>(apply_atmosphere_exposed(surface, in.rel), 1.0);
}
