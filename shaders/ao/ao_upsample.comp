#version 450
#extension GL_GOOGLE_include_directive : require
// Joint bilateral upsampling of a coarse AO image (--ao-resolution < 1) to
// the frame: each frame pixel averages the AO of its 2x2 nearest coarse
// pixels with bilinear weights, times how well the coarse
// pixel's source point lies on this pixel's tangent plane and how alike the
// normals are. So AO does not bleed across silhouettes and creases, where
// plain bilinear upsampling would halo. Output: 1 = unoccluded, NaN =
// background, as cone.comp writes at full resolution.
#include "ao_common.glsl"
#include "std140.glsl"
#include "upsample_params.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D depth_tex;   // reversed-Z
layout(binding = 1) uniform sampler2D normal_tex;  // world normal
layout(binding = 2) uniform sampler2D ao_low;      // coarse: AO, linear depth, octahedral view normal
layout(binding = 0, r32f) writeonly uniform image2D ao_image;


vec3 eye_point_at(ivec2 pix, float D) { return eye_point_at_depth(pix, size, proj_scale, D); }
vec3 eye_point(ivec2 pix, float d) { // d: reversed-Z depth
    return eye_point_at(pix, linear_depth(d, near_plane, far_plane));
}

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pix, size))) return;
    float d = texelFetch(depth_tex, pix, 0).r;
    if (d <= 0.0) {
        imageStore(ao_image, pix, vec4(uintBitsToFloat(0x7FC00000u)));
        return;
    }
    vec3 p = eye_point(pix, d);
    vec3 n = normalize(world_to_view * texelFetch(normal_tex, pix, 0).xyz);
    // Position in the coarse grid (pixel centres at integers); its 2x2
    // neighbours with bilinear weights.
    // A coarse pixel's value belongs to its source pixel's centre, not to
    // the centre of its block: shift by the difference.
    vec2 r = vec2(ao_size) / vec2(size);
    vec2 shift = (vec2(ao_source_pixel(ivec2(0), ao_size, size)) + 0.5) * r - 0.5;
    vec2 x = (vec2(pix) + 0.5) * r - 0.5 - shift;
    ivec2 c = ivec2(floor(x));
    vec2 f = x - vec2(c);
    float sigma = max(2.0 * -p.z / (proj_scale.y * float(ao_size.y)), 1e-4); // coarse texel at this depth, mm
    float sum = 0.0, wsum = 0.0, best_w = -1.0, best = 1.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 q = clamp(c + o, ivec2(0), ao_size - 1);
        vec4 c4 = texelFetch(ao_low, q, 0);
        float v = c4.x;
        if (isnan(v)) continue;
        vec3 ns = oct_decode(c4.zw);
        float dn = max(dot(n, ns), 0.0);
        dn *= dn;
        float h = dot(n, eye_point_at(ao_source_pixel(q, ao_size, size), c4.y) - p) / sigma; // off this pixel's tangent plane, in coarse texels
        h *= h;
        float wg = dn * dn / (1.0 + h * h);              // 1 / (1 + h^4): flat near the plane, steep beyond a texel
        vec2 b = mix(1.0 - f, f, vec2(o));
        float w = wg * b.x * b.y;
        sum += w * v;
        wsum += w;
        if (wg > best_w) {
            best_w = wg;
            best = v;
        }
    }
    float ao = wsum > 1e-6 ? sum / wsum : best;
    imageStore(ao_image, pix, vec4(ao));
}
