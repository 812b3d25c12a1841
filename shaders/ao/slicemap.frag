#version 450
#extension GL_GOOGLE_include_directive : require
// Each fragment writes "every voxel at or beyond my depth"; XOR blending
// (glLogicOp) of a column's front and back faces leaves the voxels between
// them set: a solid voxelization in one pass, with no depth test or culling.
#include "ao_common.glsl"
#include "std140.glsl"
#include "voxelize_params.glsl"

in float view_depth;

layout(std430, binding = 0) readonly buffer ZRange { uint zmin_bits; uint zmax_bits; };

layout(location = 0) out uvec4 out_mask[LAYERS];

void main() {
    vec2 range = slicemap_range(zmin_bits, zmax_bits, scene_far, radius, near_margin);
    int k = voxel_at(view_depth, range);
    for (int l = 0; l < LAYERS; ++l) {
        int b = k - 128 * l;
        out_mask[l] = uvec4(mask_from(b), mask_from(b - 32), mask_from(b - 64), mask_from(b - 96));
    }
}
