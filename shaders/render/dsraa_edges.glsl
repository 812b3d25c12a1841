// DSRAA's edge list: the pixels whose visibility sub-samples do not all
// show what the pixel shaded (gbuffer_sample.frag appends them, dsraa.comp
// reconstructs them). The header is glDispatchComputeIndirect's arguments:
// one 64-wide group per 64 edge pixels.
#ifndef ISO_DSRAA_EDGES_GLSL
#define ISO_DSRAA_EDGES_GLSL
#define DSRAA_GROUP 64
layout(std430, binding = 1) buffer DsraaEdges {
    uint edge_groups_x, edge_groups_y, edge_groups_z; // 0, 1, 1 at the start of a frame
    uint edge_count;
    uvec2 edges[]; // (x | y << 16, mask of the unmatched sub-samples)
};
#endif
