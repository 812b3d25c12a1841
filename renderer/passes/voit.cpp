// VOIT (docs/voit.md; the seeds' Virtual OIT): translucent surfaces are
// rasterized once into per-pixel linked lists of fragments (depth, object,
// primitive, packed normal: what shading needs, not a colour), then a
// compute pass sorts each list and composites it front to back over the
// opaque image with an early exit. Two passes:
//   oit_fragments  reads the opaque depth; writes heads, counters, nodes
//   oit_resolve    reads heads, nodes, objects; writes the colour's next version
#include <algorithm>
#include <cstring>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lod_draw.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

namespace {

OitParams oit_params(const FrameContext& ctx) {
    OitParams p;
    p.view_rotation = std140::mat3(ctx.world_to_view);
    p.image_size = {ctx.width, ctx.height};
    p.capacity = std::uint32_t(ctx.oit_capacity);
    p.epsilon = ctx.opt.look.oit_epsilon;
    p.flat_shading = ctx.opt.look.flat_shading ? 1u : 0u;
    p.near_far = {float(ctx.camera.near_plane), float(ctx.camera.far_plane)};
    p.cut_range = ctx.translucent_depth.y > ctx.translucent_depth.x ? ctx.translucent_depth : p.near_far;
    return p;
}

// Rasterizes the translucent surfaces with `prog` (bound, with its
// parameters): depth test against the opaque surfaces, no depth writes, so
// a fragment behind them never reaches the shader (early tests).
void draw_translucent(GlResources& gl, const FrameContext& ctx, GLuint depth, iso::gl::Program& prog) {
    glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer({}, depth));
    glViewport(0, 0, ctx.width, ctx.height);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    const GLint id_loc = prog.uniform("object_id");
    draw_surfaces(ctx, gl, ctx.translucent, DrawSet::InView, [&](const DrawItem& m) {
        prog.use();
        glUniform1ui(id_loc, m.id);
        bind_triangle_order(m, prog.id());
    });
    glBindVertexArray(0);
    glDepthMask(GL_TRUE);
    glDisable(GL_DEPTH_TEST);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

constexpr int kBins = 16; // OIT_BINS in oit_common.glsl

// Per pixel, the first depth bin whose fragments are merged so that what
// is nearer fits the pool: every pixel keeps its nearest fragments up to a
// common level L (the largest whose stored total fits `capacity`), in
// whole bins. `histogram`: kBins counts per pixel.
std::vector<std::uint32_t> depth_cuts(const std::vector<std::uint32_t>& histogram, std::size_t capacity) {
    const std::size_t pixels = histogram.size() / kBins;
    std::vector<std::uint64_t> cum(pixels * (kBins + 1));
    std::uint64_t most = 0;
    for (std::size_t p = 0; p < pixels; ++p) {
        std::uint64_t* c = &cum[p * (kBins + 1)];
        c[0] = 0;
        for (int b = 0; b < kBins; ++b) c[b + 1] = c[b] + histogram[p * kBins + std::size_t(b)];
        most = std::max(most, c[kBins]);
    }
    // The pixel's cut at level L: the last bin boundary with at most L nearer fragments.
    auto cut_at = [&](std::size_t p, std::uint64_t L) {
        const std::uint64_t* c = &cum[p * (kBins + 1)];
        return int(std::upper_bound(c, c + kBins + 1, L) - c) - 1;
    };
    auto stored = [&](std::uint64_t L) {
        std::uint64_t n = 0;
        for (std::size_t p = 0; p < pixels; ++p) n += cum[p * (kBins + 1) + std::size_t(cut_at(p, L))];
        return n;
    };
    std::uint64_t lo = 0, hi = most; // stored(lo) <= capacity (nothing but empty bins at L = 0)
    while (lo < hi) {
        const std::uint64_t mid = lo + (hi - lo + 1) / 2;
        if (stored(mid) <= capacity)
            lo = mid;
        else
            hi = mid - 1;
    }
    std::vector<std::uint32_t> cuts(pixels);
    for (std::size_t p = 0; p < pixels; ++p) cuts[p] = std::uint32_t(cut_at(p, lo));
    return cuts;
}

// At the cap: the depth histogram of every pixel's fragments (a geometry
// pass that stores nothing), then each pixel's cut (CPU, read back).
graph::TextureHandle depth_cut(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb) {
    struct Data {
        graph::TextureHandle depth, cut;
        graph::BufferHandle histogram, params, gbuffer_params;
    };
    const int W = ctx.width, H = ctx.height;
    return fg
        .add_pass<Data>(
            "oit_depth_cut",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.depth = b.read(gb.depth);
                d.histogram =
                    b.write(b.create("oit_histogram", graph::BufferDesc{std::size_t(W) * std::size_t(H) * kBins * 4}));
                d.cut = b.write(b.create("oit_cut", {W, H, graph::Format::R32UI}));
                d.params = params_buffer<OitParams>(b, "oit_cut_params");
                d.gbuffer_params = params_buffer<GBufferParams>(b, "oit_cut_gbuffer_params");
            },
            [&ctx, W, H](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                const GLuint zero = 0, histogram = gl.buffer(r, d.histogram);
                glClearNamedBufferData(histogram, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
                auto& prog = gl.program({"render/gbuffer.vert", "render/oit_fragments.frag"},
                                        "#define OIT_HISTOGRAM 1\n" + clip_define(ctx));
                prog.use();
                set_clip(ctx, prog);
                bind_params(gl, r, d.gbuffer_params, GBufferParams{ctx.raster_view_projection});
                bind_params(gl, r, d.params, oit_params(ctx));
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, histogram);
                draw_translucent(gl, ctx, gl.texture(r, d.depth), prog);
                std::vector<std::uint32_t> counts(std::size_t(W) * std::size_t(H) * kBins);
                glGetNamedBufferSubData(histogram, 0, GLsizeiptr(counts.size() * 4), counts.data());
                const auto cuts = depth_cuts(counts, ctx.oit_capacity);
                glTextureSubImage2D(gl.texture(r, d.cut), 0, 0, 0, W, H, GL_RED_INTEGER, GL_UNSIGNED_INT, cuts.data());
                glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
            })
        .cut;
}

