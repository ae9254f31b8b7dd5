struct Node {
    // Node centre relative to the eye (metres, ECEF axes); w: skirt depth per metre of
    // distance (twice the error the view allows there, and a margin).
    offset: vec4<f32>,
    // w: colour texels per post of the data the colours came from (terrain.rs texels_per_post).
    axis_e: vec4<f32>,
    // w: that data's post spacing, metres.
    axis_n: vec4<f32>,
    // w: the skirt's greatest depth (m).
    axis_u: vec4<f32>,
    // Morph start and end distances (m), skirt depth at the eye (m), least morph (fade-in).
    morph: vec4<f32>,
    // Atlas rectangle of the node's texels: u0, v0, du, dv.
    atlas: vec4<f32>,
    // Imagery rectangle: level-0 imagery texel coordinates (column, row) of the node's
    // south-west post relative to the view's anchor, and the node's extent in those texels.
    imagery: vec4<f32>,
    // The node's cells replaced by terrain-edit patches: bit row * cells + col.
    refined_lo: vec4<u32>,
    refined_hi: vec4<u32>,
    // x: the node's cells a side when it has patches (0: none).
    edit: vec4<f32>,
};

// One imagery clipmap level (imagery.rs LevelParams).
struct ImageryLevel {
    // xy: the toroidal phase (the anchor modulo the clip size, level texels); zw: the
    // window's south-west corner relative to the anchor, level texels.
    phase_lo: vec4<f32>,
    // xy: the window's north-east corner; z: the level's texel size, metres.
    hi: vec4<f32>,
};

struct Imagery {
    // Levels (0: no imagery), clip size, tile texels, window tiles.
    info: vec4<f32>,
    levels: array<ImageryLevel, 24>,
};

@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var normal_atlas: texture_2d<f32>;
@group(0) @binding(3) var colour_atlas: texture_2d<f32>;
@group(0) @binding(4) var atlas_sampler: sampler;
@group(0) @binding(5) var<uniform> imagery: Imagery;
@group(0) @binding(6) var imagery_clip: texture_2d_array<f32>;
@group(0) @binding(7) var imagery_pages: texture_2d_array<u32>;
// Repeating: the clipmap's windows are toroidal.
@group(0) @binding(8) var imagery_sampler: sampler;
// The terrain edits' dynamic texture (terrain.rs TerrainFrame::patch_marks): [0].x the frame's
// time from the marks' origin (s); then per patch vertex: track weight, its time, scorch
// weight, its time.
@group(2) @binding(0) var<storage, read> patch_marks: array<vec4<f32>>;

