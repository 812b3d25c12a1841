// VOIT (docs/voit.md; the seeds' Virtual OIT): translucent surfaces are
// rasterized once into per-pixel linked lists of fragments (depth, object,
// primitive, packed normal: what shading needs, not a colour), then a
// compute pass sorts each list and composites it front to back over the
// opaque image with an early exit. Two passes:
//   oit_fragments  reads the opaque depth; writes heads, counters, nodes
//   oit_resolve    reads heads, nodes, objects; writes the colour's next version
#include <cstring>

#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

namespace {

OitParams oit_params(const FrameContext& ctx) {
    OitParams p;
    p.view_rotation = std140::mat3(ctx.world_to_view);
    p.image_size = {ctx.width, ctx.height};
    p.capacity = std::uint32_t(ctx.oit_capacity);
    p.epsilon = ctx.opt.oit_epsilon;
    p.flat_shading = ctx.opt.flat_shading ? 1u : 0u;
    return p;
}

struct Lists {
    graph::TextureHandle depth, heads;
    graph::BufferHandle counters, nodes, objects, params, gbuffer_params;
};

Lists fragment_lists(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb) {
    const int W = ctx.width, H = ctx.height;
    const std::size_t object_bytes = ctx.objects.size() * sizeof(glm::vec4);
    const std::size_t node_bytes = std::max<std::size_t>(ctx.oit_capacity, 1) * kOitNodeBytes;
    return fg.add_pass<Lists>(
        "oit_fragments",
        [&](graph::FrameGraph::Builder& b, Lists& d) {
            d.depth = b.read(gb.depth);
            d.heads = b.write(b.create("oit_heads", {W, H, graph::Format::R32UI}));
            d.counters = b.write(b.create("oit_counters", graph::BufferDesc{8}));
            d.nodes = b.write(fg.history("oit_nodes", graph::BufferDesc{node_bytes}));
            d.objects = b.write(b.create("oit_objects", graph::BufferDesc{object_bytes}));
            d.params = params_buffer<OitParams>(b, "oit_params");
            d.gbuffer_params = params_buffer<GBufferParams>(b, "oit_gbuffer_params");
        },
        [&ctx, W, H](const Lists& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const GLuint heads = gl.texture(r, d.heads);
            const GLuint end = 0xFFFFFFFFu;
            glClearTexImage(heads, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &end);
            const GLuint zero = 0;
            glClearNamedBufferData(gl.buffer(r, d.counters), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
            glNamedBufferSubData(gl.buffer(r, d.objects), 0, GLsizeiptr(ctx.objects.size() * sizeof(glm::vec4)), ctx.objects.data());
            // Depth test against the opaque surfaces, no depth writes: a
            // fragment behind them never reaches the shader (early tests).
            glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({}, gl.texture(r, d.depth)));
            glViewport(0, 0, W, H);
            glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_GREATER);
            glDepthMask(GL_FALSE);
            glDisable(GL_CULL_FACE);
            auto& prog = gl.program({"render/gbuffer.vert", "render/oit_fragments.frag"});
            prog.use();
            bind_params(gl, r, d.gbuffer_params, GBufferParams{ctx.view_projection});
            bind_params(gl, r, d.params, oit_params(ctx));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.counters));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.nodes));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gl.buffer(r, d.objects));
            glBindImageTexture(0, heads, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
            const GLint id_loc = prog.uniform("object_id");
            for (const auto& m : ctx.translucent) {
                glUniform1ui(id_loc, m.id);
                glBindVertexArray(m.vao);
                glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
            }
            glBindVertexArray(0);
            glDepthMask(GL_TRUE);
            glDisable(GL_DEPTH_TEST);
            glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        });
}

} // namespace