struct Lists {
    graph::TextureHandle depth, heads, cut;
    graph::BufferHandle counters, nodes, objects, params, gbuffer_params;
    graph::BufferHandle tails; // per pixel, at the pool's cap (FrameContext::oit_merge)
    PickBuffers pick;          // with a pick: its lists' next versions
};

std::string merge_define(const FrameContext& ctx) { return ctx.oit_merge ? "#define OIT_MERGE 1\n" : ""; }
// The resolve marches the volume between the fragments (volume_march.glsl).
std::string volume_define(const FrameContext& ctx) {
    return ctx.volume ? "#define VOLUME 1\n" + volume_variant(ctx) : "";
}
constexpr std::size_t kCountersBytes = 3 * 4; // OitCounters in oit_common.glsl
constexpr std::size_t kTailBytes = 12 * 4;    // OitTail in oit_common.glsl

Lists fragment_lists(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, graph::TextureHandle cut,
                     const PickBuffers& pick) {
    const int W = ctx.width, H = ctx.height;
    const std::size_t object_bytes = ctx.objects.size() * sizeof(glm::vec4);
    const std::size_t node_bytes = std::max<std::size_t>(ctx.oit_capacity, 1) * kOitNodeBytes;
    return fg.add_pass<Lists>(
        "oit_fragments",
        [&](graph::FrameGraph::Builder& b, Lists& d) {
            d.depth = b.read(gb.depth);
            d.heads = b.write(b.create("oit_heads", {W, H, graph::Format::R32UI}));
            d.counters = b.write(b.create("oit_counters", graph::BufferDesc{kCountersBytes}));
            if (cut.valid()) d.cut = b.read(cut);
            d.pick = write_pick(b, ctx, pick);
            d.nodes = b.write(fg.history("oit_nodes", graph::BufferDesc{node_bytes}));
            d.objects = b.write(b.create("oit_objects", graph::BufferDesc{object_bytes}));
            d.params = params_buffer<OitParams>(b, "oit_params");
            d.gbuffer_params = params_buffer<GBufferParams>(b, "oit_gbuffer_params");
            if (ctx.oit_merge)
                d.tails =
                    b.write(b.create("oit_tails", graph::BufferDesc{std::size_t(W) * std::size_t(H) * kTailBytes}));
        },
        [&ctx](const Lists& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const GLuint heads = gl.texture(r, d.heads);
            const GLuint end = 0xFFFFFFFFu;
            glClearTexImage(heads, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &end);
            const GLuint zero = 0;
            glClearNamedBufferData(gl.buffer(r, d.counters), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
            glNamedBufferSubData(gl.buffer(r, d.objects), 0, GLsizeiptr(ctx.objects.size() * sizeof(glm::vec4)),
                                 ctx.objects.data());
            if (d.tails.valid()) {
                glClearNamedBufferData(gl.buffer(r, d.tails), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT,
                                       &zero); // the empty tail
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, gl.buffer(r, d.tails));
            }
            auto& prog = gl.program({"render/gbuffer.vert", "render/oit_fragments.frag"},
                                    merge_define(ctx) + (d.cut.valid() ? "#define OIT_CUT 1\n" : "") +
                                        pick_defines(d.pick) + clip_define(ctx));
            prog.use();
            set_clip(ctx, prog);
            bind_pick(gl, r, ctx, d.pick, prog, true);
            bind_params(gl, r, d.gbuffer_params, GBufferParams{ctx.raster_view_projection});
            bind_params(gl, r, d.params, oit_params(ctx));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.counters));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.nodes));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gl.buffer(r, d.objects));
            glBindImageTexture(0, heads, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
            if (d.cut.valid()) glBindImageTexture(1, gl.texture(r, d.cut), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
            draw_translucent(gl, ctx, gl.texture(r, d.depth), prog);
        });
}

} // namespace

