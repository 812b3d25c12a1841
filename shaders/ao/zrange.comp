#version 450
#extension GL_GOOGLE_include_directive : require
// Nearest and farthest visible linear depth of the frame (the local
// slicemap's range), by a workgroup reduction and two global atomics.
#include "ao_common.glsl"
#include "std140.glsl"
#include "zrange_params.glsl"
layout(local_size_x = 16, local_size_y = 16) in;

layout(binding = 0) uniform sampler2D depth_tex;   // reversed-Z, 0 = background
layout(std430, binding = 0) buffer ZRange { uint zmin_bits; uint zmax_bits; };


shared uint s_min, s_max;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_min = 0x7F800000u; // +inf: positive floats order like their bits
        s_max = 0u;
    }
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(p, size))) {
        float d = texelFetch(depth_tex, p, 0).r;
        if (d > 0.0) {
            float z = linear_depth(d, near_plane, far_plane);
            atomicMin(s_min, floatBitsToUint(z));
            atomicMax(s_max, floatBitsToUint(z));
        }
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_max != 0u) {
        atomicMin(zmin_bits, s_min);
        atomicMax(zmax_bits, s_max);
    }
}
