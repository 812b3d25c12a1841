// Cone tracing through the slicemap (docs/ao.md), shared by the cone-AO
// pass (cone.comp: opaque surfaces, per pixel) and the VOIT resolve
// (render/oit_resolve.comp: translucent fragments). Needs ao_common.glsl,
// std140.glsl and cone_params.glsl included first. The including shader may
// move the bindings (the resolve's own buffers take 0..3).
#ifndef CONE_SLICEMAP_BINDING
#define CONE_SLICEMAP_BINDING 2
#endif
#ifndef CONE_ZRANGE_BINDING
#define CONE_ZRANGE_BINDING 0
#endif
#ifndef CONE_PATTERN_BINDING
#define CONE_PATTERN_BINDING 1
#endif
layout(binding = CONE_SLICEMAP_BINDING) uniform usampler2DArray slicemap;
layout(std430, binding = CONE_ZRANGE_BINDING) readonly buffer ZRange { uint zmin_bits; uint zmax_bits; };
// [cones: axis xyz, sin(half-angle)] [sets: cos a, sin a, sphere offset] [sets x samples: disk xy]
layout(std430, binding = CONE_PATTERN_BINDING) readonly buffer Pattern { vec4 pattern[]; };

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

// AO at eye-space point p with unit eye-space normal n, traced from frame
// pixel pix (whose hash picks the jitter set): 1 = unoccluded.
float cone_ao(vec3 p, vec3 n, ivec2 pix) {
    if (zmax_bits == 0u) return 1.0; // no opaque surface in view: an empty slicemap
    float D = -p.z;
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
        float blocked = 0.0, axis_hit = 0.0;
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
            // The cone's axis as a ray (axis_weight > 0): five voxel probes
            // per sphere along it, 0.4 r apart, above the raised tangent
            // plane. Spheres see a thin wall or a narrow cavity's sides as a
            // little volume; a ray along the axis that meets any set voxel
            // is blocked, and the cone counts as at least axis_weight blocked.
            for (int a = -2; a <= 2 && axis_weight > 0.0; ++a) {
                vec3 q = p + ti * (1.0 + 0.4 * float(a) * s) * dir;
                if (dot(n, q) <= np) continue;
                float Dq = -q.z;
                vec2 g = (sm_proj_scale * q.xy / max(Dq, 1e-6)) * 0.5 + 0.5;
                ivec2 texel = ivec2(floor(g * vec2(grid)));
                int kb = int(floor((Dq - range.x) / dz));
                if (kb >= 0 && kb < BITS && count_bits(texel, kb, kb + 1) > 0) axis_hit = 1.0;
            }
        }
        blocked = max(blocked, axis_weight * axis_hit);
        blocked_sum += blocked;
    }
    return clamp(1.0 - strength * blocked_sum / float(cones), 0.0, 1.0);
}
