// Deferred lighting: key light and headlight, ambient modulated by AO when
// given, tone mapping, sRGB; background where nothing was drawn.
#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

graph::TextureHandle lighting(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, graph::TextureHandle ao) {
    struct Data {
        graph::TextureHandle normal, albedo, ao, color;
    };
    return fg.add_pass<Data>(
                 "lighting",
                 [&](graph::FrameGraph::Builder& b, Data& d) {
                     d.normal = b.read(gb.normal);
                     d.albedo = b.read(gb.albedo);
                     if (ao.valid()) d.ao = b.read(ao);
                     d.color = b.write(b.create("lit", {ctx.width, ctx.height, graph::Format::RGBA8}));
                 },
                 [&ctx](const Data& d, const graph::Resources& r) {
                     GlResources& gl = *ctx.gl;
                     glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.color)}}));
                     glViewport(0, 0, ctx.width, ctx.height);
                     auto& prog = gl.program({"render/fullscreen.vert", "render/lighting.frag"});
                     prog.use();
                     glBindTextureUnit(0, gl.texture(r, d.normal));
                     glBindTextureUnit(1, gl.texture(r, d.albedo));
                     glUniform1i(prog.uniform("normal_tex"), 0);
                     glUniform1i(prog.uniform("albedo_tex"), 1);
                     glUniform1i(prog.uniform("use_ao"), d.ao.valid() ? 1 : 0);
                     if (d.ao.valid()) {
                         glBindTextureUnit(2, gl.texture(r, d.ao));
                         glUniform1i(prog.uniform("ao_tex"), 2);
                     }
                     glUniformMatrix3fv(prog.uniform("world_to_view"), 1, GL_FALSE, &ctx.world_to_view[0][0]);
                     glUniform4fv(prog.uniform("background"), 1, &ctx.opt.background.x);
                     glBindVertexArray(gl.vertex_array("fullscreen"));
                     glDrawArrays(GL_TRIANGLES, 0, 3);
                     glBindVertexArray(0);
                     glBindFramebuffer(GL_FRAMEBUFFER, 0);
                 })
        .color;
}

} // namespace iso::passes
