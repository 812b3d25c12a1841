// Ray-traced AO (docs/ao.md, "Ray-traced AO in the shaded image"): the AO
// term computed outside the frame (RenderOptions::ao_image, rows from the
// top) uploaded into a transient texture that lighting reads as it reads
// the cone or disk chain's.
#include <algorithm>

#include "io/error.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

graph::TextureHandle imported_ao(graph::FrameGraph& fg, const FrameContext& ctx) {
    const Image* img = ctx.opt.ao_image;
    if (!img) throw Error("ray-traced AO", "the frame needs its AO image (computed on the CPU before the frame)");
    if (img->width != ctx.width || img->height != ctx.height || img->channels != 1 || !img->is_float ||
        img->floats.size() != std::size_t(img->width) * std::size_t(img->height))
        throw Error("ray-traced AO", "the AO image must have one float channel and the frame's size (" +
                                         std::to_string(ctx.width) + "x" + std::to_string(ctx.height) + ")");
    struct Data {
        graph::TextureHandle ao;
    };
    return fg
        .add_pass<Data>(
            "ao_import",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.ao = b.write(b.create("ao_imported", {ctx.width, ctx.height, graph::Format::R32F}));
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                // GL's rows go bottom-up: the image's last row is the texture's first.
                const Image& im = *ctx.opt.ao_image;
                const GLuint tex = ctx.gl->texture(r, d.ao);
                glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
                for (int y = 0; y < im.height; ++y)
                    glTextureSubImage2D(tex, 0, 0, im.height - 1 - y, im.width, 1, GL_RED, GL_FLOAT,
                                        im.floats.data() + std::size_t(y) * im.width);
            })
        .ao;
}

} // namespace iso::passes
