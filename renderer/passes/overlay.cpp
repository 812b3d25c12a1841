// Overlay: annotation triangles (scale bar, orientation letters, labels,
// markups; renderer/frame/annotations.cpp builds them) blended over the colour
// image. Markups are compared with the G-buffer's depth and dimmed where a
// surface hides them.
#include <algorithm>
#include <bit>
#include <cstddef>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle overlay(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color,
                             graph::TextureHandle depth) {
    struct Data {
        graph::TextureHandle color, depth;
        graph::BufferHandle vertices, params;
    };
    // Sized to a power of two so that a changing label keeps its buffer.
    const std::size_t bytes = std::bit_ceil(std::max<std::size_t>(ctx.overlay.size() * sizeof(OverlayVertex), 256));
    return fg
        .add_pass<Data>(
            "overlay",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.color = b.write(b.read(color));
                d.depth = b.read(depth);
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
                const auto attribute = [&](GLuint index, GLint size, std::size_t offset) {
                    glEnableVertexArrayAttrib(vao, index);
                    glVertexArrayAttribFormat(vao, index, size, GL_FLOAT, GL_FALSE, GLuint(offset));
                    glVertexArrayAttribBinding(vao, index, 0);
                };
                attribute(0, 2, offsetof(OverlayVertex, pixel));
                attribute(1, 4, offsetof(OverlayVertex, color));
                attribute(2, 2, offsetof(OverlayVertex, anchor));
                attribute(3, 1, offsetof(OverlayVertex, inv_depth));
                attribute(4, 1, offsetof(OverlayVertex, along));
                attribute(5, 1, offsetof(OverlayVertex, hidden_alpha));
                glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.color)}}));
                glViewport(0, 0, ctx.width, ctx.height);
                auto& prog = gl.program({"render/overlay.vert", "render/overlay.frag"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.depth));
                const Annotations* a = ctx.opt.annotations;
                bind_params(gl, r, d.params,
                            OverlayParams{{float(ctx.width), float(ctx.height)},
                                          {float(ctx.camera.near_plane), float(ctx.camera.far_plane)},
                                          a ? a->occlusion_tolerance_mm : 1.0f,
                                          8.0f * std::max(ctx.opt.scale, 0.1f)});
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
