// Lightning bolts: emissive lines, additive, depth-tested against the scene (no depth write).

struct BoltLine {
    // Eye-relative start (m); w: the line's radiance in light units (before exposure).
    start: vec4<f32>,
    // Eye-relative end (m); w unused.
    end: vec4<f32>,
};

struct BoltFrame {
    // Viewport width, height (px), half width of a line (px), unused.
    viewport: vec4<f32>,
    // The flash's colour (rgb), unused.
    colour: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> lines: array<BoltLine>;
@group(0) @binding(2) var<uniform> frame: BoltFrame;

struct BoltOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) across: f32,
    @location(1) radiance: f32,
    @location(2) rel: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> BoltOut {
    let line = lines[instance];
    let c = line_corner(line.start.xyz, line.end.xyz, frame.viewport.z, frame.viewport.xy, vertex);
    var out: BoltOut;
    out.clip = c.clip;
    out.across = c.across;
    out.radiance = line.start.w;
    out.rel = mix(line.start.xyz, line.end.xyz, c.along);
    return out;
}

@fragment
fn fs_main(in: BoltOut) -> @location(0) vec4<f32> {
    // A bright core and a soft glow across the line.
    let x = abs(in.across);
    let glow = exp(-x * x * 4.0);
    // Emission through the air: dimmed by the fog, never replaced by its colour.
    let f = fog_factor(length(in.rel)) * fog_layer_transmittance(in.rel);
    let radiance = frame.colour.rgb * in.radiance * glow * f;
    // Clamped below the half float's largest value: a bolt at night must not write infinity.
    return vec4<f32>(min(exposed(radiance), vec3<f32>(60000.0)), 0.0);
}
