// Read-back of what the frame was asked for into RenderResult::image: the
// colour image (RGBA8, sRGB) or one AOV as floats, rows top to bottom.
#include <algorithm>
#include <limits>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

namespace {

template <class V> void flip_rows(V& v, int width, int height, int channels) {
    const std::ptrdiff_t row = std::ptrdiff_t(width) * channels;
    for (int y = 0; y < height / 2; ++y)
        std::swap_ranges(v.begin() + y * row, v.begin() + (y + 1) * row,
                         v.begin() + std::ptrdiff_t(height - 1 - y) * row);
}

void read_texture(const FrameContext& ctx, GLuint tex, Image& img) {
    const int W = ctx.width, H = ctx.height;
    img.width = W;
    img.height = H;
    const std::size_t n = std::size_t(W) * std::size_t(H);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    switch (ctx.opt.aov) {
    case Aov::None:
        img.channels = 4;
        img.bytes.resize(n * 4);
        glGetTextureImage(tex, 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(img.bytes.size()), img.bytes.data());
        flip_rows(img.bytes, W, H, 4);
        return;
    case Aov::Depth:
        img.channels = 1;
        img.is_float = true;
        img.floats.resize(n);
        glGetTextureImage(tex, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(n * 4), img.floats.data());
        // Distance along the view axis in mm; background (depth 0) is +infinity.
        for (auto& z : img.floats)
            z = z > 0.0f ? float(ctx.camera.linear_depth(z)) : std::numeric_limits<float>::infinity();
        break;
    case Aov::Normal: {
        std::vector<float> rgba(n * 4);
        glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * 4), rgba.data());
        img.channels = 3;
        img.is_float = true;
        img.floats.resize(n * 3);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t c = 0; c < 3; ++c) img.floats[i * 3 + c] = rgba[i * 4 + c];
        break;
    }
    case Aov::Ao: // NaN marks the background
        img.channels = 1;
        img.is_float = true;
        img.floats.resize(n);
        glGetTextureImage(tex, 0, GL_RED, GL_FLOAT, GLsizei(n * 4), img.floats.data());
        break;
    case Aov::Id: {
        std::vector<GLuint> ids(n);
        glGetTextureImage(tex, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, GLsizei(n * 4), ids.data());
        img.channels = 1;
        img.is_float = true;
        img.floats.assign(ids.begin(), ids.end());
        break;
    }
    }
    flip_rows(img.floats, W, H, img.channels);
}

} // namespace

void readback(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle source) {
    side_effect_pass(fg, "readback", {{source}, {}}, [&ctx](const Reads& d, const graph::Resources& r) {
        read_texture(ctx, ctx.gl->texture(r, d.textures[0]), ctx.result->image);
    });
}

} // namespace iso::passes
