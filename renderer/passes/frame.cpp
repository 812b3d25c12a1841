// The frame, assembled from the passes; and its context.
#include <glm/glm.hpp>

#include "renderer/passes/frame.hpp"
#include "renderer/passes/gbuffer_layout.hpp"

namespace iso::passes {

FrameContext make_context(const Camera& camera, const RenderOptions& opt, std::vector<DrawItem> draws, const Bounds& bounds) {
    // Translucent surfaces go to the VOIT lists, opaque ones to the G-buffer.
    std::vector<DrawItem> opaque, translucent;
    std::vector<glm::vec4> objects(1, glm::vec4(0.0f));
    for (const auto& d : draws) {
        (d.opacity < 1.0f ? translucent : opaque).push_back(d);
        if (objects.size() <= d.id) objects.resize(d.id + 1, glm::vec4(0.0f));
        objects[d.id] = glm::vec4(d.color, d.opacity);
    }
    FrameContext ctx;
    ctx.camera = camera;
    ctx.opt = opt;
    ctx.width = opt.width;
    ctx.height = opt.height;
    const double aspect = double(opt.width) / double(opt.height);
    ctx.view_projection = glm::mat4(camera.projection(aspect) * camera.view());
    ctx.world_to_view = glm::mat3(glm::mat4(camera.view()));
    ctx.draws = std::move(opaque);
    ctx.translucent = std::move(translucent);
    ctx.objects = std::move(objects);
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
    const AmbientOcclusion ao = ambient_occlusion(fg, ctx, gb);
    graph::TextureHandle color = lighting(fg, ctx, gb, opt.ao ? ao.ao : graph::TextureHandle{});
    // Scene content, not an output request, decides this one: no translucent
    // object, no list passes. Lit translucent fragments get their own AO.
    if (!ctx.translucent.empty()) color = voit(fg, ctx, gb, color, opt.ao && !opt.flat_shading ? &ao : nullptr);
    if (opt.annotations) color = overlay(fg, ctx, color);
    if (opt.present) return present(fg, ctx, color);
    // The colour image, or the AOV: depth, AO, or the G-buffer channel the layout table names.
    graph::TextureHandle source = color;
    if (opt.aov == Aov::Depth) source = gb.depth;
    if (opt.aov == Aov::Ao) source = ao.ao;
    for (const auto& c : kGBufferLayout)
        if (opt.aov != Aov::None && c.aov == opt.aov) source = gb.*c.handle;
    readback(fg, ctx, source);
}

} // namespace iso::passes
