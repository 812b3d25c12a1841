// Voxelize: the screen-aligned solid slicemap (XOR logic op over 128-bit
// columns per layer, local z range), then, with surface_voxels, the voxels
// next to every surface OR-ed in (thin walls); rebuilt only when stale
// (ao_plan.cpp).
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lod_draw.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle voxelize(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan,
                              graph::BufferHandle range, graph::TextureHandle slicemap) {
    struct Data {
        graph::BufferHandle range, params;
        graph::TextureHandle slicemap;
    };
    return fg
        .add_pass<Data>(
            "voxelize",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.range = b.read(range);
                d.slicemap = b.write(slicemap);
                d.params = params_buffer<VoxelizeParams>(b, "voxelize_params");
            },
            [&ctx, plan](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const GLuint tex = gl.texture(r, d.slicemap);
                const int layers = plan->settings.layers;
                std::vector<GlResources::Attachment> at;
                for (int l = 0; l < layers; ++l) at.push_back({tex, l});
                const GLuint fb = gl.framebuffer(at);
                const GLuint zero[4] = {0, 0, 0, 0};
                for (int l = 0; l < layers; ++l) glClearNamedFramebufferuiv(fb, GL_COLOR, l, zero);
                glBindFramebuffer(GL_FRAMEBUFFER, fb);
                glViewport(0, 0, plan->grid_w, plan->grid_h);
                glDisable(GL_DEPTH_TEST);
                glDisable(GL_CULL_FACE);
                glEnable(GL_DEPTH_CLAMP);
                glEnable(GL_COLOR_LOGIC_OP);
                glLogicOp(GL_XOR);
                glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
                auto& prog = gl.program({"ao/slicemap.vert", "ao/slicemap.frag"},
                                        "#define LAYERS " + std::to_string(layers) + "\n");
                prog.use();
                bind_params(gl, r, d.params,
                            VoxelizeParams{plan->sm_view_projection, plan->view, plan->scene_far, plan->near_margin,
                                           plan->radius});
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.range));
                // Levels of detail drawn whole (occluders outside the view count).
                draw_surfaces(ctx, gl, ctx.draws, DrawSet::Complete, [&](const DrawItem&) { prog.use(); });
                if (plan->settings.surface_voxels) {
                    // OR in the voxels next to every surface, on its solid's side
                    // (slicemap_surface.frag): walls thinner than a voxel in z stay.
                    glLogicOp(GL_OR);
                    auto& surface = gl.program({"ao/slicemap.vert", "ao/slicemap_surface.frag"},
                                               "#define LAYERS " + std::to_string(layers) + "\n");
                    draw_surfaces(ctx, gl, ctx.draws, DrawSet::Complete, [&](const DrawItem&) { surface.use(); });
                }
                glBindVertexArray(0);
                glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
                glDisable(GL_COLOR_LOGIC_OP);
                glDisable(GL_DEPTH_CLAMP);
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
                ctx.ao->view_key = plan->key;
                ctx.result->voxelized = true;
            })
        .slicemap;
}

} // namespace iso::passes
