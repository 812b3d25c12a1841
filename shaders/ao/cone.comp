#version 450
#extension GL_GOOGLE_include_directive : require
// Cone-traced ambient occlusion in the slicemap (docs/ao.md). Per visible
// pixel: cones over the hemisphere rotated to the normal; along each cone,
// spheres sized to its cross-section up to R; a sphere's occlusion is the
// occupied fraction of its volume above the tangent plane, measured on
// Poisson-disk columns parallel to the grid's z: each column's [z_in, z_out]
// becomes a bit range, masked and counted with bitCount. Spheres combine
// front to back, cones average. Output: 1 = unoccluded, NaN = background.
#include "ao_common.glsl"
#include "std140.glsl"
#include "cone_params.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D depth_tex;      // reversed-Z
layout(binding = 1) uniform sampler2D normal_tex;     // world (LPS) normal, w = 1 on geometry
layout(binding = 2) uniform usampler2DArray slicemap;
layout(std430, binding = 0) readonly buffer ZRange { uint zmin_bits; uint zmax_bits; };
// [cones: axis xyz, sin(half-angle)] [sets: cos a, sin a, sphere offset] [sets x samples: disk xy]
layout(std430, binding = 1) readonly buffer Pattern { vec4 pattern[]; };
#ifdef COARSE
// Coarse AO for ao_upsample.comp: (AO, linear depth of the source pixel,
// its view-space normal octahedron-encoded), so the upsampling reads one
// texel per neighbour.
layout(binding = 0, rgba32f) uniform image2D ao_image;
#else
layout(binding = 0, r32f) uniform image2D ao_image;   // running mean over still frames
#endif


uint hash(uvec2 v) { // PCG-style 2D hash
    v = v * 1664525u + 1013904223u;
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v ^= v >> 16u;
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v ^= v >> 16u;
    return v.x ^ v.y;
}

// Set voxels in [b0, b1) of one texel's column.
int count_bits(ivec2 texel, int b0, int b1) {
    if (b1 <= b0 || any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, grid))) return 0;
    int n = 0;
    for (int l = b0 >> 7; l <= (b1 - 1) >> 7; ++l) {
        uvec4 w = texelFetch(slicemap, ivec3(texel, l), 0);
        int base = 128 * l;
        for (int c = 0; c < 4; ++c) {
            int lo = b0 - base - 32 * c, hi = b1 - base - 32 * c;
            n += bitCount(w[c] & mask_from(lo) & ~mask_from(hi));
        }
    }
    return n;
}

void main() {
    // The AO image may be coarser than the frame (resolution < 1): each of
    // its pixels traces from the frame pixel at the centre of its block, and
    // ao_upsample.comp brings it back to full size.
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, ao_size))) return;
    ivec2 pix = ao_source_pixel(q, ao_size, size);
    float d = texelFetch(depth_tex, pix, 0).r;
    if (d <= 0.0) {
        imageStore(ao_image, q, vec4(uintBitsToFloat(0x7FC00000u)));
        return;
    }
    // Eye-space point (camera looks down -z) and normal.
    float D = near_plane * far_plane / (d * (far_plane - near_plane) + near_plane);
    vec2 ndc = (vec2(pix) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec3 p = vec3(ndc * D / proj_scale, -D);
    vec3 n = normalize(world_to_view * texelFetch(normal_tex, pix, 0).xyz);

    vec2 range = slicemap_range(zmin_bits, zmax_bits, scene_far, radius, near_margin);
    float dz = (range.y - range.x) / float(BITS);
    float texel_w = 2.0 * D / (sm_proj_scale.y * float(grid.y)); // grid texel footprint at this depth
    // The surface's own voxels are not occluders: count only above the
    // tangent plane raised by the voxel's z extent and the texel's footprint
    // on a slope.
    float beta = bias * (abs(n.z) * dz + 0.5 * (abs(n.x) + abs(n.y)) * texel_w);
    float np = dot(n, p) + beta;

    // Tangent frame, turned by this pixel's jitter set.
    vec3 t = normalize(abs(n.z) < 0.999 ? cross(vec3(0.0, 0.0, 1.0), n) : cross(vec3(1.0, 0.0, 0.0), n));
    vec3 b = cross(n, t);
    int set = int(hash(uvec2(pix)) % uint(sets));
    vec4 js = pattern[cones + set];
    vec3 tx = js.x * t + js.y * b, ty = -js.y * t + js.x * b;
    int sample_base = cones + sets + set * samples;

    float r_min = max(dz, texel_w);
    float blocked_sum = 0.0;
    for (int c = 0; c < cones; ++c) {
        vec4 cone = pattern[c];
        vec3 dir = normalize(cone.x * tx + cone.y * ty + cone.z * n);
        float s = cone.w;
        float t_max = radius / (1.0 + s);                  // the last sphere reaches R
        float t_min = min(t_max, max(r_min / max(s, 0.05), 2.0 * r_min));
        float blocked = 0.0;
        for (int i = 0; i < spheres; ++i) {
            float u = spheres == 1 ? 1.0 : clamp((float(i) + 0.5 + js.z) / float(spheres), 0.0, 1.0);
            float ti = t_min * pow(t_max / t_min, u);       // geometric: spheres grow with the cone
            float r = ti * s;
            vec3 cen = p + ti * dir;
            float Dc = -cen.z;
            float occ_len = 0.0, tot_len = 0.0;
            for (int k = 0; k < samples; ++k) {
                vec2 q = pattern[sample_base + k].xy;
                vec2 xy = cen.xy + r * q;
                float h = r * sqrt(max(0.0, 1.0 - dot(q, q)));
                float D0 = Dc - h, D1 = Dc + h;
                // Above the raised tangent plane: n.z * D < n.xy . xy - n.p - beta.
                float a = dot(n.xy, xy) - np;
                if (n.z > 1e-4) D1 = min(D1, a / n.z);
                else if (n.z < -1e-4) D0 = max(D0, a / n.z);
                else if (a <= 0.0) continue;
                if (D1 <= D0) continue;
                tot_len += D1 - D0;
                vec2 g = (sm_proj_scale * xy / max(Dc, 1e-6)) * 0.5 + 0.5;
                ivec2 texel = ivec2(floor(g * vec2(grid)));
                occ_len += float(count_bits(texel, voxel_at(D0, range), voxel_at(D1, range))) * dz;
            }
            float o = tot_len > 0.0 ? clamp(occ_len / tot_len, 0.0, 1.0) : 0.0;
            // From occupied volume to blocked rays: a plane cutting a cap of
            // volume fraction o off the sphere blocks, on average over its
            // orientation, a fraction sqrt(o) (1.15 - 0.15 o) of the rays
            // crossing the sphere (docs/ao.md); a thin cap blocks far more
            // rays than its volume says.
            o = mix(o, sqrt(o) * (1.15 - 0.15 * o), ray_weight);
            float x = ti / radius;
            o /= 1.0 + attenuation * x * x;
            blocked = mix(1.0 - (1.0 - blocked) * (1.0 - o), max(blocked, o), persistence);
        }
        blocked_sum += blocked;
    }
    float ao = clamp(1.0 - strength * blocked_sum / float(cones), 0.0, 1.0);
    if (history_weight > 0.0) ao = mix(ao, imageLoad(ao_image, q).r, history_weight);
#ifdef COARSE
    imageStore(ao_image, q, vec4(ao, D, oct_encode(n)));
#else
    imageStore(ao_image, q, vec4(ao));
#endif
}
