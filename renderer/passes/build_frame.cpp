// The frame, assembled from the passes; and its context.
#include <algorithm>

#include <glm/glm.hpp>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gbuffer_layout.hpp"
#include "io/error.hpp"
#include "renderer/frame/ao_settings.hpp"

namespace iso::passes {

FrameContext make_context(const Camera& camera, const RenderOptions& opt, std::vector<DrawItem> draws,
                          const Bounds& bounds) {
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
    set_jitter(ctx, opt.jitter.value_or(glm::vec2(0.0f)));
    // Sub-samples serve the colour image; picks and AOVs read pixel centres.
    ctx.aa_samples = opt.image && opt.aov == Aov::None && !opt.pick ? opt.look.aa.samples : 1;
    ctx.world_to_view = glm::mat3(glm::mat4(camera.view()));
    // Translucent draws go near to far (by their bounds' nearest corner along
    // the view axis): when the pool is full at its cap, the fragments left
    // over, which are merged rather than stored, are then mostly the farther
    // objects'.
    const glm::dvec3 eye = camera.eye, forward = camera.forward();
    auto nearest = [&](const DrawItem& d) {
        double z = 1e300;
        for (int c = 0; c < 8; ++c) z = std::min(z, glm::dot(d.bounds.corner(c) - eye, forward));
        return d.bounds.empty() ? 1e300 : z;
    };
    std::stable_sort(translucent.begin(), translucent.end(),
                     [&](const DrawItem& a, const DrawItem& b) { return nearest(a) < nearest(b); });
    double z0 = 1e300, z1 = -1e300;
    for (const auto& d : translucent)
        for (int c = 0; c < 8 && !d.bounds.empty(); ++c) {
            const double z = glm::dot(d.bounds.corner(c) - eye, forward);
            z0 = std::min(z0, z);
            z1 = std::max(z1, z);
        }
    z0 = std::max(z0, camera.near_plane);
    z1 = std::min(z1, camera.far_plane);
    ctx.draws = std::move(opaque);
    ctx.translucent = std::move(translucent);
    if (z0 < z1) ctx.translucent_depth = glm::vec2(float(z0), float(z1));
    if (opt.pick) { // clipped to the image; an empty region picks nothing
        const int x0 = std::max(opt.pick->x, 0), y0 = std::max(opt.pick->y, 0);
        const int x1 = std::min(opt.pick->x + std::max(opt.pick->width, 0), opt.width);
        const int y1 = std::min(opt.pick->y + std::max(opt.pick->height, 0), opt.height);
        if (x1 > x0 && y1 > y0) ctx.pick = PickRegion{x0, y0, x1 - x0, y1 - y0};
    }
    ctx.objects = std::move(objects);
    ctx.bounds = bounds;
    if (opt.annotations) ctx.overlay = build_overlay(*opt.annotations, camera, opt.width, opt.height, opt.scale);
    return ctx;
}

void set_jitter(FrameContext& ctx, glm::vec2 jitter) {
    ctx.jitter = jitter;
    // Clip space moved by the offset: x right, y down in pixels; NDC spans 2 per image.
    const glm::vec2 ndc(2.0f * jitter.x / float(ctx.width), -2.0f * jitter.y / float(ctx.height));
    glm::mat4 t(1.0f);
    t[3] = glm::vec4(ndc, 0.0f, 1.0f);
    ctx.raster_view_projection = t * ctx.view_projection;
}

void build_frame(graph::FrameGraph& fg, const FrameContext& ctx) {
    const RenderOptions& opt = ctx.opt;
    // The GL frame computes cone and disk AO; ray-traced AO comes computed
    // (RenderOptions::ao_image) and is uploaded by ao_import.
    const AoMethod method = opt.look.ao;
    const bool raytraced = method == AoMethod::Raytraced;
    const bool reads_ao = opt.image && (opt.aov == Aov::None || opt.aov == Aov::Ao);
    if (raytraced && !opt.ao_image && reads_ao)
        throw Error("ray-traced AO", "the frame needs its AO image (computed on the CPU before the frame)");
    if (opt.aov == Aov::Ao && method == AoMethod::Off)
        throw Error("ao AOV", "needs cone, disk or raytraced ambient occlusion");
    validate(opt.look);
    const bool lit_ao = method != AoMethod::Off && (!raytraced || opt.ao_image);
    const bool disk = method == AoMethod::Disk;
    const GBuffer gb = gbuffer(fg, ctx);
    // Declared always: culled by the graph when neither lighting nor the read-back reads it.
    const AmbientOcclusion ao = ambient_occlusion(fg, ctx, gb);
    // Disk AO and ray-traced AO replace the cone chain's image (the cone chain is then culled).
    const graph::TextureHandle ao_image = raytraced && opt.ao_image ? imported_ao(fg, ctx)
                                          : disk                    ? disk_ambient_occlusion(fg, ctx, gb)
                                                                    : ao.ao;
    graph::TextureHandle color = lighting(fg, ctx, gb, lit_ao ? ao_image : graph::TextureHandle{});
    // Scene content, not an output request, decides this one: no translucent
    // object, no list passes. Lit translucent fragments get their own AO
    // (traced through the cone chain: the disk hierarchy holds the opaque
    // surfaces only); with ray-traced AO they go without (docs/ao.md).
    PickBuffers picked;
    const bool translucent_ao = lit_ao && !raytraced && !opt.look.flat_shading;
    // The volume is ray cast between the translucent fragments by the VOIT
    // resolve, or over the opaque image by its own pass.
    if (!ctx.translucent.empty())
        color = voit(fg, ctx, gb, color, translucent_ao ? &ao : nullptr, picked);
    else if (ctx.volume && opt.image && opt.aov == Aov::None)
        color = volume(fg, ctx, gb, color);
    if (ctx.pick) pick(fg, ctx, gb, picked);
    if (!opt.image) return; // nothing reads the colour image or an AOV: their passes are culled
    color = dsraa(fg, ctx, gb, color);
    if (opt.annotations) color = overlay(fg, ctx, color, gb.depth);
    if (opt.accumulate && opt.aov == Aov::None) color = accumulate(fg, ctx, color);
    if (opt.present) return present(fg, ctx, color);
    // The colour image, or the AOV: depth, AO, or the G-buffer channel the layout table names.
    graph::TextureHandle source = color;
    if (opt.aov == Aov::Depth) source = gb.depth;
    if (opt.aov == Aov::Ao) source = ao_image;
    for (const auto& c : kGBufferLayout)
        if (opt.aov != Aov::None && c.aov == opt.aov) source = gb.*c.handle;
    readback(fg, ctx, source);
}

} // namespace iso::passes
