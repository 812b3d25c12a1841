// AO upsampling: brings the coarse cone AO to full size with a joint
// bilateral filter (depth plane and normal aware: no halo across silhouettes).
#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

graph::TextureHandle ao_upsample(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const GBuffer& gb,
                                 graph::TextureHandle coarse) {
    struct Data {
        graph::TextureHandle depth, normal, coarse, ao;
    };
    return fg.add_pass<Data>(
                 "ao_upsample",
                 [&](graph::FrameGraph::Builder& b, Data& d) {
                     d.depth = b.read(gb.depth);
                     d.normal = b.read(gb.normal);
                     d.coarse = b.read(coarse);
                     d.ao = b.write(b.create("ao", {ctx.width, ctx.height, graph::Format::R32F}));
                 },
                 [&ctx, plan](const Data& d, const graph::Resources& r) {
                     GlResources& gl = *ctx.gl;
                     auto& prog = gl.program({"ao/ao_upsample.comp"});
                     prog.use();
                     glBindTextureUnit(0, gl.texture(r, d.depth));
                     glBindTextureUnit(1, gl.texture(r, d.normal));
                     glBindTextureUnit(2, gl.texture(r, d.coarse));
                     glBindImageTexture(0, gl.texture(r, d.ao), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
                     glUniformMatrix3fv(prog.uniform("world_to_view"), 1, GL_FALSE, &ctx.world_to_view[0][0]);
                     glUniform2f(prog.uniform("proj_scale"), plan->proj_scale.x, plan->proj_scale.y);
                     glUniform1f(prog.uniform("near_plane"), plan->near_plane);
                     glUniform1f(prog.uniform("far_plane"), plan->far_plane);
                     glUniform2i(prog.uniform("size"), ctx.width, ctx.height);
                     glUniform2i(prog.uniform("ao_size"), plan->ao_w, plan->ao_h);
                     glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                     glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
                 })
        .ao;
}

} // namespace iso::passes
