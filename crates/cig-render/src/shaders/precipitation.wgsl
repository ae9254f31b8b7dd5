// Rain streaks and snow flakes in a box around the eye (instanced quads, no vertex buffers).

struct Precip {
    // Axes of the particles' frame (east, north, up) in ECEF; w unused.
    east: vec4<f32>,
    north: vec4<f32>,
    up: vec4<f32>,
    // Offset of the lattice (m, 0..box), w: box size (m).
    offset: vec4<f32>,
    // Particle velocity in the frame (m/s), w: the streak's exposure time (s).
    velocity: vec4<f32>,
    // x: kind (0 streaks, 1 flakes), y: particles, z: flake diameter (m), w: opacity.
    params: vec4<f32>,
    // Lit radiance of a particle (rgb, light units), w: seconds for the snow's sway (0..20π, its period).
    colour: vec4<f32>,
    // Viewport width, height (px), smallest half size (px), seed.
    viewport: vec4<f32>,
};

@group(0) @binding(1) var<uniform> p: Precip;

struct PrecipOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) alpha: f32,
};

fn hash(x: u32) -> u32 {
    // PCG-style integer hash.
    var v = x * 747796405u + 2891336453u;
    v = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    return (v >> 22u) ^ v;
}

fn unit(x: u32) -> f32 {
    return f32(hash(x) & 0xffffffu) / 16777216.0;
}

fn to_ecef(v: vec3<f32>) -> vec3<f32> {
    return p.east.xyz * v.x + p.north.xyz * v.y + p.up.xyz * v.z;
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> PrecipOut {
    let box_m = p.offset.w;
    let seed = u32(p.viewport.w);
    let key = hash(instance ^ seed) * 3u;
    let base = vec3<f32>(unit(key), unit(key + 1u), unit(key + 2u)) * box_m;
    var rel = fract((base - p.offset.xyz) / box_m) * box_m - vec3<f32>(box_m * 0.5);
    var out: PrecipOut;
    if (p.params.x > 0.5) {
        // Snow sways sideways as it falls.
        let phase = unit(key + 7u) * 6.2831853;
        let t = p.colour.w;
        rel = rel + vec3<f32>(0.3 * sin(t * 2.1 + phase), 0.3 * cos(t * 1.7 + phase), 0.0);
    }
    let distance = length(rel);
    // Round the box into a ball, and fade the nearest particles (they would fill the view).
    let fade = (1.0 - smoothstep(box_m * 0.35, box_m * 0.5, distance)) * smoothstep(0.3, 1.0, distance);
    let centre = to_ecef(rel);
    if (p.params.x < 0.5) {
        // A streak: the drop's path over the exposure.
        let tail = centre - to_ecef(p.velocity.xyz) * p.velocity.w;
        let c = line_corner(tail, centre, p.viewport.z, p.viewport.xy, vertex);
        out.clip = c.clip;
        out.uv = vec2<f32>(c.across, 0.0);
        out.alpha = p.params.w * fade;
        return out;
    }
    // A flake: a soft disc facing the eye, its real size or the smallest drawn.
    let clip = g.view_proj * vec4<f32>(centre, 1.0);
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0));
    let corner = corners[vertex];
    let w = max(clip.w, 0.05);
    let half_px = max(p.params.z * 0.5 / w * g.flags.w, p.viewport.z);
    // A flake smaller than the smallest drawn is dimmed by its share of the disc.
    let share = min(1.0, p.params.z * 0.5 / w * g.flags.w / p.viewport.z);
    out.clip = vec4<f32>(clip.xy + corner * half_px / (p.viewport.xy * 0.5) * clip.w, clip.z, clip.w);
    if (clip.w < 0.05) {
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
    }
    out.uv = corner;
    out.alpha = p.params.w * fade * max(share, 0.7);
    return out;
}

@fragment
fn fs_main(in: PrecipOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.uv, in.uv);
    let soft = max(1.0 - r2, 0.0);
    let a = clamp(in.alpha * soft * soft, 0.0, 1.0);
    // Premultiplied: the particle's light over what is behind it.
    return vec4<f32>(exposed(p.colour.rgb) * a, a);
}
