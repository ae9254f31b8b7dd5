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
    // The water body's colour; w: explicit waves.
    water: vec4<f32>,
    // Per explicit wave (sea.rs): direction in the plane's axes, wave number, phase at the
    // eye; then amplitude and horizontal displacement amplitude.
    waves: array<vec4<f32>, 16>,
    // x: the water's surface temperature (K), y: wakes, z: wave areas.
    thermal: vec4<f32>,
    // Per wave area (sea.rs): centre relative to the eye in the plane's axes, half sizes;
    // cosine and sine of its rotation, corner radius, transition band.
    areas: array<vec4<f32>, 16>,
    // Per wave area: 1 a region's, 2 an entity's.
    area_kinds: array<vec4<f32>, 2>,
    // Per wake (sea.rs): stern relative to the eye and unit course (east, north); speed,
    // length, beam, the arms' half-angle; foam made, its e-folding time.
    wakes: array<vec4<f32>, 24>,
    // Per wake, 14 points of its turbulent wake's centreline from the stern astern (sea.rs):
    // place relative to the eye (east, north), the foam's age (s) and the wake's width (m)
    // there.
    wake_tracks: array<vec4<f32>, 112>,
};

// The ships' wakes at `local` (east, north of the eye, metres), as foam cover 0..1
// (cig_sea::wake): the turbulent wake's white water astern along the stern's track (its
// centreline's pieces, `s` metres along it), a beam wide at the stern and widening as
// s^(1/5), fading as exp(-age / tau); the bow wave's white water
// along the bow's sides; the Kelvin arms' broken crests at the apparent half-angle, decaying
// as (1 + r / L)^(-1/3) from the bow, never outside Kelvin's 19.47 degrees.
fn wake_foam(local: vec2<f32>) -> f32 {
    var foam = 0.0;
    let count = u32(sea.thermal.y);
    for (var w = 0u; w < count; w++) {
        let a = sea.wakes[3u * w];
        let b = sea.wakes[3u * w + 1u];
        let c = sea.wakes[3u * w + 2u];
        let q = local - a.xy;
        let astern = -dot(q, a.zw);
        let across = abs(a.z * q.y - a.w * q.x);
        let speed = max(b.x, 0.1);
        let hull_length = b.y;
        let hull_beam = b.z;
        // The turbulent wake, piece by piece along the centreline (its points' widths
        // precomputed, linear between them).
        let points = u32(c.z);
        for (var k = 0u; k + 1u < points; k++) {
            let p0 = sea.wake_tracks[14u * w + k];
            let p1 = sea.wake_tracks[14u * w + k + 1u];
            let piece = p1.xy - p0.xy;
            let length2 = dot(piece, piece);
            if (length2 < 1e-4) {
                continue;
            }
            let rel = local - p0.xy;
            let t_raw = dot(rel, piece) / length2;
            // Nothing ahead of the stern.
            if (k == 0u && t_raw < 0.0) {
                continue;
            }
            let t = clamp(t_raw, 0.0, 1.0);
            let off = rel - piece * t;
            let off2 = dot(off, off);
            let width = mix(p0.w, p1.w, t);
            if (off2 >= 0.25 * width * width) {
                continue;
            }
            let x = 2.0 * sqrt(off2) / width;
            let band = (1.0 - x * x) * (1.0 - x * x);
            // Broken white water behind the stern, then the lasting trail.
            let age = mix(p0.z, p1.z, t);
            foam = max(foam, c.x * (0.5 * exp(-age / 15.0) + 0.45 * exp(-age / c.y)) * band);
        }
        // The bow wave: white water hugging the fore body, as long as the hull's fore third.
        let from_bow = hull_length + astern;
        if (from_bow > -0.02 * hull_length && from_bow < 0.35 * hull_length) {
            let side = across - 0.5 * hull_beam * clamp(from_bow / (0.2 * hull_length), 0.2, 1.0);
            let spread = 0.08 * hull_beam + 0.1 * from_bow;
            foam = max(foam, 0.9 * c.x * exp(-side * side / (spread * spread)) * (1.0 - from_bow / (0.35 * hull_length)));
        }
        // The Kelvin arms, from the bow: a narrow band of cusp waves whose crests (a transverse
        // wavelength 2 pi U^2 / g apart along the arm) break white.
        if (from_bow > 0.0) {
            let angle = atan2(across, from_bow);
            if (angle < 0.3398) {
                let d = (angle - b.w) / (0.08 * b.w);
                let crest = pow(0.5 + 0.5 * cos(6.2831853 * from_bow * 9.80665 / (6.2831853 * speed * speed)), 4.0);
                let arm = exp(-d * d) * pow(1.0 + from_bow / hull_length, -1.0 / 3.0);
                foam = max(foam, 0.3 * c.x * arm * crest * exp(-3.0 * from_bow / speed / c.y));
            }
        }
    }
    return clamp(foam, 0.0, 1.0);
}

