#version 450
// GPU marching cubes over a batch of chunks (renderer/gpu/gpu_extract.cpp).
// Same conventions as the CPU path (renderer/surface/extract.hpp): a sample >= iso
// is inside, t = (iso - s0) / (s1 - s0) in double precision from the edge's
// lower-index end, clamped to [edge_margin, 1 - edge_margin] on every edge (a
// tie gets its own vertex per cut edge, just inside the edge,
// extract.hpp kEdgeMargin), VTK's MC table, world = index_to_lps * index,
// normals = -world gradient. One source, five passes selected by PASS:
//   1 MARK         per chunk sample and axis: mark the vertex slot a cut edge needs
//   2 COUNT_VERTS  per slot: count marked slots per chunk
//   3 WRITE_VERTS  per slot: number the vertex and write it
//   4 COUNT_TRIS   per cell: count triangles per chunk
//   5 WRITE_TRIS   per cell: write triangles (chunk-local vertex numbers)
#ifndef PASS
#define PASS 1
#endif

layout(local_size_x = 64) in;

struct Chunk {
    ivec4 p0;      // first sample of the chunk (global index)
    ivec4 np;      // samples per axis
    ivec4 blo;     // first sample of the halo block
    ivec4 bn;      // block samples per axis
    uvec4 offs;    // x: sample offset, y: slot offset, z: vertex base, w: triangle base
};

layout(std430, binding = 0) readonly buffer Samples { float samples[]; };
layout(std430, binding = 1) readonly buffer Chunks { Chunk chunks[]; };
layout(std430, binding = 2) buffer Slots { uint slots[]; };        // 0 none, 1 marked, k+2 vertex k
layout(std430, binding = 3) buffer Counts { uint counts[]; };      // per chunk
layout(std430, binding = 4) writeonly buffer Positions { float positions[]; };
layout(std430, binding = 5) writeonly buffer Normals { float normals[]; };
layout(std430, binding = 6) writeonly buffer Keys { uvec2 keys[]; };
layout(std430, binding = 7) writeonly buffer Border { uint border[]; };
layout(std430, binding = 8) writeonly buffer Triangles { uint triangles[]; };
layout(std430, binding = 9) readonly buffer Table { int tri_edges[256 * 16]; };
layout(std430, binding = 10) readonly buffer EdgeTable { ivec4 edges[12]; }; // xyz offset, w axis

uniform dmat4 index_to_lps;
uniform dmat3 normal_matrix;
uniform double iso;
uniform double edge_margin; // kEdgeMargin (1/128, exact in double)
uniform ivec3 dims;
uniform int chunk_size;
uniform int flip;
uniform int want_normals;

Chunk ch;

float S(ivec3 g) {
    ivec3 b = g - ch.blo.xyz;
    return samples[ch.offs.x + uint(b.x + ch.bn.x * (b.y + ch.bn.y * b.z))];
}
bool inside(ivec3 g) { return double(S(g)) >= iso; }
uint slot_index(ivec3 l, int k) { return ch.offs.y + uint(3 * (l.x + ch.np.x * (l.y + ch.np.y * l.z)) + k); }

dvec3 gradient(ivec3 g) {
    dvec3 r;
    for (int a = 0; a < 3; ++a) {
        ivec3 lo = g, hi = g;
        double scale = 0.5;
        if (dims[a] < 2) { r[a] = 0.0; continue; }
        if (g[a] == 0) { hi[a] += 1; scale = 1.0; }
        else if (g[a] >= dims[a] - 1) { lo[a] -= 1; scale = 1.0; }
        else { lo[a] -= 1; hi[a] += 1; }
        r[a] = scale * (double(S(hi)) - double(S(lo)));
    }
    return r;
}

// The slot whose vertex lies on edge (l, axis) of the chunk lattice: every
// cut edge has its own (no slot for a vertex on a sample).
uint vertex_slot(ivec3 l, int axis) { return slot_index(l, axis); }

bool on_border(int p, int a) { return p % chunk_size == 0 && p > 0 && p < dims[a] - 1; }

