// Disk-based AO (docs/ao.md, "Disk AO on the GPU"): disk_build ->
// disk_elements -> disk_gather. The hierarchy (renderer/ao/disk_hierarchy)
// is built on the CPU once per surface and cached by the renderer; the
// concatenation of the visible surfaces is uploaded when that set changes;
// the element terms are recomputed when the hierarchy, the settings or R
// change (they do not depend on the camera); only the gather runs for a new
// view.
#include <algorithm>
#include <chrono>
#include <memory>

#include <glm/glm.hpp>

#include "io/error.hpp"
#include "renderer/ao/disk_hierarchy.hpp"
#include "renderer/passes/disk_state.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"
#include "renderer/frame/ao_settings.hpp"

namespace iso::passes {

namespace {

// The graph's view of DiskState: tokens that order the passes (their
// contents are not used).
constexpr graph::BufferDesc kTokenDesc{16};

std::vector<std::uint64_t> surfaces_key(const FrameContext& ctx) {
    std::vector<std::uint64_t> key;
    for (const auto& s : ctx.disk_surfaces) key.insert(key.end(), {std::uint64_t(s.id), s.version});
    return key;
}

gl::Buffer upload(const void* data, std::size_t bytes) {
    // An empty buffer still gets 16 bytes so that it can be bound.
    return gl::Buffer(std::max<std::size_t>(bytes, 16), bytes ? data : nullptr, GL_DYNAMIC_STORAGE_BIT);
}

// The CPU side of the hierarchy: build what is not cached, concatenate, upload.
void build_and_upload(const FrameContext& ctx) {
    DiskState& S = *ctx.disk;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<const DiskHierarchy*> parts;
    for (const auto& s : ctx.disk_surfaces) {
        if (!*s.cache) *s.cache = std::make_shared<const DiskHierarchy>(build_disk_hierarchy(s.mesh()));
        parts.push_back(s.cache->get());
    }
    DiskHierarchy joined;
    if (parts.size() > 1) joined = concatenate(parts);
    const DiskHierarchy& h = parts.size() == 1 ? *parts[0] : joined; // none: empty
    ctx.result->disk_build_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    // Parents by level, deepest first (the parent passes run bottom-up), and
    // the leaves below each node (the parents' fallback weights when their
    // leaves have no area; fill_parent_terms).
    std::vector<int> levels;
    S.level_first.assign(1, 0);
    for (int l = h.levels - 1; l >= 0; --l) {
        for (std::size_t i = 0; i < h.nodes.size(); ++i)
            if (h.node_level[i] == l && h.nodes[i].links.y >= 0) levels.push_back(int(i));
        S.level_first.push_back(int(levels.size()));
    }
    std::vector<float> leaf_count(h.nodes.size(), 0.0f);
    for (std::size_t i = h.nodes.size(); i-- > 0;) {
        const DiskNode& node = h.nodes[i];
        if (node.links.y < 0) {
            leaf_count[i] = 1.0f;
            continue;
        }
        for (int c = node.links.y; c < node.links.x; c = h.nodes[std::size_t(c)].links.x)
            leaf_count[i] += leaf_count[std::size_t(c)];
    }
    S.nodes = h.nodes.size();
    S.triangles = h.triangles.size() / 3;
    S.node_buf = upload(h.nodes.data(), h.nodes.size() * sizeof(DiskNode));
    S.triangle_buf = upload(h.triangles.data(), h.triangles.size() * sizeof(glm::vec4));
    S.level_buf = upload(levels.data(), levels.size() * sizeof(int));
    S.leaf_count_buf = upload(leaf_count.data(), leaf_count.size() * sizeof(float));
    for (int k = 0; k < 2; ++k) {
        S.terms[k] = upload(nullptr, S.nodes * sizeof(float));
        S.occlusion[k] = upload(nullptr, S.nodes * sizeof(float));
    }
    S.terms_valid = false;
    S.key = surfaces_key(ctx);
    ctx.result->disk_built = true;
}

DiskParams base_params(const FrameContext& ctx) {
    const DiskState& S = *ctx.disk;
    const DiskAoSettings& st = ctx.opt.look.disk;
    DiskParams p;
    p.near_plane = float(ctx.camera.near_plane);
    p.far_plane = float(ctx.camera.far_plane);
    p.size = {ctx.width, ctx.height};
    const glm::dmat4 proj = ctx.camera.projection(double(ctx.width) / double(ctx.height));
    p.proj_scale = {float(proj[0][0]), float(proj[1][1])};
    p.view_to_world = glm::mat4(glm::inverse(ctx.camera.view()));
    p.radius = float(ctx.opt.look.cone.radius_mm);
    p.clip_epsilon = float(st.clip_epsilon);
    p.traversal_epsilon = float(st.traversal_epsilon);
    p.distance_attenuation = float(st.distance_attenuation);
    p.triangle_attenuation = float(st.triangle_attenuation);
    p.min_scale = float(st.min_scale);
    p.max_scale = float(st.max_scale);
    p.receiver_offset = float(st.receiver_offset);
    p.node_count = int(S.nodes);
    return p;
}

void bind_hierarchy(const DiskState& S) {
    S.node_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 0);
    S.triangle_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 1);
}

