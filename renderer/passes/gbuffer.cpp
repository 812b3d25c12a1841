// G-buffer: depth (reversed Z, float) and the channels of kGBufferLayout
// (world normal, object id, albedo) of the nearest surface, all meshes drawn
// once, two-sided. With DSRAA (ctx.aa_samples > 1) the meshes are drawn
// once into the visibility sub-samples: multisample depth and one RG32UI
// channel of object id and octahedral normal (8 bytes a sample besides
// depth, half of what the three channels would take: on a software GL the
// sub-samples' memory traffic is DSRAA's cost); the fragment shader still
// runs once per pixel and covered samples share its outputs, depth is per
// sample. A full-screen step then writes each pixel's sample 0 into the
// ordinary channels (the albedo from the object table): the one sample that
// the AO, lighting and translucency passes shade.
#include <cctype>
#include <iterator>

#include "renderer/passes/gbuffer_layout.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lod_draw.hpp"
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

void draw_meshes(const FrameContext& ctx, GlResources& gl, const graph::Resources& r, const GBuffer& d, bool vis,
                 GLuint depth, int samples) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDisable(GL_CULL_FACE); // open surfaces show both sides
    const auto program = [&](bool vis_variant) -> gl::Program& {
        return gl.program(
            {"render/gbuffer.vert", "render/gbuffer.frag"},
            clip_define(ctx) +
                (vis_variant
                     ? std::string("#define GB_VIS\n")
                     : gbuffer_defines() + (d.primitive.valid() ? "#define GB_PRIMITIVE " +
                                                                      std::to_string(std::size(kGBufferLayout)) + "\n"
                                                                : "")));
    };
    // The still frames after a DSRAA frame draw one sample: their program is
    // built with the first, not in the middle of the refinement.
    if (vis) program(false);
    auto& prog = program(vis);
    prog.use();
    set_clip(ctx, prog);
    bind_params(gl, r, d.params, GBufferParams{ctx.raster_view_projection});
    const GLint id_loc = prog.uniform("object_id"), albedo_loc = prog.uniform("albedo");
    // Surfaces with levels of detail are culled by clusters, which runs
    // compute steps between the draws: each draw binds the program again.
    draw_surfaces(
        ctx, gl, ctx.draws, DrawSet::Visible,
        [&](const DrawItem& m) {
            prog.use();
            glUniform1ui(id_loc, m.id);
            glUniform3fv(albedo_loc, 1, &m.color.x);
            if (d.primitive.valid()) bind_triangle_order(m, prog.id());
        },
        depth, samples);
    glBindVertexArray(0);
    glDisable(GL_DEPTH_TEST);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
}

// Each pixel's sample 0 of the sub-samples into the ordinary channels
// (depth through gl_FragDepth), and the edge list for DSRAA.
void copy_sample0(const FrameContext& ctx, GlResources& gl, const graph::Resources& r, const GBuffer& d, GLuint fb) {
    const GLuint header[4] = {0, 1, 1, 0}; // no groups of edge pixels yet (x, y, z), no edge pixels
    glNamedBufferSubData(gl.buffer(r, d.edges), 0, sizeof header, header);
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    auto& prog = gl.program({"render/fullscreen.vert", "render/gbuffer_sample.frag"}, gbuffer_defines());
    prog.use();
    glUniform1i(prog.uniform("samples"), ctx.aa_samples);
    glUniform1f(prog.uniform("normal_cos"), ctx.opt.look.aa.normal_cos);
    glBindTextureUnit(0, gl.texture(r, d.ms_depth));
    glBindTextureUnit(1, gl.texture(r, d.ms_vis));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.objects));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.edges));
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
                d.ms_vis = b.write(b.create("ms_vis", {W, H, graph::Format::RG32UI, 1, 1, false, S}));
                d.objects =
                    b.write(b.create("gbuffer_objects", graph::BufferDesc{ctx.objects.size() * sizeof(glm::vec4)}));
                // Header (4 uints) and up to one (pixel, mask) pair per pixel.
                d.edges = b.write(b.create("dsraa_edges", graph::BufferDesc{16 + std::size_t(W) * H * 8}));
            }
        },
        [&ctx, W, H, S](const GBuffer& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            std::vector<GlResources::Attachment> colors;
            for (const auto& c : kGBufferLayout) colors.push_back({gl.texture(r, d.*c.handle)});
            if (d.primitive.valid()) colors.push_back({gl.texture(r, d.primitive)});
            const GLuint fb = gl.framebuffer(colors, gl.texture(r, d.depth));
            glViewport(0, 0, W, H);
            if (S > 1) {
                glNamedBufferSubData(gl.buffer(r, d.objects), 0, GLsizeiptr(ctx.objects.size() * sizeof(glm::vec4)),
                                     ctx.objects.data());
                const GLuint ms_fb = gl.framebuffer({{gl.texture(r, d.ms_vis)}}, gl.texture(r, d.ms_depth));
                glBindFramebuffer(GL_FRAMEBUFFER, ms_fb);
                const GLuint zero_u[4] = {0, 0, 0, 0};
                const float far_depth = 0.0f; // reversed Z
                glClearNamedFramebufferuiv(ms_fb, GL_COLOR, 0, zero_u);
                glClearNamedFramebufferfv(ms_fb, GL_DEPTH, 0, &far_depth);
                draw_meshes(ctx, gl, r, d, true, gl.texture(r, d.ms_depth), S);
                copy_sample0(ctx, gl, r, d, fb);
            } else {
                glBindFramebuffer(GL_FRAMEBUFFER, fb);
                clear_gbuffer(fb, d.primitive.valid());
                draw_meshes(ctx, gl, r, d, false, gl.texture(r, d.depth), 1);
            }
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        });
}

} // namespace iso::passes
