#version 450
#extension GL_GOOGLE_include_directive : require
// Test shader for tests/gl/disk_ao_test.cpp (gltest_disk_ao): evaluates
// every kernel of disk_geometry.glsl on one input record per invocation so
// that the test can compare it with the C++ templates of
// renderer/ao/disk_geometry.cpp. Not used by the renderer.
#include "disk_geometry.glsl"

layout(local_size_x = 64) in;

// Per case, 8 vec4s in and 8 out (layout in the test: struct KernelCase).
layout(std430, binding = 0) readonly buffer Inputs { vec4 inputs[]; };
layout(std430, binding = 1) writeonly buffer Outputs { vec4 outputs[]; };

uniform int case_count;

void main() {
    int c = int(gl_GlobalInvocationID.x);
    if (c >= case_count) return;
    vec4 a0 = inputs[8 * c + 0]; // p, clip epsilon
    vec4 a1 = inputs[8 * c + 1]; // n, disk area
    vec4 a2 = inputs[8 * c + 2]; // v0, distance attenuation k
    vec4 a3 = inputs[8 * c + 3]; // v1, triangle attenuation t
    vec4 a4 = inputs[8 * c + 4]; // v2, element term e
    vec4 a5 = inputs[8 * c + 5]; // disk centre, squared distance
    vec4 a6 = inputs[8 * c + 6]; // disk normal, o0
    vec4 a7 = inputs[8 * c + 7]; // o1, min scale, max scale, -
    vec3 p = a0.xyz, n = a1.xyz, v0 = a2.xyz, v1 = a3.xyz, v2 = a4.xyz;
    float eps = a0.w;

    vec3 q[4];
    int count = disk_clip_to_tangent_plane(p, n, v0, v1, v2, eps, q);
    vec3 tri[4] = vec3[4](v0, v1, v2, v2);
    for (int i = 0; i < 4; ++i) outputs[8 * c + i] = vec4(q[i], float(count));
    outputs[8 * c + 4] = vec4(disk_polygon_form_factor(p, n, q, 4), disk_clipped_triangle_form_factor(p, n, v0, v1, v2, eps),
                              disk_form_factor(p, n, a5.xyz, a6.xyz, a1.w), disk_distance_attenuation(a5.w, a2.w));
    outputs[8 * c + 5] = vec4(disk_triangle_attenuation(a4.w, a3.w), disk_converge_blend(a6.w, a7.x, a7.y, a7.z),
                              disk_snapped_plane_distance(p, n, v0, eps), disk_snapped_plane_distance(p, n, v1, eps));
    outputs[8 * c + 6] = vec4(disk_snapped_plane_distance(p, n, v2, eps), disk_polygon_form_factor(p, n, tri, 3), 0.0, 0.0);
    outputs[8 * c + 7] = vec4(0.0);
}
