// The cone-AO passes' plan for one frame: the guard band, the slicemap and
// AO grid sizes, the z range bounds and whether the slicemap is stale. Pure
// CPU; shared by zrange, voxelize, cone_ao, ao_upsample and read_slicemap.
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "io/error.hpp"
#include "renderer/ao/cone_pattern.hpp"
#include "renderer/passes/build_frame.hpp"

namespace iso::passes {

namespace {

// Guard band: occluders just outside the view still darken visible points
// within R of them, so when the scene reaches beyond the viewport the
// slicemap covers a margin around it (same texel density), wide enough for R
// at the scene's nearest depth, at most `guard` of the viewport per side. A
// scene wholly in view needs none.
double guard_band(const FrameContext& ctx, const ConeAoSettings& st, double aspect) {
    const Bounds& sb = ctx.bounds;
    const glm::dmat4 vp = ctx.camera.projection(aspect) * ctx.camera.view();
    const glm::dmat4 v = ctx.camera.view();
    bool outside = false;
    double nearest = std::numeric_limits<double>::infinity();
    for (int c = 0; !sb.empty() && c < 8; ++c) {
        const glm::dvec4 w(sb.corner(c), 1.0);
        const glm::dvec4 clip = vp * w;
        outside |= clip.w <= 0 || std::abs(clip.x) > clip.w || std::abs(clip.y) > clip.w;
        nearest = std::min(nearest, -(v * w).z);
    }
    if (!outside || st.guard <= 0) return 0;
    const glm::dmat4 pr = ctx.camera.projection(aspect);
    const double d = std::max(nearest, ctx.camera.near_plane);
    return std::min(st.guard, 0.5 * st.radius_mm * std::max(pr[0][0], pr[1][1]) / d);
}

} // namespace

AoPlan plan_ao(const FrameContext& ctx) {
    AoPlan p;
    const int W = ctx.width, H = ctx.height;
    const double aspect = double(W) / double(H);
    p.settings = ctx.opt.look.cone;
    // The chain is declared even when AO is off (the graph culls it); bad
    // settings matter only when AO is asked for, and build_frame() refuses
    // them then.
    try {
        validate(p.settings);
    } catch (const Error&) {
        p.settings = ConeAoSettings{};
    }
    const ConeAoSettings& st = p.settings;
    p.guard = guard_band(ctx, st, aspect);
    // Whole texels of margin, so the texels stay aligned with those of the
    // viewport's own grid (a fractional shift would move every edge by up to
    // half a texel).
    const int gw0 = std::max(1, int(std::lround(W * st.grid_scale)));
    const int gh0 = std::max(1, int(std::lround(H * st.grid_scale)));
    p.grid_w = gw0 + 2 * int(std::ceil(p.guard * gw0));
    p.grid_h = gh0 + 2 * int(std::ceil(p.guard * gh0));
    p.sm_scale = {float(gw0) / float(p.grid_w), float(gh0) / float(p.grid_h)}; // slicemap NDC per frame NDC
    // The cone pass's own image when it runs coarser than the frame.
    p.ao_w = std::max(1, int(std::lround(W * st.resolution)));
    p.ao_h = std::max(1, int(std::lround(H * st.resolution)));
    p.coarse = p.ao_w != W || p.ao_h != H;
    // The scene's far bound along the view axis (the slicemap's range).
    double scene_far = 0;
    const Bounds& sb = ctx.bounds;
    if (!sb.empty())
        for (int c = 0; c < 8; ++c)
            scene_far = std::max(scene_far, -(ctx.camera.view() * glm::dvec4(sb.corner(c), 1.0)).z);
    p.scene_far = float(scene_far);
    p.radius = float(st.radius_mm);
    p.near_margin = p.guard > 0 ? p.radius : 0.0f;
    p.near_plane = float(ctx.camera.near_plane);
    p.far_plane = float(ctx.camera.far_plane);
    const glm::dmat4 proj = ctx.camera.projection(aspect);
    p.proj_scale = {float(proj[0][0]), float(proj[1][1])};
    // The slicemap's projection: the frame's, its x and y shrunk by the guard band.
    p.sm_projection = glm::scale(glm::dmat4(1.0), glm::dvec3(p.sm_scale.x, p.sm_scale.y, 1.0)) * proj;
    p.sm_view_projection = glm::mat4(p.sm_projection * ctx.camera.view());
    p.view = glm::mat4(ctx.camera.view());
    // What the slicemap depends on: camera, viewport, grid, radius (its z
    // range), the geometry and which objects are visible.
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) p.key.push_back(double(ctx.view_projection[c][r]));
    p.key.insert(p.key.end(), {double(W), double(H), double(p.grid_w), double(p.grid_h), p.guard, double(st.layers),
                               st.radius_mm, double(ctx.geometry_version), double(st.surface_voxels)});
    for (const auto& d : ctx.draws) p.key.push_back(double(d.id)); // which objects are visible
    p.slicemap_desc = graph::TextureDesc{p.grid_w, p.grid_h, graph::Format::RGBA32UI, st.layers, 1, true};
    const bool kept = ctx.pool && ctx.ao && ctx.pool->has_history("slicemap", p.slicemap_desc) &&
                      ctx.pool->has_history("zrange", AoPlan::kZRangeDesc);
    p.voxelize = !kept || !ctx.ao || p.key != ctx.ao->view_key || ctx.hooks.ao_force_voxelize;
    // cone_pattern(): cone axes, one vec4 per jitter set, then the sets' samples.
    p.pattern_bytes = std::size_t(st.cones + st.jitter_sets * (1 + st.samples)) * sizeof(glm::vec4);
    return p;
}

} // namespace iso::passes
