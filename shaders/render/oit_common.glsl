// VOIT per-pixel fragment lists (docs/voit.md): a node per stored fragment
// with what shading needs later, not a shaded colour.
struct OitNode {
    float depth;      // reversed Z: larger is nearer
    uint object;      // 1-based object id
    uint primitive;   // gl_PrimitiveID within the object's draw
    uint normal;      // octahedral world normal, packSnorm2x16
    uint next;        // next node of the pixel's list; 0xFFFFFFFF ends it
};
const uint OIT_END = 0xFFFFFFFFu;

layout(std430, binding = 0) coherent buffer OitCounters {
    uint oit_count;      // fragments offered (stored or not)
    uint oit_overflow;   // fragments that found the pool full
};
layout(std430, binding = 1) coherent buffer OitNodes { OitNode oit_nodes[]; };
// Per object: linear albedo (rgb) and opacity (a), index = object id.
layout(std430, binding = 2) readonly buffer OitObjects { vec4 oit_objects[]; };

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
