#version 450
#extension GL_GOOGLE_include_directive : require
// Disk AO per pixel (docs/ao.md): the receiver is the G-buffer's surface
// point and normal; occlusion from the whole hierarchy, each emitter
// modulated by its converged element term. Output like cone AO: R32F,
// 1 = unoccluded, NaN = background.
#include "std140.glsl"
#include "disk_params.glsl"
#include "disk_geometry.glsl"
#include "disk_traverse.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D depth_tex;  // reversed-Z
layout(binding = 1) uniform sampler2D normal_tex; // world (LPS) normal
layout(binding = 0, r32f) uniform writeonly image2D ao_image;
#ifdef READ_RECEIVERS
layout(std430, binding = 6) writeonly buffer DiskReceivers { vec4 disk_receivers[]; }; // 2 per pixel
#endif

void main() {
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pix, size))) return;
    float d = texelFetch(depth_tex, pix, 0).r;
    float nan = uintBitsToFloat(0x7FC00000u);
    if (d <= 0.0) {
        imageStore(ao_image, pix, vec4(nan));
#ifdef READ_RECEIVERS
        disk_receivers[2 * (pix.y * size.x + pix.x)] = vec4(nan);
        disk_receivers[2 * (pix.y * size.x + pix.x) + 1] = vec4(0.0);
#endif
        return;
    }
    float D = near_plane * far_plane / (d * (far_plane - near_plane) + near_plane);
    vec2 ndc = (vec2(pix) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec3 p = (view_to_world * vec4(ndc * D / proj_scale, -D, 1.0)).xyz;
    vec3 n = normalize(texelFetch(normal_tex, pix, 0).xyz);
    float ao = 1.0 - disk_occlusion(p, n);
    imageStore(ao_image, pix, vec4(ao));
#ifdef READ_RECEIVERS
    disk_receivers[2 * (pix.y * size.x + pix.x)] = vec4(p, ao);
    disk_receivers[2 * (pix.y * size.x + pix.x) + 1] = vec4(n, 0.0);
#endif
}
