// G-buffer: depth (reversed Z, float) and the channels of kGBufferLayout
// (world normal, object id, albedo) of the nearest surface, all meshes drawn
// once, two-sided. With DSRAA (ctx.aa_samples > 1) the meshes are drawn
// once into multisample channels, the visibility sub-samples (the fragment
// shader still runs once per pixel and covered samples share its outputs;
// depth is per sample), and a full-screen step copies each pixel's sample 0
// into the ordinary channels: the one sample that the AO, lighting and
// translucency passes shade.
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

namespace {

// Clears the channels (and the pick's primitive) to 0 and the depth to far.
void clear_gbuffer(GLuint fb, bool primitive) {
    const float zero[4] = {0, 0, 0, 0};
    const GLuint zero_u[4] = {0, 0, 0, 0};
    for (GLint i = 0; const auto& c : kGBufferLayout) {
        if (is_integer(c.format))
            glClearNamedFramebufferuiv(fb, GL_COLOR, i++, zero_u);
        else
            glClearNamedFramebufferfv(fb, GL_COLOR, i++, zero);
    }
    if (primitive) glClearNamedFramebufferuiv(fb, GL_COLOR, GLint(std::size(kGBufferLayout)), zero_u);
    const float far_depth = 0.0f; // reversed Z
    glClearNamedFramebufferfv(fb, GL_DEPTH, 0, &far_depth);
}

void draw_meshes(const FrameContext& ctx, GlResources& gl, const graph::Resources& r, const GBuffer& d) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDisable(GL_CULL_FACE); // open surfaces show both sides
    auto& prog = gl.program(
        {"render/gbuffer.vert", "render/gbuffer.frag"},
        gbuffer_defines() +
            (d.primitive.valid() ? "#define GB_PRIMITIVE " + std::to_string(std::size(kGBufferLayout)) + "\n" : ""));
    prog.use();
    bind_params(gl, r, d.params, GBufferParams{ctx.raster_view_projection});
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
}

// Each pixel's sample 0 of the sub-samples into the ordinary channels (depth through gl_FragDepth).
void copy_sample0(GlResources& gl, const graph::Resources& r, const GBuffer& d, GLuint fb) {
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    gl.program({"render/fullscreen.vert", "render/gbuffer_sample.frag"}, gbuffer_defines()).use();
    glBindTextureUnit(0, gl.texture(r, d.ms_depth));
    for (GLuint unit = 1; const auto& c : kGBufferLayout) glBindTextureUnit(unit++, gl.texture(r, d.*c.ms_handle));
    glBindVertexArray(gl.vertex_array("fullscreen"));
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glDepthFunc(GL_GREATER);
    glDisable(GL_DEPTH_TEST);
}

} // namespace

GBuffer gbuffer(graph::FrameGraph& fg, const FrameContext& ctx) {
    const int W = ctx.width, H = ctx.height, S = ctx.aa_samples;
    return fg.add_pass<GBuffer>(
        "gbuffer",
        [&](graph::FrameGraph::Builder& b, GBuffer& d) {
            d.depth = b.write(b.create("depth", {W, H, graph::Format::Depth32F}));
            for (const auto& c : kGBufferLayout) d.*c.handle = b.write(b.create(c.name, {W, H, c.format}));
            d.params = params_buffer<GBufferParams>(b, "gbuffer_params");
            // With a pick, the triangle of each pixel's nearest opaque surface
            // too: the pick's opaque layer (pick.cpp).
            if (ctx.pick) d.primitive = b.write(b.create("primitive", {W, H, graph::Format::R32UI}));
            if (S > 1) {
                d.ms_depth = b.write(b.create("ms_depth", {W, H, graph::Format::Depth32F, 1, 1, false, S}));
                for (const auto& c : kGBufferLayout)
                    d.*c.ms_handle = b.write(b.create(std::string("ms_") + c.name, {W, H, c.format, 1, 1, false, S}));
            }
        },
        [&ctx, W, H, S](const GBuffer& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            std::vector<GlResources::Attachment> colors, ms_colors;
            for (const auto& c : kGBufferLayout) colors.push_back({gl.texture(r, d.*c.handle)});
            if (d.primitive.valid()) colors.push_back({gl.texture(r, d.primitive)});
            const GLuint fb = gl.framebuffer(colors, gl.texture(r, d.depth));
            glViewport(0, 0, W, H);
            if (S > 1) {
                for (const auto& c : kGBufferLayout) ms_colors.push_back({gl.texture(r, d.*c.ms_handle)});
                const GLuint ms_fb = gl.framebuffer(ms_colors, gl.texture(r, d.ms_depth));
                glBindFramebuffer(GL_FRAMEBUFFER, ms_fb);
                clear_gbuffer(ms_fb, false);
                draw_meshes(ctx, gl, r, d);
                copy_sample0(gl, r, d, fb);
            } else {
                glBindFramebuffer(GL_FRAMEBUFFER, fb);
                clear_gbuffer(fb, d.primitive.valid());
                draw_meshes(ctx, gl, r, d);
            }
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        });
}

} // namespace iso::passes