// Tests: every pixel's list length, counted on the CPU from the read-back
// head image and node pool.
void read_lists(graph::FrameGraph& fg, const FrameContext& ctx, const Lists& lists) {
    side_effect_pass(fg, "read_oit_lists", {{lists.heads}, {lists.nodes}}, [&ctx](const Reads& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const int W = ctx.width, H = ctx.height;
            std::vector<std::uint32_t> heads(std::size_t(W) * std::size_t(H));
            glGetTextureImage(gl.texture(r, d.textures[0]), 0, GL_RED_INTEGER, GL_UNSIGNED_INT, GLsizei(heads.size() * 4), heads.data());
            std::vector<std::uint32_t> nodes(r.desc(d.buffers[0]).bytes / 4);
            glGetNamedBufferSubData(gl.buffer(r, d.buffers[0]), 0, GLsizeiptr(nodes.size() * 4), nodes.data());
            auto& out = ctx.result->oit_lists;
            out.assign(heads.size(), 0);
            const std::size_t capacity = nodes.size() / kOitNodeWords;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    std::uint32_t n = 0;
                    for (std::uint32_t i = heads[std::size_t(y) * W + x]; i != 0xFFFFFFFFu && i < capacity && n <= capacity; i = nodes[i * kOitNodeWords + kOitNodeNextWord])
                        ++n;
                    out[std::size_t(H - 1 - y) * W + x] = n; // GL rows are bottom-up
                }
        });
}

namespace {

// The frame's counts, for the statistics; the renderer grows the pool from them.
void report(const FrameContext& ctx, GLuint counters_buffer, GLuint stats_buffer) {
    GLuint counters[2], stats[3];
    glGetNamedBufferSubData(counters_buffer, 0, 8, counters);
    glGetNamedBufferSubData(stats_buffer, 0, 12, stats);
    OitStats& s = ctx.result->oit;
    s.fragments = counters[0];
    s.dropped = counters[1];
    s.capacity = ctx.oit_capacity;
    s.max_list = stats[0];
    s.shaded = stats[1];
    s.lists = stats[2];
}

void bind_lists(GlResources& gl, const graph::Resources& r, graph::BufferHandle counters, graph::BufferHandle nodes,
                graph::BufferHandle objects) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, counters));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, nodes));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gl.buffer(r, objects));
}