// Tests: every pixel's list length, counted on the CPU from the read-back
// head image and node pool.
void read_lists(graph::FrameGraph& fg, const FrameContext& ctx, const Lists& lists) {
    side_effect_pass(
        fg, "read_oit_lists", {{lists.heads}, {lists.nodes}}, [&ctx](const Reads& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const int W = ctx.width, H = ctx.height;
            std::vector<std::uint32_t> heads(std::size_t(W) * std::size_t(H));
            glGetTextureImage(gl.texture(r, d.textures[0]), 0, GL_RED_INTEGER, GL_UNSIGNED_INT,
                              GLsizei(heads.size() * 4), heads.data());
            std::vector<std::uint32_t> nodes(r.desc(d.buffers[0]).bytes / 4);
            glGetNamedBufferSubData(gl.buffer(r, d.buffers[0]), 0, GLsizeiptr(nodes.size() * 4), nodes.data());
            auto& out = ctx.result->oit_lists;
            out.assign(heads.size(), 0);
            const std::size_t capacity = nodes.size() / kOitNodeWords;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    std::uint32_t n = 0;
                    for (std::uint32_t i = heads[std::size_t(y) * W + x];
                         i != 0xFFFFFFFFu && i < capacity && n <= capacity;
                         i = nodes[i * kOitNodeWords + kOitNodeNextWord])
                        ++n;
                    out[std::size_t(H - 1 - y) * W + x] = n; // GL rows are bottom-up
                }
        });
}

