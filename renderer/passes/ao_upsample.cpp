// AO upsampling: brings the coarse cone AO to full size with a joint
// bilateral filter (depth plane and normal aware: no halo across silhouettes).
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle ao_upsample(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan,
                                 const GBuffer& gb, graph::TextureHandle coarse) {
    struct Data {
        graph::TextureHandle depth, normal, coarse, ao;
        graph::BufferHandle params;
    };
    return fg
        .add_pass<Data>(
            "ao_upsample",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.depth = b.read(gb.depth);
                d.normal = b.read(gb.normal);
                d.coarse = b.read(coarse);
                d.ao = b.write(b.create("ao", {ctx.width, ctx.height, graph::Format::R32F}));
                d.params = params_buffer<UpsampleParams>(b, "upsample_params");
            },
            [&ctx, plan](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                auto& prog = gl.program({"ao/ao_upsample.comp"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.depth));
                glBindTextureUnit(1, gl.texture(r, d.normal));
                glBindTextureUnit(2, gl.texture(r, d.coarse));
                glBindImageTexture(0, gl.texture(r, d.ao), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
                bind_params(gl, r, d.params,
                            UpsampleParams{std140::mat3(ctx.world_to_view),
                                           {ctx.width, ctx.height},
                                           {plan->ao_w, plan->ao_h},
                                           plan->proj_scale,
                                           plan->near_plane,
                                           plan->far_plane});
                glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
            })
        .ao;
}

} // namespace iso::passes
