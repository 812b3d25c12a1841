// DSRAA, decoupled sub-pixel reconstruction anti-aliasing (the massive-scenes
// thesis, section 3.1.5): the G-buffer pass stored ctx.aa_samples visibility
// sub-samples per pixel (object id and normal; depth decided which) but the
// frame shaded one sample per pixel. Here each sub-sample takes a shaded
// colour: its own pixel's when that pixel shows the same object with a
// similar normal, else that of the neighbour (of the 8) nearest to the
// sub-sample's position that does, else the background; the pixel is the
// mean of its sub-samples' colours in linear light (premultiplied by
// alpha, for transparent backgrounds). Runs after the translucent layers
// are composited, so a neighbour's colour carries what lies in front of it.
// Beyond the thesis, which maps a sub-sample nothing matches to the
// background: a surface's sub-sample is shaded from its own normal and
// albedo (no AO), so structures thinner than a pixel that no pixel's shaded
// sample hit still show (thin vessels); with translucent surfaces in the
// frame it takes its pixel's colour instead (shading it would leave out the
// layers in front).
#include <array>
#include <map>
#include <mutex>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::TextureHandle dsraa(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                           graph::TextureHandle color) {
    if (ctx.aa_samples <= 1 || !gb.ms_id.valid()) return color;
    struct Data {
        graph::TextureHandle color, id, normal, ms_id, ms_normal, ms_albedo, out;
        graph::BufferHandle params;
    };
    return fg
        .add_pass<Data>(
            "dsraa",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.color = b.read(color);
                d.id = b.read(gb.id);
                d.normal = b.read(gb.normal);
                d.ms_id = b.read(gb.ms_id);
                d.ms_normal = b.read(gb.ms_normal);
                d.ms_albedo = b.read(gb.ms_albedo);
                d.params = params_buffer<LightingParams>(b, "dsraa_params");
                d.out = b.write(b.create("dsraa", {ctx.width, ctx.height, graph::Format::RGBA8}));
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const int S = ctx.aa_samples;
                // Where the sub-samples lie in their pixel ([0, 1), from its
                // lower-left corner): the GL's fixed pattern for S samples,
                // asked once (a multisample framebuffer must be bound to ask).
                static std::mutex guard; // frames of different contexts may run on different threads
                static std::map<int, std::array<float, 16>> patterns;
                const std::lock_guard lock(guard);
                auto pattern = patterns.find(S);
                if (pattern == patterns.end()) {
                    glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.ms_id)}}));
                    std::array<float, 16> p{};
                    for (int s = 0; s < S && s < 8; ++s) glGetMultisamplefv(GL_SAMPLE_POSITION, GLuint(s), &p[2 * s]);
                    pattern = patterns.emplace(S, p).first;
                }
                const float* positions = pattern->second.data();
                glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({{gl.texture(r, d.out)}}));
                glViewport(0, 0, ctx.width, ctx.height);
                auto& prog = gl.program({"render/fullscreen.vert", "render/dsraa.frag"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.color));
                glBindTextureUnit(1, gl.texture(r, d.id));
                glBindTextureUnit(2, gl.texture(r, d.normal));
                glBindTextureUnit(3, gl.texture(r, d.ms_id));
                glBindTextureUnit(4, gl.texture(r, d.ms_normal));
                glBindTextureUnit(5, gl.texture(r, d.ms_albedo));
                const auto& look = ctx.opt.look;
                glUniform1i(prog.uniform("samples"), S);
                glUniform2fv(prog.uniform("sample_positions"), 8, positions);
                glUniform1f(prog.uniform("normal_cos"), look.aa.normal_cos);
                glUniform1i(prog.uniform("shade_unmatched"), ctx.translucent.empty() ? 1 : 0);
                // The lighting pass's parameters: the background as it writes it, the shading of unmatched sub-samples.
                bind_params(gl, r, d.params,
                            LightingParams{std140::mat3(ctx.world_to_view),
                                           glm::vec4(look.background, look.transparent_background ? 0.0f : 1.0f),
                                           look.ao != AoMethod::Off ? 1u : 0u, look.flat_shading ? 1u : 0u});
                glBindVertexArray(gl.vertex_array("fullscreen"));
                glDrawArrays(GL_TRIANGLES, 0, 3);
                glBindVertexArray(0);
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
            })
        .out;
}

} // namespace iso::passes
