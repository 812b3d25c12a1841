#version 450
#extension GL_GOOGLE_include_directive : require
// Culls one mesh's clusters (renderer/lod/cluster_lod.hpp) for one phase of
// a frame and appends the survivors' draws (DrawElementsIndirectCommand) to
// the phase's slot, drawn by glMultiDrawElementsIndirectCount
// (renderer/passes/lod_draw.cpp; docs/lod.md). Per cluster, in order:
//   level      the cell's level is the coarsest whose error, projected at the
//              cell's nearest point, is at most max_error_px (0: level 0 only)
//   frustum    the bounds' corners all outside one clip plane (or, for a
//              pick, the bounds' screen rectangle off the pick region)
//   backface   every triangle faces away from the eye (normal cone against
//              the bounding sphere; only for closed surfaces seen from
//              outside their bounds)
//   occlusion  the bounds' nearest depth behind the farthest depth of the
//              depth pyramid over their screen rectangle
// Bindings 20-24 and texture unit 15: the passes that draw through it keep
// theirs (VOIT's buffers at 0-4, the voxelization's range at 0).
// Modes: ALL draws what passes level and frustum (and backface when
// enabled); FIRST draws the clusters visible in the last frame (or, without
// one, the nearest batch) without an occlusion test; TEST draws the
// clusters of its batch not drawn yet that the pyramid does not hide;
// FINAL draws nothing: it marks what is visible for the next frame and
// counts what each test culled.
layout(local_size_x = 64) in;

#define MODE_ALL 0u
#define MODE_FIRST 1u
#define MODE_TEST 2u
#define MODE_FINAL 3u

struct Cell {
    vec3 lo;
    uint levels;
    vec3 hi;
    uint first_cluster;
    float error[8];      // mm: geometric error or half the RMS edge, whichever is larger
    float geometric[8];  // (statistics only)
};
struct Cluster {
    vec3 lo;
    uint cell;
    vec3 hi;
    uint level;
    vec3 axis;
    float cos_angle;
    vec3 centre;
    float radius;
    uint first_index;
    uint index_count;
    uint pad0;
    uint pad1;
};
struct Command {
    uint count;
    uint instances;
    uint first_index;
    int base_vertex;
    uint base_instance; // the cluster's first triangle in the index buffer: picks name triangles from it
};

layout(std430, binding = 20) readonly buffer Cells { Cell cells[]; };
layout(std430, binding = 21) readonly buffer Clusters { Cluster clusters[]; };
// Per cluster: bit 0 visible last frame, bit 1 drawn this frame; then per
// cell (from word cluster_count on): 1 + the level it was visible at in the
// last frame (0: none of it), so that where a cell's level changed since
// (a drag's coarser bound, a zoom) the first phase draws the new level's
// clusters over the old level's visible ones (seen_at_another_level)
// instead of testing everything against a pyramid of almost nothing.
layout(std430, binding = 22) buffer State { uint state[]; };
layout(std430, binding = 23) writeonly buffer Commands { Command commands[]; };
// [0..11]: draws per slot; then the statistics (lod_draw.cpp, LodCounter).
layout(std430, binding = 24) buffer Counts { uint counts[]; };
layout(binding = 14) uniform sampler2D pyramid; // reversed-Z farthest depth, level 0 at 2x2 pixels

uniform mat4 view_projection;
uniform vec3 eye;
uniform float px_per_mm_at_1mm; // image height / (2 tan(fov_y / 2))
uniform float max_error_px;     // 0: level 0 only
uniform float near_plane;
uniform uint cluster_count;
uniform uint mode;
uniform uint slot;
uniform bool history;       // the state's bit 0 is from the last frame
uniform vec2 batch;         // without history: the nearest distance (mm) of this phase's clusters, [x, y)
uniform bool backface;      // cull back-facing clusters
uniform bool frustum;       // cull clusters outside the view (or the pick region)
uniform bool count_tests;   // add this dispatch's culling figures to the statistics (one dispatch a frame)
uniform bool count_draws;   // add its draws
uniform vec2 viewport;      // pixels
uniform vec4 region;        // a pick region in GL pixels (x0, y0, x1, y1); x1 <= x0: none
uniform int pyramid_levels;
// Level 0's size (powers of two). Given, not asked with textureSize(): on
// Mesa's llvmpipe that gave sizes for the levels above 4 that clamped the
// lookups into too few texels, and clusters on the screen went missing.
uniform ivec2 pyramid_size;

