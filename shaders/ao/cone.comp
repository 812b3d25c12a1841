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
#include "cone_trace.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D depth_tex;      // reversed-Z
layout(binding = 1) uniform sampler2D normal_tex;     // world (LPS) normal, w = 1 on geometry
#ifdef COARSE
// Coarse AO for ao_upsample.comp: (AO, linear depth of the source pixel,
// its view-space normal octahedron-encoded), so the upsampling reads one
// texel per neighbour.
layout(binding = 0, rgba32f) uniform image2D ao_image;
#else
layout(binding = 0, r32f) uniform image2D ao_image;   // running mean over still frames
#endif

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
    float D = linear_depth(d, near_plane, far_plane);
    vec3 p = eye_point_at_depth(pix, size, proj_scale, D);
    vec3 n = normalize(world_to_view * texelFetch(normal_tex, pix, 0).xyz);

    float ao = cone_ao(p, n, pix);
    if (history_weight > 0.0) ao = mix(ao, imageLoad(ao_image, q).r, history_weight);
#ifdef COARSE
    imageStore(ao_image, q, vec4(ao, D, oct_encode(n)));
#else
    imageStore(ao_image, q, vec4(ao));
#endif
}
