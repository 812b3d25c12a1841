// gbuffer pass parameters (std140); the object id and albedo change per
// draw and stay plain uniforms of gbuffer.frag.
ISO_BLOCK_BEGIN(GBufferParams, 0)
ISO_MEMBER(mat4, view_projection)
ISO_BLOCK_END(GBufferParams)
