struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> SkyOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var out: SkyOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    out.ndc = xy;
    return out;
}

@fragment
fn fs_main(in: SkyOut) -> @location(0) vec4<f32> {
    if (g.flags.z > 0.5) {
        return vec4<f32>(1.0, 0.0, 1.0, 1.0);
    }
    let t = g.tangents;
    let x_tan = mix(-t.x, t.y, in.ndc.x * 0.5 + 0.5);
    let y_tan = mix(-t.z, t.w, in.ndc.y * 0.5 + 0.5);
    let dir = normalize(g.cam_forward.xyz + g.cam_right.xyz * x_tan + g.cam_up.xyz * y_tan);
    // Elevation above the apparent (dipped) horizon.
    let elevation = asin(clamp(dot(dir, g.eye_up.xyz), -1.0, 1.0)) + g.eye_up.w;
    var colour: vec3<f32>;
    if (elevation >= 0.0) {
        let k = pow(clamp(elevation / 1.5707963, 0.0, 1.0), 0.45);
        colour = mix(g.sky_horizon.rgb, g.sky_zenith.rgb, k);
    } else {
        colour = g.sky_horizon.rgb * mix(0.8, 0.35, clamp(-elevation * 6.0, 0.0, 1.0));
    }
    let cos_sun = dot(dir, g.sun_dir.xyz);
    let glow = pow(max(cos_sun, 0.0), 64.0) * 0.5 + pow(max(cos_sun, 0.0), 8.0) * 0.12;
    colour += g.sun_colour.rgb * glow;
    // Sun disc (0.53 degree across).
    if (cos_sun > 0.999957) {
        colour = max(colour, g.sun_colour.rgb * 4.0);
    }
    colour += celestial_radiance(dir);
    // Inside the ground fog layer, the sky is seen through the rest of it: up to its top for
    // rays that climb out, through all of it for the others.
    if (g.fog_layer.z > 0.5 && g.fog_layer.x > 0.0) {
        let rise = dot(dir, g.eye_up.xyz);
        var t = 0.0;
        if (rise > 1e-4) {
            t = exp(-g.fog_layer.y * g.fog_layer.x / rise);
        }
        colour = t * colour + (1.0 - t) * g.fog_colour.rgb;
    }
    return vec4<f32>(exposed(colour), 1.0);
}
