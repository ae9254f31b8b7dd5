struct Instance {
    // Body to eye-relative ECEF: columns of the rotation (scaled), and the origin (w unused).
    col0: vec4<f32>,
    col1: vec4<f32>,
    col2: vec4<f32>,
    origin: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> instances: array<Instance>;

struct ModelOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec3<f32>,
    // Share of the model's pixels this draw covers, [x, y) in dither thresholds.
    @location(3) @interpolate(flat) share: vec2<f32>,
    // Thermal: the vertex's code (its colour's alpha) and the instance's word (col2.w: the
    // default material's code plus 256 times its hot slot); see cig_scene::thermal.
    @location(4) @interpolate(flat) thermal_code: vec2<u32>,
};

// Ordered 4x4 (Bayer) dither threshold of a pixel, in (0, 1).
fn dither_threshold(pixel: vec2<f32>) -> f32 {
    let bayer = array<f32, 16>(0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0, 3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    let x = u32(pixel.x) & 3u;
    let y = u32(pixel.y) & 3u;
    return (bayer[y * 4u + x] + 0.5) / 16.0;
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec4<f32>,
    @builtin(instance_index) instance: u32,
) -> ModelOut {
    let m = instances[instance];
    let rel = m.col0.xyz * position.x + m.col1.xyz * position.y + m.col2.xyz * position.z + m.origin.xyz;
    var out: ModelOut;
    out.clip = g.view_proj * vec4<f32>(refracted(rel), 1.0);
    out.rel = rel;
    out.normal = normalize(m.col0.xyz * normal.x + m.col1.xyz * normal.y + m.col2.xyz * normal.z);
    // origin.w: a culture instance's tint (0 for entities).
    out.colour = pow(colour.rgb, vec3<f32>(2.2)) * (1.0 + m.origin.w);
    out.share = vec2<f32>(m.col0.w, m.col1.w);
    out.thermal_code = vec2<u32>(u32(round(colour.a * 255.0)), u32(max(m.col2.w, 0.0)));
    return out;
}

@fragment
fn fs_main(in: ModelOut) -> @location(0) vec4<f32> {
    // Level-of-detail blending: two levels cover complementary shares of the pixels.
    let threshold = dither_threshold(in.clip.xy);
    if (threshold < in.share.x || threshold >= in.share.y) {
        discard;
    }
    if (g.flags.x > 0.5) {
        return vec4<f32>(1.0, 0.6, 0.2, 1.0);
    }
    var n = normalize(in.normal);
    if (sensor_on()) {
        let code = in.thermal_code.x;
        let word = in.thermal_code.y;
        var material = word & 255u;
        let slot = word >> 8u;
        // A burning entity is hot all over; its parts at least as hot as their own rise.
        var rise = th_entity_rise(slot, 4u);
        var eps = th_emissivity(material);
        if (code < TH_MATERIALS) {
            material = code;
            eps = th_emissivity(material);
        } else if (code == TH_HOT_BASE + 3u) {
            // Crew: skin, whose slab has the body's core behind it.
            material = TH_SKIN;
            eps = th_emissivity(material);
        } else if (code >= TH_HOT_BASE && code < TH_HOT_BASE + TH_HOT_PARTS) {
            rise = max(rise, th_entity_rise(slot, code - TH_HOT_BASE));
            eps = TH_HOT_EMISSIVITY;
        }
        return th_shown(th_surface_temp(material, n) + rise, eps, n, in.rel);
    }
    var albedo = in.colour;
    if (nvg_on()) {
        albedo = nvg_model_albedo(in.thermal_code.x, in.thermal_code.y);
    }
    let colour = lit_at(albedo, n, in.rel);
    return vec4<f32>(apply_atmosphere_exposed(exposed(colour), in.rel), 1.0);
}
