// Accumulation of jittered frames (RenderOptions::accumulate): each frame is
// rasterized with a sub-pixel offset (set_jitter) and averaged into a
// history image in linear light, so the average converges to exact
// coverage: of opaque edges, translucent layers and the overlay alike. The
// renderer restarts the average when anything but the jitter changes
// (accumulation_key); so does a new history image.
#include <cmath>
#include <functional>
#include <string_view>

#include "renderer/ao/sequences.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

namespace {
template <class T> double hash_of(const std::vector<T>& v) {
    const std::string_view bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    return double(std::hash<std::string_view>{}(bytes) >> 11); // exact in a double
}
} // namespace

glm::vec2 jitter_offset(int k) {
    // Halton (2, 3) turned by half a pixel (Cranley-Patterson), so that frame 0 is the pixel's centre.
    const auto at = [](double h) { return float(h + 0.5 - std::floor(h + 0.5) - 0.5); };
    return {at(sequences::radical_inverse(std::uint32_t(k), 2)), at(sequences::radical_inverse(std::uint32_t(k), 3))};
}

std::vector<double> accumulation_key(const FrameContext& ctx) {
    std::vector<double> key;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) key.push_back(double(ctx.view_projection[c][r]));
    key.insert(key.end(), {double(ctx.width), double(ctx.height), double(ctx.geometry_version)});
    for (const auto* list : {&ctx.draws, &ctx.translucent})
        for (const auto& d : *list) key.insert(key.end(), {double(d.id), d.color.r, d.color.g, d.color.b, d.opacity});
    // The look (FrameLook has no hash: its members that change a picture).
    const FrameLook& l = ctx.opt.look;
    key.insert(key.end(), {l.background.r, l.background.g, l.background.b, double(l.transparent_background),
                           double(l.transparency), double(l.flat_shading), double(l.ao), l.cone.radius_mm,
                           double(l.aa.samples), double(l.ao_frames)});
    // The volume: whether drawn, its transfer function, mode, step, shading; the clip.
    if (ctx.volume) {
        const VolumeLook& v = l.volume;
        key.insert(key.end(), {1.0, double(v.mode), v.step, double(v.shading), double(v.skip_empty)});
        for (std::size_t i = 0; i < v.tf.points().size(); ++i) {
            const glm::dvec3 c = v.tf.linear_color(i);
            key.insert(key.end(), {v.tf.points()[i].value, v.tf.points()[i].opacity, c.r, c.g, c.b});
        }
    }
    for (const auto& h : l.clip.half_spaces()) key.insert(key.end(), {h.normal.x, h.normal.y, h.normal.z, h.offset});
    // The AO term computed outside the frame (ray-traced AO: a new batch is a new picture).
    if (ctx.opt.ao_image) key.push_back(hash_of(ctx.opt.ao_image->floats));
    // The overlay's geometry and text.
    key.push_back(hash_of(ctx.overlay.vertices));
    key.push_back(hash_of(ctx.overlay.atlas.texels));
    return key;
}

graph::TextureHandle accumulate(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color) {
    struct Data {
        graph::TextureHandle color, history, out;
    };
    const int W = ctx.width, H = ctx.height;
    const graph::TextureHandle history = fg.history("aa_history", {W, H, graph::Format::RGBA32F});
    return fg
        .add_pass<Data>(
            "accumulate",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.color = b.read(color);
                d.history = b.write(history);
                d.out = b.write(b.create("accumulated", {W, H, graph::Format::RGBA8}));
            },
            [&ctx, W, H](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const int n = r.fresh(d.history) || !ctx.aa ? 0 : ctx.aa_frame; // frames already in the mean
                auto& prog = gl.program({"render/accumulate.comp"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.color));
                glBindImageTexture(0, gl.texture(r, d.history), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
                glBindImageTexture(1, gl.texture(r, d.out), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
                glUniform1f(prog.uniform("weight"), 1.0f / float(n + 1));
                glUniform2i(prog.uniform("size"), W, H);
                glDispatchCompute(GLuint((W + 7) / 8), GLuint((H + 7) / 8), 1);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                                GL_TEXTURE_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
                if (ctx.aa) ctx.aa->frames = n + 1;
                if (ctx.result) ctx.result->aa_frames = n + 1;
            })
        .out;
}

} // namespace iso::passes
