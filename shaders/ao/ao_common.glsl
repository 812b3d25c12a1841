// Shared by the slicemap voxelization and the cone-tracing pass.
#ifndef LAYERS
#define LAYERS 2          // 128 z-voxels per RGBA32UI layer
#endif
#define BITS (128 * LAYERS)

// Linear depth (mm along the view axis) of a reversed-Z depth value d > 0,
// between the near plane zn and the far plane zf.
float linear_depth(float d, float zn, float zf) {
    return zn * zf / (d * (zf - zn) + zn);
}

// Eye-space point (the camera looks down -z) at linear depth D on the ray
// through the centre of pixel pix of an image of `image_size` pixels, with
// the projection's scale (projection[0][0], projection[1][1]).
vec3 eye_point_at_depth(ivec2 pix, ivec2 image_size, vec2 scale, float D) {
    vec2 ndc = (vec2(pix) + 0.5) / vec2(image_size) * 2.0 - 1.0;
    return vec3(ndc * D / scale, -D);
}

// Bits k and above of a 32-bit word (k <= 0: all, k >= 32: none). Bit
// arithmetic instead of the thesis's 128-entry LUT: the same masks, no fetch.
uint mask_from(int k) {
    return k <= 0 ? 0xFFFFFFFFu : (k >= 32 ? 0u : (0xFFFFFFFFu << uint(k)));
}

// The slicemap's z range (linear depth in mm): from the nearest visible depth
// (the G-buffer's, reduced by zrange.comp; nothing nearer can be on screen)
// to the nearer of the scene's far bound and the farthest visible depth + R
// (nothing farther can occlude a visible point). With a guard band, geometry
// off screen may be nearer than anything visible: the range then starts R
// nearer (near_margin = R; else 0).
vec2 slicemap_range(uint zmin_bits, uint zmax_bits, float scene_far, float radius, float near_margin) {
    float zn = max(uintBitsToFloat(zmin_bits) - near_margin, 0.0);
    float zf = min(scene_far, uintBitsToFloat(zmax_bits) + radius);
    return vec2(zn, max(zf, zn + 1e-3));
}

// Index of the first voxel whose centre lies at or beyond linear depth z.
int voxel_at(float z, vec2 range) {
    float t = (z - range.x) / (range.y - range.x) * float(BITS);
    return int(clamp(ceil(t - 0.5), 0.0, float(BITS)));
}

// The frame pixel an AO-image pixel traces from when the AO image is
// coarser than the frame: the one at the centre of its block (the identity
// when both have the same size).
ivec2 ao_source_pixel(ivec2 q, ivec2 ao_size, ivec2 size) {
    ivec2 p = ivec2(floor((vec2(q) + 0.5) * vec2(size) / vec2(ao_size)));
    return clamp(p, ivec2(0), size - 1);
}

// Octahedral encoding of a unit vector in two floats (Meyer et al. 2010).
vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.xy;
    if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
    return e;
}
vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}
