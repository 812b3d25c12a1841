#version 450
#extension GL_GOOGLE_include_directive : require
// Disk AO per pixel (docs/ao.md, "Disk AO on the GPU"): the receiver is the
// G-buffer's surface point and normal; occlusion from the whole hierarchy,
// each emitter modulated by its converged element term (when element passes
// ran). Sided as disk_occlusion_sided: when the shading normal points
// against the surface's geometric normal (reconstructed here from the depth
// of the neighbouring pixels), back faces occlude instead of front faces.
// Output like cone AO: R32F, 1 = unoccluded, NaN = background.
#include "ao_common.glsl"
#include "std140.glsl"
#include "disk_params.glsl"
#include "disk_geometry.glsl"
#include "disk_traverse.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D depth_tex;  // reversed-Z
layout(binding = 1) uniform sampler2D normal_tex; // world (LPS) normal
layout(binding = 0, r32f) uniform writeonly image2D ao_image;
#ifdef READ_RECEIVERS
// 2 per pixel: (point, AO), (normal, side).
layout(std430, binding = 6) writeonly buffer DiskReceivers { vec4 disk_receivers[]; };
#endif

// Eye-space point of a pixel and its linear depth; w = 0 on the background.
vec4 eye_point(ivec2 pix) {
    if (any(lessThan(pix, ivec2(0))) || any(greaterThanEqual(pix, size))) return vec4(0.0);
    float d = texelFetch(depth_tex, pix, 0).r;
    if (d <= 0.0) return vec4(0.0);
    return vec4(eye_point_at_depth(pix, size, proj_scale, linear_depth(d, near_plane, far_plane)), 1.0);
}

// The step to the neighbour along one axis on the same surface: the one of
// the two whose depth is nearer this pixel's (across a silhouette the other
// one jumps); none on the background.
vec3 surface_step(vec3 e, ivec2 pix, ivec2 axis) {
    vec4 a = eye_point(pix + axis), b = eye_point(pix - axis);
    if (a.w == 0.0 && b.w == 0.0) return vec3(0.0);
    if (b.w == 0.0 || (a.w != 0.0 && abs(a.z - e.z) <= abs(b.z - e.z))) return a.xyz - e;
    return e - b.xyz;
}

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, row_offset);
    if (any(greaterThanEqual(pix, size))) return;
    vec4 e = eye_point(pix);
    if (e.w == 0.0) {
        float nan = uintBitsToFloat(0x7FC00000u);
        imageStore(ao_image, pix, vec4(nan));
#ifdef READ_RECEIVERS
        disk_receivers[2 * (pix.y * size.x + pix.x)] = vec4(nan);
        disk_receivers[2 * (pix.y * size.x + pix.x) + 1] = vec4(0.0);
#endif
        return;
    }
    vec3 p = (view_to_world * vec4(e.xyz, 1.0)).xyz;
    vec3 n = normalize(texelFetch(normal_tex, pix, 0).xyz);
    // Geometric normal of the visible surface, facing the eye (the front
    // face of a closed surface seen from outside): cross of the steps to the
    // neighbours on the same surface. None (an isolated pixel): not sided.
    vec3 g = cross(surface_step(e.xyz, pix, ivec2(1, 0)), surface_step(e.xyz, pix, ivec2(0, 1)));
    float side = 1.0;
    if (dot(g, g) > 0.0) {
        if (dot(g, -e.xyz) < 0.0) g = -g;
        vec3 gw = mat3(view_to_world) * g;
        side = dot(n, gw) < 0.0 ? -1.0 : 1.0;
    }
    float ao = 1.0 - disk_occlusion(p, n, side);
    imageStore(ao_image, pix, vec4(ao));
#ifdef READ_RECEIVERS
    disk_receivers[2 * (pix.y * size.x + pix.x)] = vec4(p, ao);
    disk_receivers[2 * (pix.y * size.x + pix.x) + 1] = vec4(n, side);
#endif
}