// Tracks' marks fade over hours (the ruts' shapes stay): e-folding time, s.
const TRACK_FADE_S: f32 = 14400.0;
// A crater's scorch weathers over a day.
const SCORCH_FADE_S: f32 = 86400.0;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) node: u32,
    // Level-0 imagery texel coordinates (column, row) relative to the view's anchor.
    @location(3) img: vec2<f32>,
    // 1 for a terrain-edit patch's fragment, 0 for a node's.
    @location(4) @interpolate(flat) patched: u32,
    // The place on the node's grid (east, north; 0 to 1).
    @location(5) grid: vec2<f32>,
    // A patch's edits' slope plus the up times one plus how disturbed (ECEF), interpolated.
    @location(6) patch_normal: vec3<f32>,
    // A patch's marks now: track, scorch (0 to 1, faded with their age).
    @location(7) marks: vec2<f32>,
};

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) morph_target: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) skirt: f32,
    @builtin(vertex_index) vertex_index: u32,
) -> VertexOut {
    // One draw covers every node: a vertex's slot of the pool is its node. A terrain-edit
    // patch's vertex names its node's slot in its skirt field: -(slot + 1), less a half at a
    // skirt's foot.
    var slot = vertex_index / u32(g.cam_forward.w + 0.5);
    var hang = skirt;
    var patched = 0u;
    if (skirt < 0.0) {
        let tag = -skirt;
        slot = u32(floor(tag)) - 1u;
        hang = select(0.0, 1.0, fract(tag) > 0.25);
        patched = 1u;
    }
    let node = nodes[slot];
    // A patch does not morph; its morph target field is its normal.
    let morph_to = select(morph_target, position, patched == 1u);
    let target_rel = morph_to + node.offset.xyz;
    let d = length(target_rel);
    // Morph by distance, and never less than the node's fade-in floor (finer data arriving).
    let m = max(clamp((d - node.morph.x) / max(node.morph.y - node.morph.x, 1e-3), 0.0, 1.0), node.morph.w);
    var rel = mix(position, morph_to, m) + node.offset.xyz;
    // A skirt's foot hangs below its edge post by what neighbours can differ there.
    rel -= node.axis_u.xyz * (hang * min(node.morph.z + node.offset.w * d, node.axis_u.w));
    var out: VertexOut;
    out.clip = g.view_proj * vec4<f32>(refracted(rel), 1.0);
    out.rel = rel;
    out.uv = node.atlas.xy + uv * node.atlas.zw;
    out.img = node.imagery.xy + uv * node.imagery.zw;
    out.node = slot;
    out.patched = patched;
    out.patch_normal = select(vec3<f32>(0.0), morph_target, patched == 1u);
    out.marks = vec2<f32>(0.0);
    if (patched == 1u) {
        let now = patch_marks[0].x;
        let m = patch_marks[vertex_index + 1u];
        out.marks = vec2<f32>(
            m.x * exp(-max(now - m.y, 0.0) / TRACK_FADE_S),
            m.z * exp(-max(now - m.w, 0.0) / SCORCH_FADE_S),
        );
    }
    out.grid = uv;
    return out;
}

// Euclidean modulo (WGSL's % truncates towards zero, which breaks the wrap for negative cells).
fn wrap(i: vec2<f32>, c: f32) -> vec2<f32> {
    return i - c * floor(i / c);
}

// The hash of a lattice point from its per-axis fractions q = fract(p * K): each axis's
// fraction depends on that axis alone, so a cell's four corners share two per axis.
const HASH_K: vec2<f32> = vec2<f32>(0.1031, 0.1030);

fn hash_of_fractions(q: vec2<f32>) -> f32 {
    let r = vec3<f32>(q, 0.0973) + dot(vec3<f32>(q, 0.0973), vec3<f32>(q.y, q.x, 0.0973) + 33.33);
    return fract((r.x + r.y) * r.z);
}

// Two hashes of a lattice point: x is `hash_of_fractions`, y the same hash of the fractions
// taken the other way round (unrelated values from the lattice work already done).
fn hash2_of_fractions(q: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(hash_of_fractions(q), hash_of_fractions(q.yx + 0.37));
}

