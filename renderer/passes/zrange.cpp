// Z range: the nearest and farthest visible linear depth (compute, atomics),
// the slicemap's local range.
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

graph::BufferHandle zrange(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                           graph::BufferHandle range) {
    struct Data {
        graph::TextureHandle depth;
        graph::BufferHandle range, params;
    };
    return fg
        .add_pass<Data>(
            "zrange",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.depth = b.read(gb.depth);
                d.range = b.write(range);
                d.params = params_buffer<ZRangeParams>(b, "zrange_params");
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const GLuint buf = gl.buffer(r, d.range);
                const GLuint init[2] = {0x7F800000u, 0u}; // +inf, 0
                glNamedBufferSubData(buf, 0, 8, init);
                auto& prog = gl.program({"ao/zrange.comp"});
                prog.use();
                glBindTextureUnit(0, gl.texture(r, d.depth));
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
                bind_params(
                    gl, r, d.params,
                    ZRangeParams{{ctx.width, ctx.height}, float(ctx.camera.near_plane), float(ctx.camera.far_plane)});
                glDispatchCompute(GLuint((ctx.width + 15) / 16), GLuint((ctx.height + 15) / 16), 1);
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            })
        .range;
}

} // namespace iso::passes
