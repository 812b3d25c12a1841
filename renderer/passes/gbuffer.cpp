// G-buffer: depth (reversed Z, float) and the channels of kGBufferLayout
// (world normal, object id, albedo) of the nearest surface, all meshes drawn
// once, two-sided.
#include <cctype>
#include <iterator>

#include "renderer/passes/gbuffer_layout.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

bool is_integer(graph::Format f) { return f == graph::Format::R32UI || f == graph::Format::RGBA32UI; }

std::string gbuffer_defines() {
    std::string d;
    int location = 0;
    for (const auto& c : kGBufferLayout) {
        std::string name = c.name;
        for (auto& ch : name) ch = char(std::toupper(static_cast<unsigned char>(ch)));
        d += "#define GB_" + name + " " + std::to_string(location++) + "\n";
    }
    return d;
}

GBuffer gbuffer(graph::FrameGraph& fg, const FrameContext& ctx) {
    const int W = ctx.width, H = ctx.height;
    return fg.add_pass<GBuffer>(
        "gbuffer",
        [&](graph::FrameGraph::Builder& b, GBuffer& d) {
            d.depth = b.write(b.create("depth", {W, H, graph::Format::Depth32F}));
            for (const auto& c : kGBufferLayout) d.*c.handle = b.write(b.create(c.name, {W, H, c.format}));
            d.params = params_buffer<GBufferParams>(b, "gbuffer_params");
            // With a pick, the triangle of each pixel's nearest opaque surface
            // too: the pick's opaque layer (pick.cpp).
            if (ctx.pick) d.primitive = b.write(b.create("primitive", {W, H, graph::Format::R32UI}));
        },
        [&ctx, W, H](const GBuffer& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            std::vector<GlResources::Attachment> colors;
            for (const auto& c : kGBufferLayout) colors.push_back({gl.texture(r, d.*c.handle)});
            if (d.primitive.valid()) colors.push_back({gl.texture(r, d.primitive)});
            const GLuint fb = gl.framebuffer(colors, gl.texture(r, d.depth));
            glBindFramebuffer(GL_FRAMEBUFFER, fb);
            glViewport(0, 0, W, H);
            const float zero[4] = {0, 0, 0, 0};
            const GLuint zero_u[4] = {0, 0, 0, 0};
            for (GLint i = 0; const auto& c : kGBufferLayout) {
                if (is_integer(c.format))
                    glClearNamedFramebufferuiv(fb, GL_COLOR, i++, zero_u);
                else
                    glClearNamedFramebufferfv(fb, GL_COLOR, i++, zero);
            }
            if (d.primitive.valid()) glClearNamedFramebufferuiv(fb, GL_COLOR, GLint(std::size(kGBufferLayout)), zero_u);
            const float far_depth = 0.0f; // reversed Z
            glClearNamedFramebufferfv(fb, GL_DEPTH, 0, &far_depth);
            glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_GREATER);
            glDisable(GL_CULL_FACE); // open surfaces show both sides
            auto& prog = gl.program(
                {"render/gbuffer.vert", "render/gbuffer.frag"},
                gbuffer_defines() + (d.primitive.valid()
                                         ? "#define GB_PRIMITIVE " + std::to_string(std::size(kGBufferLayout)) + "\n"
                                         : ""));
            prog.use();
            bind_params(gl, r, d.params, GBufferParams{ctx.view_projection});
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