const uint C_SELECTED = 12u, C_FRUSTUM = 13u, C_BACKFACE = 14u, C_OCCLUDED = 15u, C_DRAWN = 16u, C_TRIANGLES = 17u,
           C_OTHER_LEVEL = 18u;

uint select_level(Cell c) {
    if (max_error_px <= 0.0) return 0u;
    vec3 nearest = clamp(eye, c.lo, c.hi);
    float d = max(length(eye - nearest), near_plane);
    float limit = max_error_px * d / px_per_mm_at_1mm;
    for (uint l = c.levels - 1u; l > 0u; --l)
        if (c.error[l] <= limit) return l;
    return 0u;
}

// The bounds on screen: rectangle (pixels, GL's bottom-up) and nearest
// reversed-Z depth; false when a corner is at or behind the eye plane
// (the bounds cross the near plane: never culled by the rectangle).
bool project(Cluster c, out vec4 rect, out float nearest, out bool outside) {
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    nearest = 0.0;
    bvec4 all_out = bvec4(true); // x < -w, x > w, y < -w, y > w
    bool all_far = true, all_near = true;
    bool behind = false;
    for (int i = 0; i < 8; ++i) {
        vec3 p = vec3((i & 1) != 0 ? c.hi.x : c.lo.x, (i & 2) != 0 ? c.hi.y : c.lo.y, (i & 4) != 0 ? c.hi.z : c.lo.z);
        vec4 q = view_projection * vec4(p, 1.0);
        all_out = bvec4(all_out.x && q.x < -q.w, all_out.y && q.x > q.w, all_out.z && q.y < -q.w,
                        all_out.w && q.y > q.w);
        all_far = all_far && q.z < 0.0;    // reversed Z: beyond the far plane
        all_near = all_near && q.z > q.w;  // in front of the near plane
        if (q.w <= 1e-6) {
            behind = true;
            continue;
        }
        vec3 n = q.xyz / q.w;
        lo = min(lo, n.xy);
        hi = max(hi, n.xy);
        nearest = max(nearest, n.z);
    }
    outside = any(all_out) || all_far || all_near;
    rect = vec4((lo * 0.5 + 0.5) * viewport, (hi * 0.5 + 0.5) * viewport);
    return !behind;
}

bool back_facing(Cluster c) {
    if (!backface || c.cos_angle <= 0.0) return false;
    vec3 w = c.centre - eye;
    float L = length(w);
    if (L <= c.radius) return false;
    // Every normal n in the cone has dot(n, w) >= L cos(beta + alpha); the
    // cluster faces away when that exceeds the radius.
    float cb = dot(w, c.axis) / L, sb = sqrt(max(0.0, 1.0 - cb * cb));
    float ca = c.cos_angle, sa = sqrt(max(0.0, 1.0 - ca * ca));
    return L * (cb * ca - sb * sa) > c.radius;
}

bool occluded(vec4 rect, float nearest) {
    vec2 lo = clamp(rect.xy, vec2(0.0), viewport - 1.0), hi = clamp(rect.zw, vec2(0.0), viewport - 1.0);
    // Level 0's texels are 2x2 pixels: the level whose texels are at least
    // the rectangle's size, where it spans at most 2x2 of them.
    vec2 size = max(hi - lo, vec2(2.0));
    int level = clamp(int(ceil(log2(max(size.x, size.y)))) - 1, 0, pyramid_levels - 1);
    ivec2 top = max(pyramid_size >> level, ivec2(1)) - 1;
    ivec2 a = min(ivec2(floor(lo)) >> (level + 1), top), b = min(ivec2(floor(hi)) >> (level + 1), top);
    float farthest = 1.0;
    for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) farthest = min(farthest, texelFetch(pyramid, ivec2(x, y), level).r);
    return nearest < farthest;
}

