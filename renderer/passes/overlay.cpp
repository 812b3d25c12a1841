// Overlay: annotation triangles (scale bar, orientation letters, labels;
// renderer/render/overlay.cpp builds them) blended over the colour image.
#include <bit>

#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle overlay(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color) {
    struct Data {
        graph::TextureHandle color;
        graph::BufferHandle vertices, params;
    };
    // Sized to a power of two so that a changing label keeps its buffer.
    const std::size_t bytes = std::bit_ceil(std::max<std::size_t>(ctx.overlay.size() * sizeof(OverlayVertex), 256));
    return fg.add_pass<Data>(
                 "overlay",
                 [&](graph::FrameGraph::Builder& b, Data& d) {
                     d.color = b.write(b.read(color));
                     d.vertices = b.write(b.create("overlay_vertices", graph::BufferDesc{bytes}));
                     d.params = params_buffer<OverlayParams>(b, "overlay_params");
                 },
                 [&ctx](const Data& d, const graph::Resources& r) {
                     if (ctx.overlay.empty()) return;
                     GlResources& gl = *ctx.gl;
                     const GLuint vb = gl.buffer(r, d.vertices);
                     glNamedBufferSubData(vb, 0, GLsizeiptr(ctx.overlay.size() * sizeof(OverlayVertex)), ctx.overlay.data());
                     const GLuint vao = gl.vertex_array("overlay");
                     glVertexArrayVertexBuffer(vao, 0, vb, 0, sizeof(OverlayVertex));
                     glEnableVertexArrayAttrib(vao, 0);
                     glVertexArrayAttribFormat(vao, 0, 2, GL_FLOAT, GL_FALSE, 0);
                     glVertexArrayAttribBinding(vao, 0, 0);
                     glEnableVertexArrayAttrib(vao, 1);
                     glVertexArrayAttribFormat(vao, 1, 4, GL_FLOAT, GL_FALSE, sizeof(glm::vec2));
                     glVertexArrayAttribBinding(vao, 1, 0);
                     glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.color)}}));
                     glViewport(0, 0, ctx.width, ctx.height);
                     auto& prog = gl.program({"render/overlay.vert", "render/overlay.frag"});
                     prog.use();
                     bind_params(gl, r, d.params, OverlayParams{{float(ctx.width), float(ctx.height)}});
                     glEnable(GL_BLEND);
                     // Colour blends; alpha accumulates so a transparent background keeps annotations opaque.
                     glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
                     glBindVertexArray(vao);
                     glDrawArrays(GL_TRIANGLES, 0, GLsizei(ctx.overlay.size()));
                     glBindVertexArray(0);
                     glDisable(GL_BLEND);
                     glBindFramebuffer(GL_FRAMEBUFFER, 0);
                 })
        .color;
}

} // namespace iso::passes