GLuint groups(std::size_t n) { return GLuint((n + 63) / 64); }

// Every level's parents from their children, deepest first.
void update_parents(GlResources& gl, const graph::Resources& r, graph::BufferHandle params, DiskParams p,
                    const DiskState& S, const gl::Buffer& terms) {
    auto& prog = gl.program({"ao/disk_parent.comp"});
    prog.use();
    S.node_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 0);
    terms.bind_base(GL_SHADER_STORAGE_BUFFER, 4);
    S.level_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 5);
    S.leaf_count_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 6);
    for (std::size_t l = 0; l + 1 < S.level_first.size(); ++l) {
        p.first = S.level_first[l];
        p.count = S.level_first[l + 1] - S.level_first[l];
        if (p.count == 0) continue;
        bind_params(gl, r, params, p);
        glDispatchCompute(groups(std::size_t(p.count)), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
    }
}

// The execute step of disk_elements. As disk_element_passes: pass k reads
// the terms of pass k - 1 (none for the first) and writes its own terms
// and leaf occlusion; parents follow each pass.
void run_element_passes(const FrameContext& ctx, const graph::Resources& r, graph::BufferHandle params) {
    GlResources& gl = *ctx.gl;
    DiskState& S = *ctx.disk;
    const DiskAoSettings& st = ctx.opt.look.disk;
    DiskParams p = base_params(ctx);
    const int passes = st.passes; // >= 1: the pass is declared only then
    for (int pass = 0; pass < passes; ++pass) {
        const int out = pass % 2, in = 1 - out;
        auto& prog = gl.program({"ao/disk_element.comp"});
        prog.use();
        bind_hierarchy(S);
        S.terms[in].bind_base(GL_SHADER_STORAGE_BUFFER, 3);
        S.terms[out].bind_base(GL_SHADER_STORAGE_BUFFER, 4);
        S.occlusion[out].bind_base(GL_SHADER_STORAGE_BUFFER, 7);
        p.use_terms = pass > 0 ? 1 : 0;
        bind_params(gl, r, params, p);
        glDispatchCompute(groups(S.nodes), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        update_parents(gl, r, params, p, S, S.terms[out]);
        S.final_terms = out;
    }
    // The weighted minimum of the last two passes' occlusion.
    if (passes >= 2) {
        const int last = (passes - 1) % 2;
        auto& prog = gl.program({"ao/disk_blend.comp"});
        prog.use();
        S.node_buf.bind_base(GL_SHADER_STORAGE_BUFFER, 0);
        S.terms[last].bind_base(GL_SHADER_STORAGE_BUFFER, 4);
        S.occlusion[last].bind_base(GL_SHADER_STORAGE_BUFFER, 7);
        S.occlusion[1 - last].bind_base(GL_SHADER_STORAGE_BUFFER, 8);
        bind_params(gl, r, params, p);
        glDispatchCompute(groups(S.nodes), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        update_parents(gl, r, params, p, S, S.terms[last]);
    }
    S.terms_valid = true;
    S.settings = st;
    S.radius = ctx.opt.look.cone.radius_mm;
    ctx.result->disk_elements = true;
}

struct GatherData {
    graph::TextureHandle depth, normal, ao;
    graph::BufferHandle hierarchy, terms, params;
};

// The execute step of disk_gather: every pixel's receiver against the
// hierarchy, in bands of rows when progress is reported.
void run_gather(const FrameContext& ctx, const GatherData& d, const graph::Resources& r) {
    GlResources& gl = *ctx.gl;
    DiskState& S = *ctx.disk;
    const bool read = ctx.hooks.read_disk;
    auto& prog = gl.program({"ao/disk_gather.comp"}, read ? "#define READ_RECEIVERS 1\n" : "");
    prog.use();
    bind_hierarchy(S);
    S.terms[S.final_terms].bind_base(GL_SHADER_STORAGE_BUFFER, 3);
    glBindTextureUnit(0, gl.texture(r, d.depth));
    glBindTextureUnit(1, gl.texture(r, d.normal));
    glBindImageTexture(0, gl.texture(r, d.ao), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    DiskParams p = base_params(ctx);
    const bool modulated = ctx.opt.look.disk.passes > 0;
    p.use_terms = modulated ? 1 : 0;
    gl::Buffer receivers;
    const std::size_t pixels = std::size_t(ctx.width) * std::size_t(ctx.height);
    if (read) {
        receivers = gl::Buffer(pixels * 2 * sizeof(glm::vec4), nullptr, 0);
        receivers.bind_base(GL_SHADER_STORAGE_BUFFER, 6);
    }
    // With a progress callback, bands of 64 rows, each finished
    // before it is reported (about 8 on a 512-row image; the
    // glFinish costs nothing next to a band's traversals).
    const int band = ctx.opt.progress ? 64 : ctx.height;
    for (int y0 = 0; y0 < ctx.height; y0 += band) {
        const int rows = std::min(band, ctx.height - y0);
        p.row_offset = y0;
        bind_params(gl, r, d.params, p);
        glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((rows + 7) / 8), 1);
        if (!ctx.opt.progress) continue;
        glFinish();
        if (!ctx.opt.progress(double(y0 + rows) / double(ctx.height), "disk AO")) {
            ctx.result->cancelled = true;
            break;
        }
    }
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_SHADER_STORAGE_BARRIER_BIT);
    ctx.result->disk_nodes = S.nodes;
    ctx.result->disk_triangles = S.triangles;
    if (read) {
        ctx.result->disk_receivers = receivers.read_all<glm::vec4>();
        ctx.result->disk_terms.assign(S.nodes, 1.0f);
        if (S.nodes && modulated)
            glGetNamedBufferSubData(S.terms[S.final_terms].id(), 0, GLsizeiptr(S.nodes * sizeof(float)),
                                    ctx.result->disk_terms.data());
    }
}

// disk_build: writes the hierarchy token (build_and_upload).
graph::BufferHandle add_build_pass(graph::FrameGraph& fg, const FrameContext& ctx, graph::BufferHandle hierarchy) {
    struct Data {
        graph::BufferHandle token;
    };
    return fg
        .add_pass<Data>(
            "disk_build", [&](graph::FrameGraph::Builder& b, Data& d) { d.token = b.write(hierarchy); },
            [&ctx](const Data&, const graph::Resources&) { build_and_upload(ctx); })
        .token;
}

// disk_elements: reads the hierarchy token, writes the terms token.
graph::BufferHandle add_elements_pass(graph::FrameGraph& fg, const FrameContext& ctx, graph::BufferHandle hierarchy,
                                      graph::BufferHandle terms) {
    struct Data {
        graph::BufferHandle hierarchy, token, params;
    };
    return fg
        .add_pass<Data>(
            "disk_elements",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.hierarchy = b.read(hierarchy);
                d.token = b.write(terms);
                d.params = params_buffer<DiskParams>(b, "disk_element_params");
            },
            [&ctx](const Data& d, const graph::Resources& r) { run_element_passes(ctx, r, d.params); })
        .token;
}