void main() {
    ch = chunks[gl_WorkGroupID.y];
    const uint chunk = gl_WorkGroupID.y;
    const uint item = gl_GlobalInvocationID.x;
    const uint npts = uint(ch.np.x * ch.np.y * ch.np.z);

#if PASS == 1 || PASS == 2 || PASS == 3
    // Items are (sample, k): k 0..2 the edge along x/y/z.
    if (item >= npts * 3u) return;
    const int k = int(item % 3u);
    const uint p = item / 3u;
    const ivec3 l = ivec3(int(p % uint(ch.np.x)), int((p / uint(ch.np.x)) % uint(ch.np.y)), int(p / uint(ch.np.x * ch.np.y)));
#if PASS == 1
    ivec3 e = ivec3(0); e[k] = 1;
    if (l[k] + 1 >= ch.np[k]) return;
    const ivec3 g = ch.p0.xyz + l;
    if (inside(g) != inside(g + e)) slots[vertex_slot(l, k)] = 1u;
#elif PASS == 2
    if (slots[slot_index(l, k)] == 1u) atomicAdd(counts[chunk], 1u);
#else
    const uint s = slot_index(l, k);
    if (slots[s] != 1u) return;
    const uint local = atomicAdd(counts[chunk], 1u);
    slots[s] = local + 2u;
    const uint v = ch.offs.z + local;
    const ivec3 g = ch.p0.xyz + l;
    dvec3 ip = dvec3(g);
    dvec3 n = dvec3(0.0);
    bool b = false;
    {
        ivec3 e = ivec3(0); e[k] = 1;
        precise double s0 = double(S(g)), s1 = double(S(g + e));
        precise double t = clamp((iso - s0) / (s1 - s0), edge_margin, 1.0 - edge_margin);
        ip[k] += t;
        if (want_normals != 0) {
            dvec3 g0 = gradient(g), g1 = gradient(g + e);
            n = g0 + t * (g1 - g0);
        }
        for (int a = 0; a < 3; ++a)
            if (a != k && on_border(g[a], a)) b = true;
    }
    precise dvec3 w = dvec3(index_to_lps * dvec4(ip, 1.0));
    positions[3u * v + 0u] = float(w.x);
    positions[3u * v + 1u] = float(w.y);
    positions[3u * v + 2u] = float(w.z);
    if (want_normals != 0) {
        dvec3 wn = -(normal_matrix * n);
        double len = length(wn);
        vec3 fn = len > 0.0 ? vec3(wn / len) : vec3(0.0);
        normals[3u * v + 0u] = fn.x;
        normals[3u * v + 1u] = fn.y;
        normals[3u * v + 2u] = fn.z;
    }
    // Key: 4 * (global linear sample index) + k, as a 64-bit pair.
    const uint lin_lo = uint(g.x) + uint(dims.x) * (uint(g.y) + uint(dims.y) * uint(g.z));
    // The product may exceed 32 bits: compute it in two halves with umulExtended.
    uint hi1, lo1, hi2, lo2;
    umulExtended(uint(g.y) + uint(dims.y) * uint(g.z), uint(dims.x), hi1, lo1);
    uint carry;
    lo2 = uaddCarry(lo1, uint(g.x), carry);
    hi2 = hi1 + carry;
    // times 4 plus k
    const uint key_lo = (lo2 << 2) | uint(k);
    const uint key_hi = (hi2 << 2) | (lo2 >> 30);
    keys[v] = uvec2(key_lo, key_hi);
    border[v] = b ? 1u : 0u;
#endif

#else // PASS 4, 5: per cell
    const uvec3 nc = uvec3(ch.np.xyz - 1);
    if (item >= nc.x * nc.y * nc.z) return;
    const ivec3 c = ivec3(int(item % nc.x), int((item / nc.x) % nc.y), int(item / (nc.x * nc.y)));
    const ivec3 corner[8] = ivec3[8](ivec3(0, 0, 0), ivec3(1, 0, 0), ivec3(1, 1, 0), ivec3(0, 1, 0),
                                     ivec3(0, 0, 1), ivec3(1, 0, 1), ivec3(1, 1, 1), ivec3(0, 1, 1));
    int cs = 0;
    for (int i = 0; i < 8; ++i)
        if (inside(ch.p0.xyz + c + corner[i])) cs |= 1 << i;
    if (cs == 0 || cs == 255) return;
    for (int t = 0; t < 5; ++t) {
        if (tri_edges[cs * 16 + 3 * t] < 0) break;
        uint vid[3];
        for (int j = 0; j < 3; ++j) {
            ivec4 e = edges[tri_edges[cs * 16 + 3 * t + j]];
            vid[j] = slots[vertex_slot(c + e.xyz, e.w)] - 2u;
        }
#if PASS == 4
        atomicAdd(counts[chunk], 1u);
#else
        const uint tri = ch.offs.w + atomicAdd(counts[chunk], 1u);
        triangles[3u * tri + 0u] = vid[0];
        triangles[3u * tri + 1u] = flip != 0 ? vid[2] : vid[1];
        triangles[3u * tri + 2u] = flip != 0 ? vid[1] : vid[2];
#endif
    }
#endif
}