// The resolve in one pass: sort, shade (no AO), composite.
graph::TextureHandle resolve(graph::FrameGraph& fg, const FrameContext& ctx, const Lists& lists, graph::TextureHandle color) {
    struct Data {
        graph::TextureHandle heads, color;
        graph::BufferHandle counters, nodes, objects, params, stats;
    };
    return fg.add_pass<Data>(
                 "oit_resolve",
                 [&](graph::FrameGraph::Builder& b, Data& d) {
                     d.heads = b.read(lists.heads);
                     d.counters = b.read(lists.counters);
                     d.nodes = b.read(lists.nodes);
                     d.objects = b.read(lists.objects);
                     d.color = b.write(b.read(color));
                     d.params = params_buffer<OitParams>(b, "oit_resolve_params");
                     d.stats = b.write(b.create("oit_stats", graph::BufferDesc{12}));
                 },
                 [&ctx](const Data& d, const graph::Resources& r) {
                     GlResources& gl = *ctx.gl;
                     const GLuint zero = 0;
                     glClearNamedBufferData(gl.buffer(r, d.stats), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
                     gl.program({"render/oit_resolve.comp"}).use();
                     bind_params(gl, r, d.params, oit_params(ctx));
                     bind_lists(gl, r, d.counters, d.nodes, d.objects);
                     glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, gl.buffer(r, d.stats));
                     glBindImageTexture(0, gl.texture(r, d.heads), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
                     glBindImageTexture(1, gl.texture(r, d.color), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA8);
                     glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                     glMemoryBarrier(GL_ALL_BARRIER_BITS);
                     report(ctx, gl.buffer(r, d.counters), gl.buffer(r, d.stats));
                 })
        .color;
}

// With translucent AO: sort (and list what will be shaded), trace, composite.
graph::TextureHandle resolve_with_ao(graph::FrameGraph& fg, const FrameContext& ctx, const Lists& lists, graph::TextureHandle color,
                                     const AmbientOcclusion& ao) {
    struct Sorted {
        graph::TextureHandle heads;
        graph::BufferHandle counters, nodes, objects, params, stats, trace;
    };
    const std::size_t capacity = std::max<std::size_t>(ctx.oit_capacity, 1);
    const Sorted& sorted = fg.add_pass<Sorted>(
        "oit_sort",
        [&](graph::FrameGraph::Builder& b, Sorted& d) {
            d.heads = b.write(b.read(lists.heads));
            d.counters = b.read(lists.counters);
            d.nodes = b.write(b.read(lists.nodes));
            d.objects = b.read(lists.objects);
            d.params = params_buffer<OitParams>(b, "oit_sort_params");
            d.stats = b.write(b.create("oit_stats", graph::BufferDesc{12}));
            d.trace = b.write(b.create("oit_trace", graph::BufferDesc{16 + capacity * 8}));
        },
        [&ctx](const Sorted& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const GLuint zero = 0, start[4] = {0, 1, 1, 0}; // no groups yet, (x, 1, 1); no entries
            glClearNamedBufferData(gl.buffer(r, d.stats), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
            glNamedBufferSubData(gl.buffer(r, d.trace), 0, sizeof start, start);
            gl.program({"render/oit_resolve.comp"}, "#define OIT_SORT 1\n").use();
            bind_params(gl, r, d.params, oit_params(ctx));
            bind_lists(gl, r, d.counters, d.nodes, d.objects);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, gl.buffer(r, d.stats));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, gl.buffer(r, d.trace));
            glBindImageTexture(0, gl.texture(r, d.heads), 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
            glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
            glMemoryBarrier(GL_ALL_BARRIER_BITS);
            report(ctx, gl.buffer(r, d.counters), gl.buffer(r, d.stats));
        });

    struct Traced {
        graph::TextureHandle slicemap;
        graph::BufferHandle nodes, trace, zrange, pattern, cone_params, params, ao;
    };
    const Traced& traced = fg.add_pass<Traced>(
        "oit_ao",
        [&](graph::FrameGraph::Builder& b, Traced& d) {
            d.nodes = b.read(sorted.nodes);
            d.trace = b.read(sorted.trace);
            d.slicemap = b.read(ao.tracer.slicemap);
            d.zrange = b.read(ao.tracer.zrange);
            d.pattern = b.read(ao.cones.pattern);
            d.cone_params = b.read(ao.cones.params);
            d.params = params_buffer<OitParams>(b, "oit_ao_params");
            d.ao = b.write(b.create("oit_ao", graph::BufferDesc{capacity * 4}));
        },
        [&ctx, layers = ao.layers](const Traced& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            gl.program({"render/oit_ao.comp"}, "#define LAYERS " + std::to_string(layers) + "\n").use();
            bind_params(gl, r, d.params, oit_params(ctx));
            // The cone tracer's inputs, as the cone AO pass left them.
            glBindBufferBase(GL_UNIFORM_BUFFER, ConeParams::binding, gl.buffer(r, d.cone_params));
            glBindTextureUnit(0, gl.texture(r, d.slicemap));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.nodes));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, gl.buffer(r, d.zrange));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, gl.buffer(r, d.pattern));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, gl.buffer(r, d.trace));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, gl.buffer(r, d.ao));
            glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, gl.buffer(r, d.trace));
            glDispatchComputeIndirect(0);
            glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        });

    struct Composite {
        graph::TextureHandle heads, color;
        graph::BufferHandle counters, nodes, objects, ao, params;
    };
    return fg.add_pass<Composite>(
                 "oit_resolve",
                 [&](graph::FrameGraph::Builder& b, Composite& d) {
                     d.heads = b.read(sorted.heads);
                     d.counters = b.read(sorted.counters);
                     d.nodes = b.read(sorted.nodes);
                     d.objects = b.read(sorted.objects);
                     d.ao = b.read(traced.ao);
                     d.color = b.write(b.read(color));
                     d.params = params_buffer<OitParams>(b, "oit_resolve_params");
                 },
                 [&ctx](const Composite& d, const graph::Resources& r) {
                     GlResources& gl = *ctx.gl;
                     gl.program({"render/oit_resolve.comp"}, "#define OIT_SORTED 1\n").use();
                     bind_params(gl, r, d.params, oit_params(ctx));
                     bind_lists(gl, r, d.counters, d.nodes, d.objects);
                     glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, gl.buffer(r, d.ao));
                     glBindImageTexture(0, gl.texture(r, d.heads), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
                     glBindImageTexture(1, gl.texture(r, d.color), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA8);
                     glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                     glMemoryBarrier(GL_ALL_BARRIER_BITS);
                 })
        .color;
}

} // namespace

graph::TextureHandle voit(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, graph::TextureHandle color,
                          const AmbientOcclusion* ao) {
    const Lists lists = fragment_lists(fg, ctx, gb);
    if (ctx.hooks.read_oit_lists) read_lists(fg, ctx, lists);
    return ao ? resolve_with_ao(fg, ctx, lists, color, *ao) : resolve(fg, ctx, lists, color);
}

} // namespace iso::passes