// disk_gather: reads depth, normal and both tokens, writes the AO image.
graph::TextureHandle add_gather_pass(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                                     graph::BufferHandle hierarchy, graph::BufferHandle terms) {
    return fg
        .add_pass<GatherData>(
            "disk_gather",
            [&](graph::FrameGraph::Builder& b, GatherData& d) {
                d.depth = b.read(gb.depth);
                d.normal = b.read(gb.normal);
                d.hierarchy = b.read(hierarchy);
                d.terms = b.read(terms);
                d.ao = b.write(b.create("disk_ao", graph::TextureDesc{ctx.width, ctx.height, graph::Format::R32F}));
                d.params = params_buffer<DiskParams>(b, "disk_gather_params");
            },
            [&ctx](const GatherData& d, const graph::Resources& r) { run_gather(ctx, d, r); })
        .ao;
}

} // namespace

graph::TextureHandle disk_ambient_occlusion(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb) {
    const DiskState* S = ctx.disk;
    const auto key = surfaces_key(ctx);
    const bool rebuild = !S || S->key != key;
    // No element passes (passes = 0, the default): every term is 1 and the
    // gather sums unmodulated form factors.
    const bool modulated = ctx.opt.look.disk.passes > 0;
    const bool elements = modulated && (rebuild || !S->terms_valid || !same_settings(S->settings, ctx.opt.look.disk) ||
                                        S->radius != ctx.opt.look.cone.radius_mm);

    graph::BufferHandle hierarchy = fg.history("disk_hierarchy", kTokenDesc);
    if (rebuild) hierarchy = add_build_pass(fg, ctx, hierarchy);
    graph::BufferHandle terms = fg.history("disk_terms", kTokenDesc);
    if (elements) terms = add_elements_pass(fg, ctx, hierarchy, terms);
    return add_gather_pass(fg, ctx, gb, hierarchy, terms);
}

} // namespace iso::passes
