// The sky: the sky-view table along each pixel's direction, the sun's disc (limb darkened,
// its radiance the solar illuminance through the atmosphere's transmittance), the ground fog
// layer. The flat sky model paints the fog colour.

struct SkyOut {
    // Depth 0 exactly, tested Equal against the cleared far plane: invariant, so no compiler
    // may compute it differently between passes.
    @builtin(position) @invariant clip: vec4<f32>,
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

// Limb darkening coefficient of the sun's disc, I(μ) = 1 - u (1 - μ) (a linear law near 550 nm).
const SUN_LIMB_U: f32 = 0.6;

@fragment
fn fs_main(in: SkyOut) -> @location(0) vec4<f32> {
    if (g.flags.z > 0.5) {
        // The key colour, bright enough that the tone map passes it as pure magenta.
        return vec4<f32>(KEY_RADIANCE, 0.0, KEY_RADIANCE, 1.0);
    }
    let t = g.tangents;
    let x_tan = mix(-t.x, t.y, in.ndc.x * 0.5 + 0.5);
    let y_tan = mix(-t.z, t.w, in.ndc.y * 0.5 + 0.5);
    let dir = normalize(g.cam_forward.xyz + g.cam_right.xyz * x_tan + g.cam_up.xyz * y_tan);
    if (g.sensor.x > 0.5) {
        // A thermal sensor sees the sky's band radiance (sensor.rs), no sun, moon or stars.
        return vec4<f32>(vec3<f32>(th_sky(dir)), 1.0);
    }
    var colour = exposed(g.fog_colour.rgb);
    if (physical_sky()) {
        colour = sky_radiance(dir);
        // The sky behind, un-exposed: the background of the eye's threshold for the stars.
        let sky_behind = colour / max(g.flags.y, 1e-30);
        let r = eye_radius();
        let mu = dot(dir, g.eye_up.xyz);
        // What the air lets through toward space along this ray (0 into the ground).
        let view_t = transmittance_to_top(r, mu);
        // The sun's disc: mean radiance E / (π α²), limb darkened, through the atmosphere.
        let cos_sun = dot(dir, g.sun_dir.xyz);
        let cos_radius = cos(ATM_SUN_RADIUS);
        if (cos_sun > cos_radius) {
            let x = sqrt(max(1.0 - cos_sun * cos_sun, 0.0)) / sin(ATM_SUN_RADIUS);
            let mu_limb = sqrt(max(1.0 - x * x, 0.0));
            let limb = (1.0 - SUN_LIMB_U * (1.0 - mu_limb)) / (1.0 - SUN_LIMB_U / 3.0);
            let solid_angle = PI * ATM_SUN_RADIUS * ATM_SUN_RADIUS;
            // Shown as π L (the contract's emitter convention).
            colour += exposed(g.sun_toa.rgb * view_t * (PI * limb / solid_angle));
        }
        // Moon and stars (celestial.wgsl, the pipeline's @group(2)), dimmed by their own
        // extinction model and hidden below the apparent horizon, under the fog below.
        colour += exposed(celestial_radiance(dir, sky_behind));
    }
    // Inside the ground fog layer, the sky is seen through the rest of it: up to its top for
    // rays that climb out, through all of it for the others.
    if (ground_fog_on() && g.fog_layer.x > 0.0) {
        let rise = dot(dir, g.eye_up.xyz);
        var through = 0.0;
        if (rise > 1e-4) {
            through = exp(-g.fog_layer.y * g.fog_layer.x / rise);
        }
        colour = through * colour + (1.0 - through) * exposed(g.fog_colour.rgb);
    }
    return vec4<f32>(min(colour, vec3<f32>(60000.0)), 1.0);
}
