// Overlay: annotation triangles (scale bar, orientation letters, labels,
// markups; renderer/frame/annotations.cpp builds them) blended over the colour
// image, text through the frame's glyph atlas (uploaded here into a pooled
// texture: a steady view keeps its size). Markup lines and glyphs are
// compared with the G-buffer's depth and dimmed where a surface hides them;
// labels never are.
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
        graph::TextureHandle color, depth, atlas;
        graph::BufferHandle vertices, params;
    };
    const auto& vertices = ctx.overlay.vertices;
    const text::AtlasImage& atlas = ctx.overlay.atlas;
    // Sized to a power of two so that a changing label keeps its buffer (the atlas is one already).
    const std::size_t bytes = std::bit_ceil(std::max<std::size_t>(vertices.size() * sizeof(OverlayVertex), 256));
    const graph::TextureDesc atlas_desc{std::max(atlas.width, 1), std::max(atlas.height, 1), graph::Format::RGBA8};
    return fg
        .add_pass<Data>(
            "overlay",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.color = b.write(b.read(color));
                d.depth = b.read(depth);
                d.vertices = b.write(b.create("overlay_vertices", graph::BufferDesc{bytes}));
                d.atlas = b.write(b.create("overlay_atlas", atlas_desc));
                d.params = params_buffer<OverlayParams>(b, "overlay_params");
            },
            [&ctx, &vertices, &atlas](const Data& d, const graph::Resources& r) {
                if (ctx.result) ctx.result->labels = ctx.overlay.labels;
                if (vertices.empty()) return;
                GlResources& gl = *ctx.gl;
                const GLuint vb = gl.buffer(r, d.vertices);
                glNamedBufferSubData(vb, 0, GLsizeiptr(vertices.size() * sizeof(OverlayVertex)), vertices.data());
                const GLuint atlas_tex = gl.texture(r, d.atlas);
                if (!atlas.texels.empty()) { // coverage and halo into red and green; rows of 2 x 2^n bytes
                    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
                    glTextureSubImage2D(atlas_tex, 0, 0, 0, atlas.width, atlas.height, GL_RG, GL_UNSIGNED_BYTE,
                                        atlas.texels.data());
                    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
                }
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
                attribute(6, 2, offsetof(OverlayVertex, texel));
                attribute(7, 1, offsetof(OverlayVertex, atlas_channel));
                glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.color)}}));
                glViewport(0, 0, ctx.width, ctx.height);
                auto& prog = gl.program({"render/overlay.vert", "render/overlay.frag"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.depth));
                glBindTextureUnit(1, atlas_tex);
                const Annotations* a = ctx.opt.annotations;
                bind_params(gl, r, d.params,
                            OverlayParams{{float(ctx.width), float(ctx.height)},
                                          {float(ctx.camera.near_plane), float(ctx.camera.far_plane)},
                                          a ? a->occlusion_tolerance_mm : 1.0f,
                                          8.0f * std::max(ctx.opt.scale, 0.1f), ctx.jitter});
                glEnable(GL_BLEND);
                // Colour blends; alpha accumulates so a transparent background keeps annotations opaque.
                glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
                glBindVertexArray(vao);
                glDrawArrays(GL_TRIANGLES, 0, GLsizei(vertices.size()));
                glBindVertexArray(0);
                glDisable(GL_BLEND);
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
            })
        .color;
}

} // namespace iso::passes
