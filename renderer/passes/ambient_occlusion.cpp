// The cone-AO chain (docs/ao.md): zrange -> voxelize (when the slicemap is
// stale) -> cone_ao -> ao_upsample (when traced coarser than the frame), with
// the slicemap, its z range and the accumulated AO as history resources.
// Declared whenever a frame is built; the graph culls the chain when nothing
// reads the AO image.
#include <memory>

#include "renderer/passes/build_frame.hpp"

namespace iso::passes {

AmbientOcclusion ambient_occlusion(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb) {
    const auto plan = std::make_shared<const AoPlan>(plan_ao(ctx));
    AoResources res;
    res.zrange = fg.history("zrange", AoPlan::kZRangeDesc);
    res.slicemap = fg.history("slicemap", plan->slicemap_desc);
    if (plan->voxelize) {
        res.zrange = zrange(fg, ctx, gb, res.zrange);
        res.slicemap = voxelize(fg, ctx, plan, res.zrange, res.slicemap);
    }
    const auto history = fg.history(
        plan->coarse ? "ao_coarse" : "ao_accum",
        graph::TextureDesc{plan->ao_w, plan->ao_h, plan->coarse ? graph::Format::RGBA32F : graph::Format::R32F});
    AmbientOcclusion out;
    out.cones = cone_ao(fg, ctx, plan, gb, res, history);
    if (ctx.hooks.read_slicemap) read_slicemap(fg, ctx, plan, res);
    out.ao = plan->coarse ? ao_upsample(fg, ctx, plan, gb, out.cones.ao) : out.cones.ao;
    out.tracer = res;
    out.layers = plan->settings.layers;
    return out;
}

} // namespace iso::passes