namespace {

constexpr std::size_t kStatsBytes = 5 * 4; // OitStats in oit_resolve.comp

// The frame's counts, for the statistics; the renderer grows the pool from them.
void report(const FrameContext& ctx, GLuint counters_buffer, GLuint stats_buffer) {
    GLuint counters[3], stats[5];
    glGetNamedBufferSubData(counters_buffer, 0, kCountersBytes, counters);
    glGetNamedBufferSubData(stats_buffer, 0, kStatsBytes, stats);
    OitStats& s = ctx.result->oit;
    s.fragments = counters[0] + counters[2]; // offered to the pool, and merged by the depth cut
    s.merged = counters[1] + counters[2];
    s.overflowed = counters[1];
    s.merged_pixels = stats[3];
    float bound;
    std::memcpy(&bound, &stats[4], 4);
    s.merge_error_max = bound;
    s.capacity = ctx.oit_capacity;
    s.max_list = stats[0];
    s.shaded = stats[1];
    s.lists = stats[2];
}

// What every resolve variant binds: the lists (0..2), the merged tails (3)
// and the statistics (5).
struct ListInputs {
    graph::TextureHandle heads;
    graph::BufferHandle counters, nodes, objects, tails, stats;
};
ListInputs list_inputs(graph::FrameGraph::Builder& b, const Lists& lists, graph::BufferHandle stats, bool write_lists) {
    ListInputs in;
    in.heads = write_lists ? b.write(b.read(lists.heads)) : b.read(lists.heads);
    in.nodes = write_lists ? b.write(b.read(lists.nodes)) : b.read(lists.nodes);
    in.counters = b.read(lists.counters);
    in.objects = b.read(lists.objects);
    if (lists.tails.valid()) in.tails = b.read(lists.tails);
    in.stats = b.write(stats);
    return in;
}
void bind_lists(GlResources& gl, const graph::Resources& r, const ListInputs& in, GLenum heads_access) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, in.counters));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, in.nodes));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gl.buffer(r, in.objects));
    if (in.tails.valid()) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, gl.buffer(r, in.tails));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, gl.buffer(r, in.stats));
    glBindImageTexture(0, gl.texture(r, in.heads), 0, GL_FALSE, 0, heads_access, GL_R32UI);
}
void clear_stats(GlResources& gl, const graph::Resources& r, const ListInputs& in) {
    const GLuint zero = 0;
    glClearNamedBufferData(gl.buffer(r, in.stats), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
}

// The resolve in one pass: sort, shade (no AO), composite.
graph::TextureHandle resolve(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, const Lists& lists,
                             graph::TextureHandle color) {
    struct Data {
        ListInputs in;
        graph::TextureHandle color;
        graph::BufferHandle params;
        VolumeBindings vol;
    };
    return fg
        .add_pass<Data>(
            "oit_resolve",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.in = list_inputs(b, lists, b.create("oit_stats", graph::BufferDesc{kStatsBytes}), false);
                d.color = b.write(b.read(color));
                d.params = params_buffer<OitParams>(b, "oit_resolve_params");
                if (ctx.volume) d.vol = declare_volume(b, ctx, gb);
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                clear_stats(gl, r, d.in);
                gl.program({"render/oit_resolve.comp"}, merge_define(ctx) + volume_define(ctx)).use();
                bind_params(gl, r, d.params, oit_params(ctx));
                bind_lists(gl, r, d.in, GL_READ_ONLY);
                if (ctx.volume) bind_volume(gl, r, ctx, d.vol);
                glBindImageTexture(1, gl.texture(r, d.color), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA8);
                glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                glMemoryBarrier(GL_ALL_BARRIER_BITS);
                report(ctx, gl.buffer(r, d.in.counters), gl.buffer(r, d.in.stats));
                if (ctx.volume) report_volume(gl, r, ctx, d.vol);
            })
        .color;
}