void emit(uint k, Cluster c) {
    uint i = atomicAdd(counts[slot], 1u);
    commands[slot * cluster_count + i] = Command(c.index_count, 1u, c.first_index, 0, c.first_index / 3u);
    if (count_draws) {
        atomicAdd(counts[C_DRAWN], 1u);
        atomicAdd(counts[C_TRIANGLES], c.index_count / 3u);
    }
}

// A cluster of a cell that the last frame saw at another level (a drag's
// coarser bound, a zoom) counts as visible last frame if a cluster of that
// level its bounds overlap was: the cell's clusters are in order of level
// (a cell has a few dozen).
bool seen_at_another_level(Cluster c) {
    uint seen = state[cluster_count + c.cell];
    if (seen == 0u || seen == c.level + 1u) return false;
    for (uint j = cells[c.cell].first_cluster; j < cluster_count; ++j) {
        Cluster o = clusters[j];
        if (o.cell != c.cell || o.level + 1u > seen) break;
        if (o.level + 1u == seen && (state[j] & 1u) != 0u && all(lessThanEqual(o.lo, c.hi)) &&
            all(lessThanEqual(c.lo, o.hi)))
            return true;
    }
    return false;
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= cluster_count) return;
    Cluster c = clusters[k];
    uint st = state[k];
    bool final_pass = mode == MODE_FINAL;
    if (c.level != select_level(cells[c.cell])) {
        if (final_pass) state[k] = 0u;
        if (count_tests) atomicAdd(counts[C_OTHER_LEVEL], 1u);
        return;
    }
    if (count_tests) atomicAdd(counts[C_SELECTED], 1u);
    vec4 rect;
    float nearest;
    bool outside;
    bool in_front = project(c, rect, nearest, outside);
    if (region.z > region.x && in_front)
        outside = outside || rect.z < region.x || rect.x >= region.z || rect.w < region.y || rect.y >= region.w;
    if (frustum && outside) {
        if (final_pass) state[k] = 0u;
        if (count_tests) atomicAdd(counts[C_FRUSTUM], 1u);
        return;
    }
    if (back_facing(c)) {
        if (final_pass) state[k] = 0u;
        if (count_tests) atomicAdd(counts[C_BACKFACE], 1u);
        return;
    }
    if (mode == MODE_ALL) {
        emit(k, c);
        return;
    }
    float dist = length(eye - clamp(eye, c.lo, c.hi));
    bool in_batch = dist >= batch.x && dist < batch.y;
    if (mode == MODE_FIRST) {
        bool first = history ? (st & 1u) != 0u || seen_at_another_level(c) : in_batch;
        if (first) emit(k, c);
        state[k] = (st & 1u) | (first ? 2u : 0u);
        return;
    }
    bool drawn = (st & 2u) != 0u;
    if (mode == MODE_TEST) {
        if (drawn || !(history || in_batch)) return;
        if (in_front && occluded(rect, nearest)) return;
        emit(k, c);
        state[k] = st | 2u;
        return;
    }
    // MODE_FINAL: visible next frame if drawn and not hidden by the whole frame's depth.
    bool hidden = in_front && occluded(rect, nearest);
    state[k] = drawn && !hidden ? 1u : 0u;
    if (drawn && !hidden) state[cluster_count + c.cell] = c.level + 1u; // one level a cell: every writer writes the same
    if (!drawn && count_tests) atomicAdd(counts[C_OCCLUDED], 1u);
}
