// DSRAA, decoupled sub-pixel reconstruction anti-aliasing (the massive-scenes
// thesis, section 3.1.5): the G-buffer pass stored ctx.aa_samples visibility
// sub-samples per pixel (object id and octahedral normal in one RG32UI
// channel; depth decided which) but the frame shaded one sample per pixel.
// Each sub-sample takes a shaded colour: its own pixel's when that pixel
// shows the same object with a similar normal, else that of the neighbour
// (of the 8) nearest to the sub-sample's position that does, else the
// background; the pixel is the mean of its sub-samples' colours in linear
// light (premultiplied by alpha, for transparent backgrounds). Runs after
// the translucent layers are composited, so a neighbour's colour carries
// what lies in front of it. Beyond the thesis, which maps a sub-sample
// nothing matches to the background: a surface's sub-sample is shaded from
// its own normal and albedo (no AO), so structures thinner than a pixel
// that no pixel's shaded sample hit still show (thin vessels); with
// translucent surfaces in the frame it takes its pixel's colour instead
// (shading it would leave out the layers in front).
//
// Only edge pixels are reconstructed: the G-buffer's sample-0 copy lists
// the pixels with a sub-sample that does not match their own (a few per
// cent of a frame), this pass copies the shaded frame and runs one compute
// invocation per listed pixel (glDispatchComputeIndirect). A full-screen
// reconstruction cost as much on every pixel: a software GL (llvmpipe)
// runs both sides of a branch for all pixels of its SIMD block.
#include <array>
#include <map>
#include <mutex>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lighting_params.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

namespace {

// Where the sub-samples lie in their pixel ([0, 1), from its lower-left
// corner): the GL's fixed pattern for `samples`, asked once (a multisample
// framebuffer must be bound to ask; `ms` is a multisample texture of them).
const float* sample_positions(GlResources& gl, GLuint ms, int samples) {
    static std::mutex guard; // frames of different contexts may run on different threads
    static std::map<int, std::array<float, 16>> patterns;
    const std::lock_guard lock(guard);
    auto pattern = patterns.find(samples);
    if (pattern == patterns.end()) {
        glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{ms}}));
        std::array<float, 16> p{};
        for (int s = 0; s < samples && s < 8; ++s) glGetMultisamplefv(GL_SAMPLE_POSITION, GLuint(s), &p[2 * s]);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        pattern = patterns.emplace(samples, p).first;
    }
    return pattern->second.data();
}

} // namespace

graph::TextureHandle dsraa(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                           graph::TextureHandle color) {
    if (ctx.aa_samples <= 1 || !gb.ms_vis.valid()) return color;
    struct Data {
        graph::TextureHandle color, id, normal, ms_vis, out;
        graph::BufferHandle objects, edges, params;
    };
    return fg
        .add_pass<Data>(
            "dsraa",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.color = b.read(color);
                d.id = b.read(gb.id);
                d.normal = b.read(gb.normal);
                d.ms_vis = b.read(gb.ms_vis);
                d.objects = b.read(gb.objects);
                d.edges = b.read(gb.edges);
                d.params = params_buffer<LightingParams>(b, "dsraa_params");
                d.out = b.write(b.create("dsraa", {ctx.width, ctx.height, graph::Format::RGBA8}));
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const int S = ctx.aa_samples;
                const float* positions = sample_positions(gl, gl.texture(r, d.ms_vis), S);
                // Every pixel as shaded, then the edge pixels reconstructed over it.
                glCopyImageSubData(GLuint(gl.texture(r, d.color)), GL_TEXTURE_2D, 0, 0, 0, 0,
                                   GLuint(gl.texture(r, d.out)), GL_TEXTURE_2D, 0, 0, 0, 0, ctx.width, ctx.height, 1);
                auto& prog = gl.program({"render/dsraa.comp"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.color));
                glBindTextureUnit(1, gl.texture(r, d.id));
                glBindTextureUnit(2, gl.texture(r, d.normal));
                glBindTextureUnit(3, gl.texture(r, d.ms_vis));
                glBindImageTexture(0, gl.texture(r, d.out), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.objects));
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.edges));
                const auto& look = ctx.opt.look;
                glUniform1i(prog.uniform("samples"), S);
                glUniform2fv(prog.uniform("sample_positions"), 8, positions);
                glUniform1f(prog.uniform("normal_cos"), look.aa.normal_cos);
                glUniform1i(prog.uniform("shade_unmatched"), ctx.translucent.empty() ? 1 : 0);
                // The lighting pass's parameters: the background as it writes it, the shading of unmatched sub-samples.
                bind_params(gl, r, d.params, lighting_params(ctx, look.ao != AoMethod::Off));
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                                GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
                glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, gl.buffer(r, d.edges));
                glDispatchComputeIndirect(0);
                glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                                GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
            })
        .out;
}

} // namespace iso::passes