// Value noise on a lattice of unit cells in the detail plane (the database centre's tangent
// plane: world-fixed and the same for every node, so patterns run on across nodes and tiles;
// two dimensions, half the corners of a 3-D noise), periodic with 256 cells.
fn value_noise(p: vec2<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let q0 = fract(wrap(i, 256.0) * HASH_K);
    let q1 = fract(wrap(i + 1.0, 256.0) * HASH_K);
    let a = hash_of_fractions(q0);
    let b = hash_of_fractions(vec2<f32>(q1.x, q0.y));
    let c = hash_of_fractions(vec2<f32>(q0.x, q1.y));
    let d = hash_of_fractions(q1);
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

// Two value noises on one lattice (x is `value_noise`), for little more than the price of one.
// `value_noise` is kept beside it, not replaced by this one's x, because a shader pays here
// for every hash on every pixel (lavapipe runs every path) and most octaves need one value.
fn value_noise2(p: vec2<f32>) -> vec2<f32> {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let q0 = fract(wrap(i, 256.0) * HASH_K);
    let q1 = fract(wrap(i + 1.0, 256.0) * HASH_K);
    let a = hash2_of_fractions(q0);
    let b = hash2_of_fractions(vec2<f32>(q1.x, q0.y));
    let c = hash2_of_fractions(vec2<f32>(q0.x, q1.y));
    let d = hash2_of_fractions(q1);
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

// The surface material at an atlas point, with smooth borders between materials. Each colour
// texel holds its material's colour and, in alpha, the material's index (high nibble) and
// specular weight (low nibble); the texels of the node's data posts are every `axis_e.w`-th.
// Near the eye (a post over a few pixels) the four posts around a point each weigh their
// material by the bilinear weights of every post of the same material, and the heaviest
// material wins: its border is the 0.5 level of the materials' bilinear fields over the posts
// (the marching-squares contour, which cuts across a cell where the post grid would step
// around it, after NPSNET's majority-coloured posts and explicit shorelines, source 003),
// bent by a domain warp of value noise at 19 m so the border is irregular as land cover is,
// and softened over about a pixel against aliasing. Far away (posts under a pixel or two) the
// materials blend bilinearly, the average a pixel covers, so the border does not shimmer.
// Returns the linear albedo and the specular weight.
struct Surface {
    albedo: vec3<f32>,
    specular: f32,
    // The heaviest material's index.
    kind: u32,
};

fn material_at(node: Node, uv: vec2<f32>, rel: vec3<f32>, n: vec3<f32>, warp_noise: vec2<f32>) -> Surface {
    let size = vec2<f32>(textureDimensions(colour_atlas));
    let step = max(node.axis_e.w, 1.0);
    // Texel indices: continuous, and of the node's first and last texel.
    let first = node.atlas.xy * size - 0.5;
    let posts = max(round(node.atlas.zw * size / step), vec2<f32>(1.0));
    var local = ((uv * size - 0.5) - first) / step;
    // A post's size on screen, from its size in metres and the distance (not from screen
    // derivatives, which change from triangle to triangle of a morphing mesh and would draw
    // its edges), foreshortened by the slope toward the eye.
    let distance_m = max(length(rel), 1.0);
    let facing = abs(dot(n, rel)) / distance_m;
    let post_px = node.axis_n.w * g.flags.w / distance_m * sqrt(max(facing, 0.01));
    // 1 when a post spans 4 or more pixels, 0 when it spans 2 or less.
    let sharpness = clamp(0.5 * (post_px - 2.0), 0.0, 1.0);
    if (sharpness > 0.0) {
        let warp = warp_noise - 0.5;
        // Up to a third of a post each way, fading to none at the node's edges (where the
        // neighbour, which cannot see past its own edge either, samples the same posts), so
        // borders run on across nodes without a seam.
        let edge = min(min(local, posts - local), vec2<f32>(1.0));
        let fade = clamp(min(edge.x, edge.y), 0.0, 1.0);
        local += warp * (0.7 * sharpness * fade);
    }
    local = clamp(local, vec2<f32>(0.0), posts);
    let cell = min(floor(local), max(posts - 1.0, vec2<f32>(0.0)));
    let f = local - cell;
    let base = first + cell * step;
    let near = vec2<i32>(round(base));
    let far = vec2<i32>(round(base + step));
    // x (0, 1), y (1, 1), z (1, 0), w (0, 0): the corners as textureGather orders them.
    let c0 = textureLoad(colour_atlas, vec2<i32>(near.x, far.y), 0);
    let c1 = textureLoad(colour_atlas, far, 0);
    let c2 = textureLoad(colour_atlas, vec2<i32>(far.x, near.y), 0);
    let c3 = textureLoad(colour_atlas, near, 0);
    let w = vec4<f32>((1.0 - f.x) * f.y, f.x * f.y, f.x * (1.0 - f.y), (1.0 - f.x) * (1.0 - f.y));
    let tags = vec4<u32>(round(vec4<f32>(c0.a, c1.a, c2.a, c3.a) * 255.0));
    let kind = tags >> vec4<u32>(4u);
    let specular = vec4<f32>(tags & vec4<u32>(15u)) / 15.0;
    // Each post's material's total weight (written out: a vector indexed in a loop costs a
    // trip through memory on some compilers).
    let total = vec4<f32>(
        dot(w, vec4<f32>(kind == vec4<u32>(kind.x))),
        dot(w, vec4<f32>(kind == vec4<u32>(kind.y))),
        dot(w, vec4<f32>(kind == vec4<u32>(kind.z))),
        dot(w, vec4<f32>(kind == vec4<u32>(kind.w))),
    );
    // A soft argmax over materials: each post's weight times a ramp of how far its material
    // trails the heaviest; slope 0 is the bilinear blend, a steep one the winner alone. Across
    // a border a material's total changes by about 2 per post, so this slope softens it over
    // about a pixel.
    let exponent = 1.0 * post_px * sharpness;
    let lead = max(max(total.x, total.y), max(total.z, total.w));
    let share = w * clamp(1.0 + exponent * (total - lead), vec4<f32>(0.0), vec4<f32>(1.0));
    let sum = max(share.x + share.y + share.z + share.w, 1e-6);
    let albedo = (share.x * c0.rgb + share.y * c1.rgb + share.z * c2.rgb + share.w * c3.rgb) / sum;
    // The heaviest material (by its total weight, not by one post's share).
    let lead_xy = select(kind.y, kind.x, total.x >= total.y);
    let lead_zw = select(kind.w, kind.z, total.z >= total.w);
    let kind_lead = select(lead_zw, lead_xy, max(total.x, total.y) >= max(total.z, total.w));
    return Surface(albedo, dot(share, specular) / sum, kind_lead);
}

fn imagery_sample(k: u32, p: vec2<f32>) -> vec4<f32> {
    let level = imagery.levels[k];
    let uv = (p * exp2(-f32(k)) + level.phase_lo.xy) / imagery.info.y;
    return textureSampleLevel(imagery_clip, imagery_sampler, uv, i32(k), 0.0);
}

// The draped imagery at level-0 texel point `p` (relative to the anchor at the eye) whose
// footprint on screen is `lambda` (log2 of level-0 texels per pixel): the level that matches
// the footprint, or the coarser one the point's distance from the eye needs (every level's
// window reaches at least `info.w / 2 - 1` tiles from the eye), then the level the page table
// resolves there (the finest loaded one with its coarser levels loaded), blended with the next
// level up so level borders do not show. No loop and one page read: on a CPU rasterizer every
// iteration and branch costs on every pixel. Returns the linear colour, premultiplied by its
// coverage, and the coverage (0 where no imagery is); `texel_m`, the drawn texels' size.
struct Drape {
    colour: vec4<f32>,
    texel_m: f32,
};

fn imagery_at(p: vec2<f32>, lambda: f32) -> Drape {
    let levels = max(u32(imagery.info.x), 1u);
    let reach = (0.5 * imagery.info.w - 1.0) * imagery.info.z;
    let far = log2(max(max(abs(p.x), abs(p.y)), 1.0) / reach);
    let k0 = u32(clamp(max(floor(lambda), ceil(far)), 0.0, f32(levels - 1u)));
    let level = imagery.levels[k0];
    let slot = wrap(floor((p * exp2(-f32(k0)) + level.phase_lo.xy) / imagery.info.z), imagery.info.w);
    let resolved = textureLoad(imagery_pages, vec2<i32>(slot), i32(k0), 0).r;
    let k = min(resolved, levels - 1u);
    let up = min(k + 1u, levels - 1u);
    // Blend toward the next level as the footprint grows, only where the level drawn is the
    // one the footprint asked for (a fallback level is drawn alone).
    let t = select(0.0, clamp(lambda - f32(k), 0.0, 1.0), k == k0 && up > k);
    let colour = mix(imagery_sample(k, p), imagery_sample(up, p), t);
    let none = resolved == 255u || u32(imagery.info.x) == 0u;
    return Drape(select(colour, vec4<f32>(0.0), none), imagery.levels[k].hi.z);
}

// Each material's detail: the amplitudes of its value-noise octaves at 0.34, 2.7, 19.3 and
// 151 m (x to w), so grass, forest and rock are mottled at every scale, asphalt and snow are
// fine-grained and even, water nearly flat (waves are not drawn). Indexed by
// `cig_terrain::Material` (water, sand, dry clay, grass, forest, rock, snow, paved road, dirt
// road).
var<private> DETAIL: array<vec4<f32>, 9> = array<vec4<f32>, 9>(
    vec4<f32>(0.00, 0.02, 0.05, 0.05),
    vec4<f32>(0.22, 0.14, 0.12, 0.20),
    vec4<f32>(0.22, 0.16, 0.18, 0.22),
    vec4<f32>(0.40, 0.24, 0.22, 0.25),
    vec4<f32>(0.30, 0.30, 0.25, 0.25),
    vec4<f32>(0.30, 0.26, 0.25, 0.25),
    vec4<f32>(0.06, 0.05, 0.08, 0.08),
    vec4<f32>(0.26, 0.06, 0.08, 0.10),
    vec4<f32>(0.26, 0.16, 0.15, 0.15),
);
// The hue the largest octave shifts vegetation toward (dry grass, sunlit canopy) where its
// noise is high, and soil and rock toward ochre: land cover is never one flat colour.
var<private> MACRO_TINT: array<vec3<f32>, 9> = array<vec3<f32>, 9>(
    vec3<f32>(1.0, 1.0, 1.0),
    vec3<f32>(1.04, 1.0, 0.92),
    vec3<f32>(1.06, 1.0, 0.90),
    vec3<f32>(1.18, 1.08, 0.80),
    vec3<f32>(1.10, 1.12, 0.85),
    vec3<f32>(1.06, 1.0, 0.92),
    vec3<f32>(1.0, 1.0, 1.0),
    vec3<f32>(1.0, 1.0, 1.0),
    vec3<f32>(1.06, 1.0, 0.90),
);

// Water posts at the sea's level are the sea's (the sea pass draws its waves there): the
// fragment's height relative to the eye on the curved earth, against the cut.
fn is_sea(kind: u32, rel: vec3<f32>) -> bool {
    if (!sea_cut_on() || kind != 0u) {
        return false;
    }
    let along = dot(rel, g.eye_up.xyz);
    let across2 = max(dot(rel, rel) - along * along, 0.0);
    return along + across2 / (2.0 * max(g.fog_layer.w, 1.0e6)) <= g.detail_north.w;
}

// Linear albedo of freshly turned earth (dark loam, about 0.06).
const DISTURBED_SOIL: vec3<f32> = vec3<f32>(0.075, 0.055, 0.038);
// Soot and burnt earth of a fresh crater.
const SCORCHED: vec3<f32> = vec3<f32>(0.022, 0.020, 0.018);

// Whether the node's cell at `grid` is drawn by a terrain-edit patch instead.
fn patched_cell(node: Node, grid: vec2<f32>) -> bool {
    let cells = node.edit.x;
    if (cells < 0.5) {
        return false;
    }
    let last = u32(cells) - 1u;
    let cell = min(vec2<u32>(max(floor(grid * cells), vec2<f32>(0.0))), vec2<u32>(last));
    let bit = cell.y * u32(cells) + cell.x;
    let word = bit / 32u;
    var w = 0u;
    if (word < 4u) {
        w = node.refined_lo[word];
    } else {
        w = node.refined_hi[word - 4u];
    }
    return ((w >> (bit % 32u)) & 1u) == 1u;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    if (g.flags.x > 0.5) {
        return vec4<f32>(0.9, 0.9, 0.9, 1.0);
    }
    let node = nodes[in.node];
    // The imagery's footprint: level-0 texels per pixel along the longer screen axis, allowing
    // two of anisotropy (sharper at grazing angles; the bilinear taps average the rest).
    let img_dx = length(dpdx(in.img));
    let img_dy = length(dpdy(in.img));
    let img_lambda = log2(max(max(min(img_dx, img_dy), 0.5 * max(img_dx, img_dy)), 1e-6));
    if (in.patched == 0u && patched_cell(node, in.grid)) {
        discard;
    }
    let ne = textureSample(normal_atlas, atlas_sampler, in.uv).xyz * 2.0 - 1.0;
    let ground_n = normalize(node.axis_e.xyz * ne.x + node.axis_n.xyz * ne.y + node.axis_u.xyz * ne.z);
    var n = ground_n;
    // A patch's normal: the node's own tilted by the edits' slope (edit_patch.rs: the
    // field is the slope along the ground plus the up times one plus how disturbed).
    let up = node.axis_u.xyz;
    let patch_up = dot(in.patch_normal, up);
    if (in.patched == 1u && patch_up > 0.5) {
        let slope = in.patch_normal - up * patch_up;
        n = normalize(ground_n / max(dot(ground_n, up), 0.2) + slope);
    }
    let distance_m = length(in.rel);
    if (sensor_on()) {
        // A thermal sensor: the material's temperature for this normal, as band radiance.
        var kind: u32;
        var texture_k = 0.0;
        if (ground_detail_on()) {
            let plane = vec2<f32>(dot(in.rel, g.detail_east.xyz), dot(in.rel, g.detail_north.xyz));
            let n1 = value_noise2(plane / g.noise1.w + g.noise1.xy);
            kind = material_at(node, in.uv, in.rel, n, n1).kind;
            // The ground's patchiness in temperature (moisture, cover, shade): about +-1 K
            // with the 19.3 m octave, +-0.5 K with the 2.7 m one where it resolves.
            let px_per_m = g.flags.w / max(distance_m, 1.0);
            let fade0 = clamp((g.noise0.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
            var fine = 0.0;
            if (fade0 > 0.0) {
                fine = (value_noise(plane / g.noise0.w + g.noise0.xy) - 0.5) * fade0;
            }
            texture_k = 2.0 * (n1.y - 0.5) + fine;
        } else {
            let size = vec2<f32>(textureDimensions(colour_atlas));
            kind = u32(round(textureLoad(colour_atlas, vec2<i32>(in.uv * size), 0).a * 255.0)) >> 4u;
        }
        if (is_sea(kind, in.rel)) {
            discard;
        }
        // The thermal channel does not see the edits' shapes yet (their slopes' sun and sky
        // would need the surface model's history): it takes the ground's own normal.
        let t_k = th_surface_temp(kind, ground_n) + texture_k + th_hot_spots(in.rel);
        return th_shown(t_k, th_emissivity(kind), ground_n, in.rel);
    }
    var surface: Surface;
    var albedo: vec3<f32>;
    if (ground_detail_on()) {
        // Detail: four octaves of value noise in the detail plane with incommensurate periods
        // (no visible tiling), faded out with distance before they alias; the finest is the
        // 2.7 m lattice eight times finer (0.34 m, so its 256-cell period wraps with the
        // coarser one's).
        let plane = vec2<f32>(dot(in.rel, g.detail_east.xyz), dot(in.rel, g.detail_north.xyz));
        let p0 = plane / g.noise0.w + g.noise0.xy;
        let p1 = plane / g.noise1.w + g.noise1.xy;
        let p2 = plane / g.noise2.w + g.noise2.xy;
        // Each octave fades out as its cells shrink below 6 pixels on screen (no aliasing, in
        // narrow and wide views alike).
        let px_per_m = g.flags.w / max(distance_m, 1.0);
        let fade_micro = clamp((g.noise0.w * 0.125 * px_per_m - 2.0) / 4.0, 0.0, 1.0);
        let fade0 = clamp((g.noise0.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
        let fade1 = clamp((g.noise1.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
        let fade2 = clamp((g.noise2.w * px_per_m - 2.0) / 4.0, 0.0, 1.0);
        // An octave that has faded out is not evaluated on GPUs whose threads skip a branch none of
        // them takes (the same colour, less work far away); lavapipe runs every branch under a mask,
        // so there a shader costs the sum of all its paths (measured: an `if` no pixel enters cost
        // as much as its body).
        var octaves = vec4<f32>(0.0);
        if (fade_micro > 0.0) {
            octaves.x = (value_noise(p0 * 8.0) - 0.5) * fade_micro;
        }
        if (fade0 > 0.0) {
            octaves.y = (value_noise(p0) - 0.5) * fade0;
        }
        // The 19.3 m octave also bends material borders (material_at's domain warp).
        let n1 = value_noise2(p1);
        octaves.z = (n1.x - 0.5) * fade1;
        if (fade2 > 0.0) {
            octaves.w = (value_noise(p2) - 0.5) * fade2;
        }
        surface = material_at(node, in.uv, in.rel, n, n1);
        let detail = 1.0 + dot(DETAIL[surface.kind], octaves);
        let tint = mix(vec3<f32>(1.0), MACRO_TINT[surface.kind], clamp(octaves.w + 0.5 * fade2, 0.0, 1.0) * fade2);
        albedo = surface.albedo * detail * tint;
        // Draped imagery over the materials where it covers, with the detail octaves finer
        // than its texels (so coarse imagery still shows texture flowing past up close).
        let drape = imagery_at(in.img, img_lambda);
        let under = clamp(0.5 + 0.5 * log2(drape.texel_m / vec2<f32>(g.noise0.w * 0.125, g.noise0.w)), vec2<f32>(0.0), vec2<f32>(1.0));
        let fine = 1.0 + DETAIL[surface.kind].x * octaves.x * under.x + DETAIL[surface.kind].y * octaves.y * under.y;
        // Premultiplied: the colour already carries its coverage.
        albedo = albedo * (1.0 - drape.colour.a) + drape.colour.rgb * fine;
    } else {
        // Plain: the colour texels blended bilinearly, with no detail (the baseline).
        let size = vec2<f32>(textureDimensions(colour_atlas));
        let nearest = textureLoad(colour_atlas, vec2<i32>(in.uv * size), 0);
        let tag = u32(round(nearest.a * 255.0));
        surface = Surface(
            textureSample(colour_atlas, atlas_sampler, in.uv).rgb,
            f32(tag & 15u) / 15.0,
            tag >> 4u,
        );
        albedo = surface.albedo;
    }
    if (is_sea(surface.kind, in.rel)) {
        discard;
    }
    if (in.patched == 1u) {
        // Earth the edits moved: bare, dark soil.
        let disturbed = clamp(patch_up - 1.0, 0.0, 1.0);
        let plane = vec2<f32>(dot(in.rel, g.detail_east.xyz), dot(in.rel, g.detail_north.xyz));
        let grain = value_noise(plane / 0.6 + vec2<f32>(17.0, 5.0));
        let soil = DISTURBED_SOIL * (0.75 + 0.5 * grain);
        albedo = mix(albedo, soil, 0.85 * disturbed);
        // Track marks: crushed vegetation and compacted, darker soil along the ruts, fading.
        albedo = mix(albedo, 0.8 * soil, 0.8 * in.marks.x);
        // Scorch: soot over the crater and its lip, ragged at its edge.
        let ragged = clamp(in.marks.y * 1.6 - 0.6 * value_noise(plane / 0.35 + vec2<f32>(3.0, 11.0)), 0.0, 1.0);
        albedo = mix(albedo, SCORCHED * (0.7 + 0.6 * grain), 0.9 * ragged);
    }
    if (nvg_on()) {
        albedo = nvg_terrain_albedo(surface.kind, albedo);
    }
    var colour = lit_at(albedo, n, in.rel);
    // Water and wet surfaces: a sun glint.
    let view_dir = -in.rel / max(distance_m, 1e-3);
    let h = normalize(view_dir + g.sun_dir.xyz);
    let spec = pow(max(dot(n, h), 0.0), 80.0) * surface.specular;
    colour += g.sun_colour.rgb * spec * 0.8;
    return vec4<f32>(apply_atmosphere_exposed(exposed(colour), in.rel), 1.0);
}
