// The lighting pass's parameters (shaders/render/lighting_params.glsl) for a
// frame: also what DSRAA shades a sub-sample no pixel matches with, and the
// background it maps background sub-samples to.
#pragma once

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

inline LightingParams lighting_params(const FrameContext& ctx, bool use_ao) {
    const FrameLook& look = ctx.opt.look;
    return LightingParams{std140::mat3(ctx.world_to_view),
                          glm::vec4(look.background, look.transparent_background ? 0.0f : 1.0f), use_ao ? 1u : 0u,
                          look.flat_shading ? 1u : 0u};
}

} // namespace iso::passes
