// Thin screen-aligned quads for world-space lines (lightning bolts, rain streaks): the two ends
// projected, clipped to the near plane, and widened by a fixed number of pixels, so a line is
// as wide on screen at any distance and never vanishes between pixels.

struct LineCorner {
    clip: vec4<f32>,
    // -1..1 across the line, and 0..1 along it.
    across: f32,
    along: f32,
};

// Corner `corner` (0..5, two triangles) of the quad around the eye-relative segment a-b,
// `half_width_px` wide on each side (and as much past each end), in a viewport of `size_px`.
fn line_corner(a: vec3<f32>, b: vec3<f32>, half_width_px: f32, size_px: vec2<f32>, corner: u32) -> LineCorner {
    var ca = g.view_proj * vec4<f32>(a, 1.0);
    var cb = g.view_proj * vec4<f32>(b, 1.0);
    var out: LineCorner;
    let near_w = 0.05;
    if (ca.w < near_w && cb.w < near_w) {
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
        out.across = 0.0;
        out.along = 0.0;
        return out;
    }
    if (ca.w < near_w) {
        ca = mix(ca, cb, (near_w - ca.w) / (cb.w - ca.w));
    } else if (cb.w < near_w) {
        cb = mix(cb, ca, (near_w - cb.w) / (ca.w - cb.w));
    }
    let pa = ca.xy / ca.w * size_px * 0.5;
    let pb = cb.xy / cb.w * size_px * 0.5;
    var dir = pb - pa;
    let len = length(dir);
    if (len < 1e-4) {
        dir = vec2<f32>(1.0, 0.0);
    } else {
        dir = dir / len;
    }
    let normal = vec2<f32>(-dir.y, dir.x);
    // Corners: (end, side) for two triangles.
    var ends = array<f32, 6>(0.0, 1.0, 1.0, 0.0, 1.0, 0.0);
    var sides = array<f32, 6>(-1.0, -1.0, 1.0, -1.0, 1.0, 1.0);
    let e = ends[corner];
    let s = sides[corner];
    var c = ca;
    if (e > 0.5) {
        c = cb;
    }
    let offset_px = normal * s * half_width_px + dir * (e * 2.0 - 1.0) * half_width_px;
    c = vec4<f32>(c.xy + offset_px / (size_px * 0.5) * c.w, c.z, c.w);
    out.clip = c;
    out.across = s;
    out.along = e;
    return out;
}
