struct Node {
    // Node centre relative to the eye (metres, ECEF axes); w: skirt depth per metre of
    // distance (twice the error the view allows there, and a margin).
    offset: vec4<f32>,
    axis_e: vec4<f32>,
    axis_n: vec4<f32>,
    // w: the skirt's greatest depth (m).
    axis_u: vec4<f32>,
    // Morph start and end distances (m), skirt depth at the eye (m), least morph (fade-in).
    morph: vec4<f32>,
    // Atlas rectangle of the node's texels: u0, v0, du, dv.
    atlas: vec4<f32>,
};

@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var normal_atlas: texture_2d<f32>;
@group(0) @binding(3) var colour_atlas: texture_2d<f32>;
@group(0) @binding(4) var atlas_sampler: sampler;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) node: u32,
};

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) morph_target: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) skirt: f32,
    @builtin(vertex_index) vertex_index: u32,
) -> VertexOut {
    // One draw covers every node: a vertex's slot of the pool is its node.
    let slot = vertex_index / u32(g.cam_forward.w + 0.5);
    let node = nodes[slot];
    let target_rel = morph_target + node.offset.xyz;
    let d = length(target_rel);
    // Morph by distance, and never less than the node's fade-in floor (finer data arriving).
    let m = max(clamp((d - node.morph.x) / max(node.morph.y - node.morph.x, 1e-3), 0.0, 1.0), node.morph.w);
    var rel = mix(position, morph_target, m) + node.offset.xyz;
    // A skirt's foot hangs below its edge post by what neighbours can differ there.
    rel -= node.axis_u.xyz * (skirt * min(node.morph.z + node.offset.w * d, node.axis_u.w));
    var out: VertexOut;
    out.clip = g.view_proj * vec4<f32>(rel, 1.0);
    out.rel = rel;
    out.uv = node.atlas.xy + uv * node.atlas.zw;
    out.node = slot;
    return out;
}

// Euclidean modulo (WGSL's % truncates towards zero, which breaks the wrap for negative cells).
fn wrap(i: vec3<f32>, c: f32) -> vec3<f32> {
    return i - c * floor(i / c);
}

// The hash of a lattice point from its per-axis fractions q = fract(p * K): each axis's
// fraction depends on that axis alone, so a cell's eight corners share two per axis.
const HASH_K: vec3<f32> = vec3<f32>(0.1031, 0.1030, 0.0973);

fn hash_of_fractions(q: vec3<f32>) -> f32 {
    let r = q + dot(q, q.yxz + 33.33);
    return fract((r.x + r.y) * r.z);
}

// Value noise on a lattice of unit cells, periodic with 256 cells.
fn value_noise(p: vec3<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let c = 256.0;
    let q0 = fract(wrap(i, c) * HASH_K);
    let q1 = fract(wrap(i + 1.0, c) * HASH_K);
    let a = hash_of_fractions(q0);
    let b = hash_of_fractions(vec3<f32>(q1.x, q0.y, q0.z));
    let cc = hash_of_fractions(vec3<f32>(q0.x, q1.y, q0.z));
    let d = hash_of_fractions(vec3<f32>(q1.x, q1.y, q0.z));
    let e = hash_of_fractions(vec3<f32>(q0.x, q0.y, q1.z));
    let ff = hash_of_fractions(vec3<f32>(q1.x, q0.y, q1.z));
    let gg = hash_of_fractions(vec3<f32>(q0.x, q1.y, q1.z));
    let h = hash_of_fractions(q1);
    return mix(
        mix(mix(a, b, u.x), mix(cc, d, u.x), u.y),
        mix(mix(e, ff, u.x), mix(gg, h, u.x), u.y),
        u.z,
    );
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    if (g.flags.x > 0.5) {
        return vec4<f32>(0.9, 0.9, 0.9, 1.0);
    }
    let node = nodes[in.node];
    let ne = textureSample(normal_atlas, atlas_sampler, in.uv).xyz * 2.0 - 1.0;
    let n = normalize(node.axis_e.xyz * ne.x + node.axis_n.xyz * ne.y + node.axis_u.xyz * ne.z);
    let base = textureSample(colour_atlas, atlas_sampler, in.uv);
    let distance_m = length(in.rel);
    // Detail: three octaves of value noise with incommensurate periods (no visible tiling),
    // faded out with distance before they alias.
    let p0 = in.rel / g.noise0.w + g.noise0.xyz;
    let p1 = in.rel / g.noise1.w + g.noise1.xyz;
    let p2 = in.rel / g.noise2.w + g.noise2.xyz;
    // Each octave fades out as its cells shrink below 6 pixels on screen (no aliasing, in
    // narrow and wide views alike).
    let px_per_m = g.flags.w / max(distance_m, 1.0);
    let fade0 = clamp((g.noise0.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
    let fade1 = clamp((g.noise1.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
    let fade2 = clamp((g.noise2.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
    // An octave that has faded out is not evaluated on GPUs whose threads skip a branch none of
    // them takes (the same colour, less work far away); lavapipe runs every branch under a mask,
    // so there a shader costs the sum of all its paths (measured: an `if` no pixel enters cost
    // as much as its body).
    var detail = 1.0;
    if (fade0 > 0.0) {
        detail += 0.18 * (value_noise(p0) - 0.5) * fade0;
    }
    if (fade1 > 0.0) {
        detail += 0.22 * (value_noise(p1) - 0.5) * fade1;
    }
    if (fade2 > 0.0) {
        detail += 0.25 * (value_noise(p2) - 0.5) * fade2;
    }
    let albedo = base.rgb * detail;
    var colour = lit(albedo, n);
    // Water and wet surfaces: a sun glint.
    let view_dir = -in.rel / max(distance_m, 1e-3);
    let h = normalize(view_dir + g.sun_dir.xyz);
    let spec = pow(max(dot(n, h), 0.0), 80.0) * base.a;
    colour += g.sun_colour.rgb * spec * 0.8;
    return vec4<f32>(apply_atmosphere_exposed(exposed(colour), in.rel), 1.0);
}
