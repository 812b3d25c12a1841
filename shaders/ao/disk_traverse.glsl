// The disk hierarchy's traversal (docs/ao.md, "Disk AO on the GPU"): the
// GLSL mirror of disk_occlusion_t<float> in renderer/ao/disk_hierarchy.cpp,
// line by line, so that the GPU's element terms and gathered pixels equal
// the CPU's within float rounding (tests/gl/disk_ao_test.cpp). Needs the
// DiskParams block (disk_params.glsl through std140.glsl) and
// disk_geometry.glsl.

// DiskNode (renderer/ao/disk_hierarchy.hpp), std430: 48 bytes.
struct DiskNode {
    vec4 centre_area;  // xyz centre, w area
    vec4 normal_bound; // xyz unit normal (zero when cancelled), w bounding radius
    ivec4 links;       // skip, first child (-1: leaf), first triangle, triangle count
};

layout(std430, binding = 0) readonly buffer DiskNodes { DiskNode disk_nodes[]; };
layout(std430, binding = 1) readonly buffer DiskTriangles { vec4 disk_triangles[]; }; // 3 per triangle
layout(std430, binding = 3) readonly buffer DiskTermsIn { float disk_terms_in[]; };  // accessibility per node

// Occlusion (0 open .. 1) at the receiver (p_in, n) within R. One stackless
// walk over every tree (a root's skip is the next tree's root). side: +1
// front faces occlude (disk_occlusion), -1 back faces (a receiver whose
// normal points into the solid: disk_occlusion_sided).
float disk_occlusion(vec3 p_in, vec3 n, float side) {
    float R = max(radius, 0.0);
    float R2 = R * R;
    float eps = traversal_epsilon;
    float k = distance_attenuation;
    float t = triangle_attenuation;
    float clip_eps = clip_epsilon;
    bool modulate = use_terms != 0;
    // Self-occlusion: the receiver raised along its normal by receiver_offset x R.
    vec3 p = p_in + receiver_offset * R * n;

    float occlusion = 0.0;
    int count = node_count;
    int i = 0;
    while (i < count) {
        DiskNode node = disk_nodes[i];
        vec3 c = node.centre_area.xyz;
        float area = node.centre_area.w;
        vec3 m = node.normal_bound.xyz;
        float bound = node.normal_bound.w;
        int skip = node.links.x;
        int child = node.links.y;
        vec3 v = c - p;
        float d2 = dot(v, v);
        // Wholly beyond R: nothing below can occlude.
        if (d2 >= (R + bound) * (R + bound)) {
            i = skip;
            continue;
        }
        float term = modulate ? disk_terms_in[i] : 1.0;
        float modulation = disk_triangle_attenuation(term, t);
        bool near = d2 < eps * area;
        if (child >= 0) {
            // One disk only when far and wholly within R; else its children.
            bool inside = bound <= R && d2 <= (R - bound) * (R - bound);
            if (near || !inside) {
                i = child;
                continue;
            }
            occlusion += disk_form_factor(p, n, c, side * m, area) * modulation * disk_distance_attenuation(d2, k);
            i = skip;
            continue;
        }
        if (near) {
            // Its triangles, clipped, exact form factor, front faces only;
            // each counted when its centroid is within R.
            int first = node.links.z;
            int end = first + node.links.w;
            for (int tri = first; tri < end; ++tri) {
                vec3 v0 = disk_triangles[3 * tri].xyz;
                vec3 v1 = disk_triangles[3 * tri + 1].xyz;
                vec3 v2 = disk_triangles[3 * tri + 2].xyz;
                vec3 g = (v0 + v1 + v2) * (1.0 / 3.0) - p;
                float g2 = dot(g, g);
                if (g2 > R2) continue;
                float ff = max(side * disk_clipped_triangle_form_factor(p, n, v0, v1, v2, clip_eps), 0.0);
                occlusion += ff * modulation * disk_distance_attenuation(g2, k);
            }
        } else if (d2 <= R2) {
            occlusion += disk_form_factor(p, n, c, side * m, area) * modulation * disk_distance_attenuation(d2, k);
        }
        i = skip;
    }
    return clamp(occlusion, 0.0, 1.0);
}
