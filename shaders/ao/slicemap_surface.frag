#version 450
#extension GL_GOOGLE_include_directive : require
// Surface voxels: OR-blended after the solid XOR pass, every
// fragment sets voxels its surface passes through within its texel, on the
// solid's side of it: the depths [z, z + h] or [z - h, z], h = half the depth
// change across the texel (0.5 (|dz/dx| + |dz/dy|)), as the voxels whose
// centres they hold, and at least the voxel next to the surface. The solid pass sets a
// voxel only when its centre is inside, so a wall thinner than a voxel in z
// (front and back in one voxel: XOR clears it) vanishes; this keeps it one
// voxel thick. Walls seen edge-on and narrower than a texel cover no texel
// centre and stay lost: drawing the triangles' edges as lines as well
// (glPolygonMode GL_LINE) kept them, but cost 3-7x the voxelization on
// llvmpipe and, without the polygon's facing in llvmpipe's line fragments,
// set voxels outside surfaces (self-occlusion); see docs/ao.md.
#include "ao_common.glsl"
#include "std140.glsl"
#include "voxelize_params.glsl"

in float view_depth;

layout(std430, binding = 0) readonly buffer ZRange { uint zmin_bits; uint zmax_bits; };

layout(location = 0) out uvec4 out_mask[LAYERS];

void main() {
    vec2 range = slicemap_range(zmin_bits, zmax_bits, scene_far, radius, near_margin);
    float scale = float(BITS) / (range.y - range.x);
    // Half the depth change across the texel, at most two voxels: near a
    // silhouette a triangle is almost edge-on, its slope per texel is huge
    // while the triangle spans a fraction of a millimetre, and an uncut h
    // stamped a fin of voxels in front of and behind the surface (voxel-grid
    // reference bias -0.19 on the thin phantom). Cutting h to the triangle's
    // own depth extent (a geometry shader passing it on) did the same but
    // doubled the pass's cost on llvmpipe.
    float h = min(0.5 * (abs(dFdx(view_depth)) + abs(dFdy(view_depth))), 2.0 / scale);
    // Only voxels on the solid's side of the surface: for a face towards the
    // camera (the solid lies beyond it) the first voxel whose centre is at or
    // beyond z, as the XOR pass sets, and those with centres in [z, z + h];
    // for a face away from it the last voxel whose centre is at or before z
    // and those in [z - h, z]. So no set voxel reaches farther out of a
    // surface than the solid pass's half voxel, and the raised tangent plane
    // still keeps a surface's own voxels out (setting every voxel the depths
    // touch, on both sides, made the voxel-grid reference 0.05 too dark on
    // the thin phantom: self-occlusion). A sheet thinner than a voxel gets
    // the two voxels around it.
    float c = (view_depth - range.x) * scale - 0.5; // depth in voxel-centre units
    float ch = h * scale;
    int k0, k1; // voxels [k0, k1)
    if (gl_FrontFacing) {
        k0 = int(ceil(c));
        k1 = max(k0 + 1, int(floor(c + ch)) + 1);
    } else {
        k1 = int(floor(c)) + 1;
        k0 = min(k1 - 1, int(ceil(c - ch)));
    }
    k0 = clamp(k0, 0, BITS);
    k1 = clamp(k1, 0, BITS);
    if (view_depth + h < range.x || view_depth - h >= range.y) k1 = k0; // wholly outside the range: nothing
    for (int l = 0; l < LAYERS; ++l) {
        int b0 = k0 - 128 * l, b1 = k1 - 128 * l;
        out_mask[l] = uvec4(mask_from(b0) & ~mask_from(b1), mask_from(b0 - 32) & ~mask_from(b1 - 32),
                            mask_from(b0 - 64) & ~mask_from(b1 - 64), mask_from(b0 - 96) & ~mask_from(b1 - 96));
    }
}
