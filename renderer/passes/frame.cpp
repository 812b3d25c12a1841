// The frame, assembled from the passes; and its context.
#include <glm/glm.hpp>

#include "renderer/passes/frame.hpp"
#include "renderer/passes/gbuffer_layout.hpp"

namespace iso::passes {

FrameContext make_context(const Camera& camera, const RenderOptions& opt, std::vector<DrawItem> draws, const Bounds& bounds) {
    FrameContext ctx;
    ctx.camera = camera;
    ctx.opt = opt;
    ctx.width = opt.width;
    ctx.height = opt.height;
    const double aspect = double(opt.width) / double(opt.height);
    ctx.view_projection = glm::mat4(camera.projection(aspect) * camera.view());
    ctx.world_to_view = glm::mat3(glm::mat4(camera.view()));
    ctx.draws = std::move(draws);
    ctx.bounds = bounds;
    if (opt.annotations) ctx.overlay = build_overlay(*opt.annotations, camera, opt.width, opt.height, opt.scale);
    return ctx;
}

void build_frame(graph::FrameGraph& fg, const FrameContext& ctx) {
    const RenderOptions& opt = ctx.opt;
    const bool ao_wanted = opt.ao || opt.aov == Aov::Ao;
    if (ao_wanted) validate(opt.ao_settings);
    const GBuffer gb = gbuffer(fg, ctx);
    // Declared always: culled by the graph when neither lighting nor the read-back reads it.
    const graph::TextureHandle ao = ambient_occlusion(fg, ctx, gb);
    graph::TextureHandle color = lighting(fg, ctx, gb, opt.ao ? ao : graph::TextureHandle{});
    if (opt.annotations) color = overlay(fg, ctx, color);
    if (opt.present) return present(fg, ctx, color);
    graph::TextureHandle source = opt.aov == Aov::None ? color : opt.aov == Aov::Depth ? gb.depth : ao;
    for (const auto& c : kGBufferLayout)
        if (c.aov == opt.aov && opt.aov != Aov::None) source = gb.*c.handle;
    readback(fg, ctx, source);
}

} // namespace iso::passes