// With translucent AO: sort (and list what will be shaded), trace, composite.
graph::TextureHandle resolve_with_ao(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                                     const Lists& lists, graph::TextureHandle color, const AmbientOcclusion& ao) {
    struct Sorted {
        ListInputs in;
        graph::BufferHandle params, trace;
    };
    const std::size_t capacity = std::max<std::size_t>(ctx.oit_capacity, 1);
    const Sorted& sorted = fg.add_pass<Sorted>(
        "oit_sort",
        [&](graph::FrameGraph::Builder& b, Sorted& d) {
            d.in = list_inputs(b, lists, b.create("oit_stats", graph::BufferDesc{kStatsBytes}), true);
            d.params = params_buffer<OitParams>(b, "oit_sort_params");
            d.trace = b.write(b.create("oit_trace", graph::BufferDesc{16 + capacity * 8}));
        },
        [&ctx](const Sorted& d, const graph::Resources& r) {
            GlResources& gl = *ctx.gl;
            const GLuint start[4] = {0, 1, 1, 0}; // no groups yet, (x, 1, 1); no entries
            clear_stats(gl, r, d.in);
            glNamedBufferSubData(gl.buffer(r, d.trace), 0, sizeof start, start);
            gl.program({"render/oit_resolve.comp"}, "#define OIT_SORT 1\n").use();
            bind_params(gl, r, d.params, oit_params(ctx));
            bind_lists(gl, r, d.in, GL_READ_WRITE);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, gl.buffer(r, d.trace));
            glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
            glMemoryBarrier(GL_ALL_BARRIER_BITS);
        });

    struct Traced {
        graph::TextureHandle slicemap;
        graph::BufferHandle nodes, trace, zrange, pattern, cone_params, params, ao;
    };
    const Traced& traced = fg.add_pass<Traced>(
        "oit_ao",
        [&](graph::FrameGraph::Builder& b, Traced& d) {
            d.nodes = b.read(sorted.in.nodes);
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
        ListInputs in;
        graph::TextureHandle color;
        graph::BufferHandle ao, params;
        VolumeBindings vol;
    };
    return fg
        .add_pass<Composite>(
            "oit_resolve",
            [&](graph::FrameGraph::Builder& b, Composite& d) {
                Lists sorted_lists = lists;
                sorted_lists.heads = sorted.in.heads;
                sorted_lists.nodes = sorted.in.nodes;
                d.in = list_inputs(b, sorted_lists, b.read(sorted.in.stats), false);
                d.ao = b.read(traced.ao);
                d.color = b.write(b.read(color));
                d.params = params_buffer<OitParams>(b, "oit_resolve_params");
                if (ctx.volume) d.vol = declare_volume(b, ctx, gb);
            },
            [&ctx](const Composite& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                gl.program({"render/oit_resolve.comp"},
                           "#define OIT_SORTED 1\n" + merge_define(ctx) + volume_define(ctx))
                    .use();
                bind_params(gl, r, d.params, oit_params(ctx));
                bind_lists(gl, r, d.in, GL_READ_ONLY);
                if (ctx.volume) bind_volume(gl, r, ctx, d.vol);
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, gl.buffer(r, d.ao));
                glBindImageTexture(1, gl.texture(r, d.color), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA8);
                glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                glMemoryBarrier(GL_ALL_BARRIER_BITS);
                report(ctx, gl.buffer(r, d.in.counters), gl.buffer(r, d.in.stats));
                if (ctx.volume) report_volume(gl, r, ctx, d.vol);
            })
        .color;
}

} // namespace

graph::TextureHandle voit(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb, graph::TextureHandle color,
                          const AmbientOcclusion* ao, PickBuffers& pick) {
    const Lists lists =
        fragment_lists(fg, ctx, gb, ctx.oit_cut ? depth_cut(fg, ctx, gb) : graph::TextureHandle{}, pick);
    pick = lists.pick;
    if (ctx.hooks.read_oit_lists) read_lists(fg, ctx, lists);
    return ao ? resolve_with_ao(fg, ctx, gb, lists, color, *ao) : resolve(fg, ctx, gb, lists, color);
}

} // namespace iso::passes
