// Octahedral unit normals in one uint (packSnorm2x16): the VOIT fragment
// nodes and DSRAA's visibility sub-samples. 16 bits per coordinate: about
// 1e-4 rad, finer than a half-float normal.
#ifndef ISO_OCTAHEDRAL_GLSL
#define ISO_OCTAHEDRAL_GLSL
vec2 oct_wrap(vec2 v) { return (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

uint pack_normal(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.z >= 0.0 ? n.xy : oct_wrap(n.xy);
    return packSnorm2x16(e);
}

vec3 unpack_normal(uint p) {
    vec2 e = unpackSnorm2x16(p);
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = oct_wrap(n.xy);
    return normalize(n);
}
#endif