// The explicit (Gerstner) waves at `local`: height (x), displacement in the plane's axes
// (yz), and in `slopes` their slope (xy, plane axes) and displacement gradient (dxx, dyy,
// dxy) for the shading.
struct Explicit {
    height_displacement: vec3<f32>,
    slope: vec2<f32>,
    gradient: vec3<f32>,
};

// The weight of wave area `i` at `p` (plane axes, from the eye), cig_sea::surface::WaveArea:
// 1 inside its rounded rectangle, smoothstep down to 0 across its transition band.
fn area_weight(i: u32, p: vec2<f32>) -> f32 {
    let a = sea.areas[2u * i];
    let b = sea.areas[2u * i + 1u];
    let d = p - a.xy;
    let q = vec2<f32>(d.x * b.x - d.y * b.y, d.x * b.y + d.y * b.x);
    var radius = b.z;
    if (a.z > 0.0 || a.w > 0.0) {
        radius = min(radius, min(a.z, a.w));
    }
    let e = abs(q) - max(a.zw - vec2<f32>(radius), vec2<f32>(0.0));
    let distance = length(max(e, vec2<f32>(0.0))) + min(max(e.x, e.y), 0.0) - radius;
    if (distance <= 0.0) {
        return 1.0;
    }
    // The band, at least cig_sea::surface::MIN_AREA_BAND_M (sea.rs writes it so).
    let t = clamp(1.0 - distance / b.w, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

fn area_kind(i: u32) -> f32 {
    return sea.area_kinds[i / 4u][i % 4u];
}

fn explicit_waves(local: vec2<f32>) -> Explicit {
    var out = Explicit(vec3<f32>(0.0), vec2<f32>(0.0), vec3<f32>(0.0));
    let p = to_plane(local);
    // How much entities' and regions' areas cover the point: they take precedence.
    var entities = 0.0;
    var regions = 0.0;
    let areas = u32(sea.thermal.z);
    for (var i = 0u; i < areas; i++) {
        let w = area_weight(i, p);
        if (area_kind(i) > 1.5) {
            entities += w;
        } else {
            regions += w;
        }
    }
    entities = min(entities, 1.0);
    regions = min(regions, 1.0);
    let count = u32(sea.water.w);
    for (var w = 0u; w < count; w++) {
        let a = sea.waves[2u * w];
        let b = sea.waves[2u * w + 1u];
        var weight = (1.0 - entities) * (1.0 - regions);
        if (b.z > 0.5) {
            let i = u32(b.z + 0.5) - 1u;
            weight = area_weight(i, p);
            if (area_kind(i) < 1.5) {
                weight *= 1.0 - entities;
            }
        }
        if (weight <= 0.0) {
            continue;
        }
        let phase = a.w + a.z * dot(a.xy, p);
        let s = sin(phase);
        let c = cos(phase);
        let amplitude = weight * b.x;
        let displacement = weight * b.y;
        out.height_displacement += vec3<f32>(amplitude * c, -displacement * a.xy * s);
        out.slope += -amplitude * a.z * s * a.xy;
        let compression = -displacement * a.z * c;
        out.gradient += compression * vec3<f32>(a.x * a.x, a.y * a.y, a.x * a.y);
    }
    return out;
}

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
    d += explicit_waves(local).height_displacement;
    let p = local + from_plane(d.yz);
    // The round earth: the surface drops below the eye's horizontal plane by d^2 / 2R.
    let drop = dot(p, p) / (2.0 * sea.params.y);
    let up = g.eye_up.xyz;
    let rel = sea.east.xyz * p.x + sea.north.xyz * p.y + up * (sea.params.x + d.x - drop);
    var out: SeaOut;
    out.clip = g.view_proj * vec4<f32>(refracted(rel), 1.0);
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

// Fresnel reflectance (unpolarised) of a dielectric of index `n_ir` at incidence cosine `c`.
fn fresnel_dielectric(c: f32, n_ir: f32) -> f32 {
    let cos_i = clamp(c, 1e-4, 1.0);
    let sin_t = sqrt(1.0 - cos_i * cos_i) / n_ir;
    let cos_t = sqrt(max(1.0 - sin_t * sin_t, 0.0));
    let rs = (cos_i - n_ir * cos_t) / (cos_i + n_ir * cos_t);
    let rp = (n_ir * cos_i - cos_t) / (n_ir * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// What a thermal sensor sees of the sea: the water's emission at its surface temperature with
// the emissivity of water in the thermal infrared (Fresnel with n = 1.22 at 10 um: 0.99 looking
// down, 0.83 at 75 degrees from the vertical, falling to 0 at grazing; Masuda et al. 1988
// measured 0.88 there on a rough sea), the sky reflected specularly along `r`, the sun's glint,
// then the path to the eye and a ground fog's droplets.
fn sea_thermal(n: vec3<f32>, v: vec3<f32>, r: vec3<f32>, s2: f32, rel: vec3<f32>) -> vec4<f32> {
    let reflectance = fresnel_dielectric(dot(n, v), 1.22);
    var l = (1.0 - reflectance) * th_band_radiance(sea.thermal.x) + reflectance * th_sky(r);
    // glint() gives pi L (the visible light's units); band radiances here are L.
    l += glint(vec3<f32>(g.sensor.w), g.sun_dir.xyz, v, n, s2).x / 3.14159265;
    let p = th_path(rel);
    let fog = sqrt(fog_layer_transmittance(rel));
    let air = th_band_radiance(thermal[TH_OFF_SPOT_COUNT + 1u]);
    return vec4<f32>(vec3<f32>(fog * (p.x * l + p.y) + (1.0 - fog) * air), 1.0);
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
    let waves = explicit_waves(in.local);
    slope += from_plane(waves.slope);
    grad += waves.gradient;
    let up = g.eye_up.xyz;
    let n = normalize(up - sea.east.xyz * slope.x - sea.north.xyz * slope.y);
    let distance_m = max(length(in.rel), 1e-3);
    let v = -in.rel / distance_m;
    let cos_v = max(dot(n, v), 0.0);
    let f = fresnel(cos_v);
    let r = reflect(-v, n);
    // Whitecaps where the surface's Jacobian folds.
    let jacobian = (1.0 + grad.x) * (1.0 + grad.y) - grad.z * grad.z;
    let foam = max(1.0 - smoothstep(sea.shade.y - 0.2, sea.shade.y + 0.05, jacobian), wake_foam(in.local));
    let s2 = max(variance, 1e-4);
    if (sensor_on()) {
        return sea_thermal(n, v, r, s2, in.rel);
    }
    let light = glint(g.sun_colour.rgb, g.sun_dir.xyz, v, n, s2)
        + glint(g.moon_colour.rgb, g.moon_dir.xyz, v, n, s2);
    // The water body: light scattered up from below, leaving through the surface. On goggles
    // (the near infrared, 0.6-0.9 um) water absorbs within tens of centimetres (2.9 /m at
    // 750 nm, 4.3 /m at 850 nm: Hale and Querry 1973), so little comes back from the body:
    // taken as a tenth of the visible's; foam reflects about 40 % less at 850 nm than in the
    // visible (Frouin, Schwindling and Deschamps 1996). The sky's reflection and the glitter
    // are the same surface's in any band.
    var body_albedo = sea.water.rgb;
    var foam_albedo = vec3<f32>(0.75);
    if (nvg_on()) {
        body_albedo = vec3<f32>(0.1 * dot(sea.water.rgb, vec3<f32>(0.2126, 0.7152, 0.0722)));
        foam_albedo = vec3<f32>(0.45);
    }
    let body = lit_at(body_albedo, up, in.rel) * (1.0 - f);
    let foam_colour = lit_at(foam_albedo, n, in.rel);
    let surface = exposed(mix(light + body, foam_colour, foam)) + reflected_sky(r) * (f * (1.0 - foam));
    return vec4<f32>(apply_atmosphere_exposed(surface, in.rel), 1.0);
}
