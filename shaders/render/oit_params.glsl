// VOIT passes' parameters (oit_fragments.frag and oit_resolve.comp; std140)
ISO_BLOCK_BEGIN(OitParams, 1)   // binding 1: the fragment pass also reads GBufferParams at 0
ISO_MEMBER(mat3, view_rotation)   // world -> view (named apart from ConeParams' members: the resolve reads both)
ISO_MEMBER(ivec2, image_size)
ISO_MEMBER(uint, capacity)        // nodes the pool holds
ISO_MEMBER(float, epsilon)        // stop once the remaining transmittance is below it
ISO_MEMBER(bool, flat_shading)    // a fragment is its albedo (no lighting)
ISO_MEMBER(vec2, near_far)        // the camera's near and far planes (mm): linear depth from reversed Z
ISO_MEMBER(vec2, cut_range)       // linear depth (mm) the cut's OIT_BINS bins span: the translucent objects' extent
ISO_BLOCK_END(OitParams)
