// Picking (docs/picking.md): a pick rides on a frame. The frame's own
// geometry passes give it what it needs, with no extra pass over the scene:
// the G-buffer writes each pixel's triangle next to its object id (the
// nearest opaque surface), and the VOIT list pass appends every translucent
// fragment inside the pick region to that region pixel's linked list
// (shaders/render/pick_common.glsl). Then two small passes:
//   pick_resolve  compute: adds the G-buffer's opaque surface to each
//                 pixel's list, sorts it front to back, ends it there,
//                 writes the transmittance in front of each entry
//   read_pick     reads the lists back into RenderResult::pick
#include <algorithm>
#include <cstring>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

namespace {

constexpr std::size_t kEntryWords = 6; // PickEntry in pick_common.glsl
constexpr std::uint32_t kEnd = 0xFFFFFFFFu;

std::size_t region_pixels(const FrameContext& ctx) {
    return ctx.pick ? std::size_t(ctx.pick->width) * std::size_t(ctx.pick->height) : 0;
}

} // namespace

glm::ivec4 pick_rect_gl(const FrameContext& ctx) {
    const PickRegion& p = *ctx.pick;
    return {p.x, ctx.height - p.y - p.height, p.width, p.height};
}

std::size_t pick_capacity(const FrameContext& ctx) {
    return std::clamp<std::size_t>(64 * region_pixels(ctx), 4096, std::size_t(1) << 22);
}

PickBuffers write_pick(graph::FrameGraph::Builder& b, const FrameContext& ctx, const PickBuffers& previous) {
    PickBuffers p;
    if (!ctx.pick) return p;
    if (!previous.valid()) {
        p.counters = b.write(b.create("pick_counters", graph::BufferDesc{8}));
        p.entries = b.write(b.create("pick_entries", graph::BufferDesc{pick_capacity(ctx) * kEntryWords * 4}));
        p.heads = b.write(b.create("pick_heads", graph::BufferDesc{region_pixels(ctx) * 4}));
    } else {
        p.counters = b.write(b.read(previous.counters));
        p.entries = b.write(b.read(previous.entries));
        p.heads = b.write(b.read(previous.heads));
    }
    return p;
}

void bind_pick(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const PickBuffers& p,
               iso::gl::Program& prog, bool first) {
    if (!p.valid()) return;
    if (first) {
        const GLuint counters[2] = {0, GLuint(pick_capacity(ctx))};
        glNamedBufferSubData(gl.buffer(r, p.counters), 0, sizeof counters, counters);
        glClearNamedBufferData(gl.buffer(r, p.heads), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &kEnd);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, gl.buffer(r, p.counters));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, gl.buffer(r, p.entries));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, gl.buffer(r, p.heads));
    const glm::ivec4 rect = pick_rect_gl(ctx);
    glUniform4i(prog.uniform("pick_rect"), rect.x, rect.y, rect.z, rect.w);
}

void pick(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, const PickBuffers& lists) {
    struct Data {
        PickBuffers lists;
        graph::TextureHandle depth, id, primitive;
        bool first = false; // no list pass ran: the lists start here
    };
    const Data& sorted = fg.add_pass<Data>(
        "pick_resolve",
        [&](graph::FrameGraph::Builder& b, Data& d) {
            d.first = !lists.valid();
            d.lists = write_pick(b, ctx, lists);
            d.depth = b.read(gb.depth);
            d.id = b.read(gb.id);
            d.primitive = b.read(gb.primitive);
        },
        [&ctx](const Data& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            auto& prog = gl.program({"render/pick_resolve.comp"});
            prog.use();
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            bind_pick(gl, r, ctx, d.lists, prog, d.first);
            glBindTextureUnit(0, gl.texture(r, d.depth));
            glBindTextureUnit(1, gl.texture(r, d.id));
            glBindTextureUnit(2, gl.texture(r, d.primitive));
            glDispatchCompute(GLuint((region_pixels(ctx) + 63) / 64), 1, 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        });
    side_effect_pass(
        fg, "read_pick", {{}, {sorted.lists.counters, sorted.lists.entries, sorted.lists.heads}},
        [&ctx](const Reads& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            GLuint counters[2];
            glGetNamedBufferSubData(gl.buffer(r, d.buffers[0]), 0, sizeof counters, counters);
            const std::size_t px = region_pixels(ctx), stored = std::min<std::size_t>(counters[0], counters[1]);
            std::vector<std::uint32_t> heads(px), entries(stored * kEntryWords);
            glGetNamedBufferSubData(gl.buffer(r, d.buffers[2]), 0, GLsizeiptr(px * 4), heads.data());
            if (stored)
                glGetNamedBufferSubData(gl.buffer(r, d.buffers[1]), 0, GLsizeiptr(entries.size() * 4), entries.data());
            PickList& out = ctx.result->pick;
            out.region = *ctx.pick;
            out.offered = counters[0];
            out.capacity = counters[1];
            out.pixels.assign(px, {});
            const int w = ctx.pick->width, h = ctx.pick->height;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    // GL rows go up from the region's bottom; the result's go down from its top.
                    auto& list = out.pixels[std::size_t(h - 1 - y) * std::size_t(w) + std::size_t(x)];
                    for (std::uint32_t i = heads[std::size_t(y) * std::size_t(w) + std::size_t(x)];
                         i < stored && list.size() < stored; i = entries[i * kEntryWords + 4]) {
                        const std::uint32_t* e = &entries[i * kEntryWords];
                        PickFragment f;
                        std::memcpy(&f.depth, &e[0], 4);
                        f.object = e[1];
                        f.primitive = e[2];
                        std::memcpy(&f.alpha, &e[3], 4);
                        std::memcpy(&f.transmittance, &e[5], 4);
                        list.push_back(f);
                    }
                }
        });
}

} // namespace iso::passes
