// overlay pass parameters (std140)
ISO_BLOCK_BEGIN(OverlayParams, 0)
ISO_MEMBER(vec2, viewport)
ISO_BLOCK_END(OverlayParams)
