// Deferred lighting: key light and headlight, ambient modulated by AO when
// given, tone mapping, sRGB; background where nothing was drawn.
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lighting_params.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle lighting(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                              graph::TextureHandle ao) {
    struct Data {
        graph::TextureHandle normal, albedo, ao, color;
        graph::BufferHandle params;
    };
    return fg
        .add_pass<Data>(
            "lighting",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.normal = b.read(gb.normal);
                d.albedo = b.read(gb.albedo);
                if (ao.valid()) d.ao = b.read(ao);
                d.color = b.write(b.create("lit", {ctx.width, ctx.height, graph::Format::RGBA8}));
                d.params = params_buffer<LightingParams>(b, "lighting_params");
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.color)}}));
                glViewport(0, 0, ctx.width, ctx.height);
                auto& prog = gl.program({"render/fullscreen.vert", "render/lighting.frag"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.normal));
                glBindTextureUnit(1, gl.texture(r, d.albedo));
                if (d.ao.valid()) glBindTextureUnit(2, gl.texture(r, d.ao));
                bind_params(gl, r, d.params, lighting_params(ctx, d.ao.valid()));
                glBindVertexArray(gl.vertex_array("fullscreen"));
                glDrawArrays(GL_TRIANGLES, 0, 3);
                glBindVertexArray(0);
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
            })
        .color;
}

} // namespace iso::passes
