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
    uint oit_count;       // fragments offered to the pool (stored or not)
    uint oit_overflow;    // fragments that found the pool full
    uint oit_cut_merged;  // fragments beyond their pixel's depth cut (OIT_CUT): merged
};
#define OIT_BINS 16       // depth bins of the cut's histogram
layout(std430, binding = 1) coherent buffer OitNodes { OitNode oit_nodes[]; };
// Per object: linear albedo (rgb) and opacity (a), index = object id.
layout(std430, binding = 2) readonly buffer OitObjects { vec4 oit_objects[]; };

#include "octahedral.glsl"

// Past the pool's cap (OIT_MERGE), fragments that find it full are merged
// per pixel, order-independently, in fixed point (integer atomics: GL 4.5
// has no float atomics): their count, the sum of alpha * colour, the sum of
// alpha, the sum of -log2(1 - alpha) (the product of transmittances), and
// the range of their colours.
// The resolve composites them behind the sorted list.
struct OitTail {
    uint count;
    uint color[3];     // sum of alpha * colour, OIT_TAIL_ONE per unit
    uint alpha;        // sum of alpha, OIT_TAIL_ONE per unit
    uint optical;      // sum of -log2(1 - alpha), OIT_TAIL_LOG_ONE per unit, each at most OIT_TAIL_LOG_MAX
    // The colours' range per channel, 65535 per unit (bounds the lost
    // order's error): the low end stored as 65535 - low and raised with
    // atomicMax, so that an all-zero buffer is the empty tail.
    uint lo_complement[3], hi[3];
};
#define OIT_TAIL_ONE 16384.0      // 2^14: 2^18 fragments per pixel before a sum wraps
#define OIT_TAIL_LOG_ONE 4096.0   // 2^12
#define OIT_TAIL_LOG_MAX 24.0     // alpha 1 counts as transmittance 2^-24
layout(std430, binding = 3) coherent buffer OitTails { OitTail oit_tails[]; };   // per pixel, with OIT_MERGE
