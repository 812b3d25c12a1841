// overlay pass parameters (std140)
ISO_BLOCK_BEGIN(OverlayParams, 0)
ISO_MEMBER(vec2, viewport)
ISO_MEMBER(vec2, near_far)       // the camera's planes (mm): the frame's reversed-Z depth -> mm along the view axis
ISO_MEMBER(float, tolerance_mm)  // a markup hides only this far behind the frame's surface
ISO_MEMBER(float, dash_period)   // pixels: hidden markup lines are dashed, half on, half off
ISO_MEMBER(vec2, jitter)         // the frame's sub-pixel offset (pixels, y down): lines and glyphs move with the scene, text stays on its pixels
ISO_BLOCK_END(OverlayParams)
