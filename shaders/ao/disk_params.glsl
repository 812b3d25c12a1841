// Disk AO pass parameters (std140): shared by disk_element.comp,
// disk_parent.comp, disk_blend.comp and disk_gather.comp.
ISO_BLOCK_BEGIN(DiskParams, 0)
ISO_MEMBER(mat4, view_to_world)      // gather: eye space -> LPS mm
ISO_MEMBER(vec2, proj_scale)         // projection[0][0], projection[1][1]
ISO_MEMBER(ivec2, size)              // the frame's
ISO_MEMBER(float, near_plane)
ISO_MEMBER(float, far_plane)
ISO_MEMBER(float, radius)            // R: occluders farther than this do not count
ISO_MEMBER(float, clip_epsilon)
ISO_MEMBER(float, traversal_epsilon)
ISO_MEMBER(float, distance_attenuation)
ISO_MEMBER(float, triangle_attenuation)
ISO_MEMBER(float, min_scale)
ISO_MEMBER(float, max_scale)
ISO_MEMBER(float, receiver_offset)   // x R along the normal
ISO_MEMBER(int, node_count)
ISO_MEMBER(int, use_terms)           // 0: every emitter's term is 1 (the first pass)
ISO_MEMBER(int, first)               // disk_parent: this level's range in the level list
ISO_MEMBER(int, count)
ISO_MEMBER(int, row_offset)          // disk_gather: first image row of this dispatch (bands, for progress)
ISO_BLOCK_END(DiskParams)
