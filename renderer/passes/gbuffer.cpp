// G-buffer: depth (reversed Z, float), world normal, object id and albedo of
// the nearest surface, all meshes drawn once, two-sided.
#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

GBuffer gbuffer(graph::FrameGraph& fg, const FrameContext& ctx) {
    const int W = ctx.width, H = ctx.height;
    return fg.add_pass<GBuffer>(
        "gbuffer",
        [&](graph::FrameGraph::Builder& b, GBuffer& d) {
            d.depth = b.write(b.create("depth", {W, H, graph::Format::Depth32F}));
            d.normal = b.write(b.create("normal", {W, H, graph::Format::RGBA16F}));
            d.id = b.write(b.create("id", {W, H, graph::Format::R32UI}));
            d.albedo = b.write(b.create("albedo", {W, H, graph::Format::RGBA8}));
        },
        [&ctx, W, H](const GBuffer& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const GLuint fb = gl.framebuffer({{gl.texture(r, d.normal)}, {gl.texture(r, d.id)}, {gl.texture(r, d.albedo)}},
                                             gl.texture(r, d.depth));
            glBindFramebuffer(GL_FRAMEBUFFER, fb);
            glViewport(0, 0, W, H);
            const float zero[4] = {0, 0, 0, 0};
            const GLuint zero_u[4] = {0, 0, 0, 0};
            const float far_depth = 0.0f; // reversed Z
            glClearNamedFramebufferfv(fb, GL_COLOR, 0, zero);
            glClearNamedFramebufferuiv(fb, GL_COLOR, 1, zero_u);
            glClearNamedFramebufferfv(fb, GL_COLOR, 2, zero);
            glClearNamedFramebufferfv(fb, GL_DEPTH, 0, &far_depth);
            glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_GREATER);
            glDisable(GL_CULL_FACE); // open surfaces show both sides
            auto& prog = gl.program({"render/gbuffer.vert", "render/gbuffer.frag"});
            prog.use();
            glUniformMatrix4fv(prog.uniform("view_projection"), 1, GL_FALSE, &ctx.view_projection[0][0]);
            const GLint id_loc = prog.uniform("object_id"), albedo_loc = prog.uniform("albedo");
            for (const auto& m : ctx.draws) {
                glUniform1ui(id_loc, m.id);
                glUniform3fv(albedo_loc, 1, &m.color.x);
                glBindVertexArray(m.vao);
                glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
            }
            glBindVertexArray(0);
            glDisable(GL_DEPTH_TEST);
            glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        });
}

} // namespace iso::passes
