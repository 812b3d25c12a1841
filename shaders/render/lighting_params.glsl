// lighting pass parameters (std140)
ISO_BLOCK_BEGIN(LightingParams, 0)
ISO_MEMBER(mat3, world_to_view)   // rotation part of the view matrix
ISO_MEMBER(vec4, background)      // linear RGB, alpha
ISO_MEMBER(bool, use_ao)
ISO_MEMBER(bool, flat_shading)   // albedo only: no lighting, no AO
ISO_BLOCK_END(LightingParams)
