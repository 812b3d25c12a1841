// Culled, indirect drawing of surfaces with levels of detail (lod_draw.hpp).
#include "renderer/passes/lod_draw.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

namespace {

// Slots of a surface's command buffer: the G-buffer's phases (taken in
// turn), then the other sets; the last (the visibility pass) draws nothing.
constexpr std::uint32_t kPhaseSlots = 8, kSlots = 12, kInViewSlot = 8, kCompleteSlot = 9, kPickSlot = 10;
// Counts buffer: per-slot draw counts, then the statistics (lod_cull.comp's C_*).
enum LodCounter : std::uint32_t {
    kSelected = kStatsWord,
    kFrustum,
    kBackface,
    kOccluded,
    kDrawn,
    kTriangles,
    kOtherLevel,
    kCounters
};
static_assert(kCounters <= kCountWords);
constexpr std::uint32_t kModeAll = 0, kModeFirst = 1, kModeTest = 2, kModeFinal = 3;
constexpr std::size_t kCommandBytes = 20; // DrawElementsIndirectCommand
constexpr double kOcclusionTrianglesPerPixel = 1.0;

struct CullCall {
    std::uint32_t mode = kModeAll, slot = 0;
    bool history = false, backface = false, frustum = true, count_tests = false, count_draws = false;
    float max_error_px = 0;
    glm::vec2 batch{0.0f, std::numeric_limits<float>::infinity()};
};

float pixels_per_mm_at_1mm(const FrameContext& ctx) {
    return float(double(ctx.height) / (2.0 * std::tan(glm::radians(ctx.camera.fov_y_degrees) / 2.0)));
}

// Runs lod_cull.comp over one surface's clusters.
void cull(const FrameContext& ctx, GlResources& gl, const GpuLod& lod, const CullCall& c, const CullState* pyramid) {
    const GLuint zero = 0;
    glClearNamedBufferSubData(lod.counts.id(), GL_R32UI, c.slot * 4, 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    auto& prog = gl.program({"render/lod_cull.comp"});
    prog.use();
    const GLuint p = prog.id();
    const float px_per_mm = pixels_per_mm_at_1mm(ctx);
    glProgramUniformMatrix4fv(p, prog.uniform("view_projection"), 1, GL_FALSE, &ctx.raster_view_projection[0][0]);
    const glm::vec3 eye(ctx.camera.eye);
    glProgramUniform3fv(p, prog.uniform("eye"), 1, &eye.x);
    glProgramUniform1f(p, prog.uniform("px_per_mm_at_1mm"), px_per_mm);
    glProgramUniform1f(p, prog.uniform("max_error_px"), c.max_error_px);
    glProgramUniform1f(p, prog.uniform("near_plane"), float(ctx.camera.near_plane));
    glProgramUniform1ui(p, prog.uniform("cluster_count"), lod.cluster_count);
    glProgramUniform1ui(p, prog.uniform("mode"), c.mode);
    glProgramUniform1ui(p, prog.uniform("slot"), c.slot);
    glProgramUniform1i(p, prog.uniform("history"), c.history);
    glProgramUniform2f(p, prog.uniform("batch"), c.batch.x, c.batch.y);
    glProgramUniform1i(p, prog.uniform("backface"), c.backface);
    glProgramUniform1i(p, prog.uniform("frustum"), c.frustum);
    glProgramUniform1i(p, prog.uniform("count_tests"), c.count_tests);
    glProgramUniform1i(p, prog.uniform("count_draws"), c.count_draws);
    glProgramUniform2f(p, prog.uniform("viewport"), float(ctx.width), float(ctx.height));
    glm::vec4 region(0.0f);
    if (ctx.pick) {
        const glm::ivec4 r = pick_rect_gl(ctx);
        region = glm::vec4(r.x, r.y, r.x + r.z, r.y + r.w);
    }
    glProgramUniform4fv(p, prog.uniform("region"), 1, &region.x);
    glProgramUniform1i(p, prog.uniform("pyramid_levels"), pyramid ? pyramid->levels : 1);
    glProgramUniform2i(p, prog.uniform("pyramid_size"), pyramid ? pyramid->width : 1, pyramid ? pyramid->height : 1);
    if (pyramid) glBindTextureUnit(14, pyramid->pyramid.id());
    lod.cells.bind_base(GL_SHADER_STORAGE_BUFFER, 20);
    lod.clusters.bind_base(GL_SHADER_STORAGE_BUFFER, 21);
    lod.state.bind_base(GL_SHADER_STORAGE_BUFFER, 22);
    lod.commands.bind_base(GL_SHADER_STORAGE_BUFFER, 23);
    lod.counts.bind_base(GL_SHADER_STORAGE_BUFFER, 24);
    glDispatchCompute((lod.cluster_count + 63) / 64, 1, 1);
    glMemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

// Draws what cull() appended to `slot`.
void draw_slot(const DrawItem& item, const GpuLod& lod, std::uint32_t slot) {
    glBindVertexArray(item.vao);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, lod.commands.id());
    glBindBuffer(GL_PARAMETER_BUFFER_ARB, lod.counts.id());
    glMultiDrawElementsIndirectCountARB(
        GL_TRIANGLES, GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(std::uintptr_t(slot) * lod.cluster_count * kCommandBytes), GLintptr(slot * 4),
        GLsizei(lod.cluster_count), GLsizei(kCommandBytes));
    glBindBuffer(GL_PARAMETER_BUFFER_ARB, 0);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
}

// `count` indices of the item's element buffer from `first` on.
void draw_range(const DrawItem& item, std::uint32_t first, std::uint32_t count) {
    glBindVertexArray(item.vao);
    glDrawElements(GL_TRIANGLES, GLsizei(count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(std::uintptr_t(first) * 4));
}

void draw_whole(const DrawItem& item) { draw_range(item, 0, std::uint32_t(item.count)); }

// The pyramid of the depth drawn so far (depth_pyramid.comp).
void build_pyramid(const FrameContext& ctx, GlResources& gl, CullState& s, GLuint depth, int samples) {
    // Level 0 at half the image's resolution (2x2 pixels a texel), powers of two.
    const int w = int(std::bit_ceil(unsigned(ctx.width + 1) / 2)), h = int(std::bit_ceil(unsigned(ctx.height + 1) / 2));
    if (s.width != w || s.height != h) {
        s.levels = std::bit_width(unsigned(std::max(w, h)));
        s.pyramid = gl::Texture::create_2d_levels(GL_R32F, w, h, s.levels);
        s.width = w;
        s.height = h;
    }
    const GLuint tex = s.pyramid.id();
    auto& first = gl.program({"render/depth_pyramid.comp"},
                             "#define FROM_DEPTH 1\n" +
                                 (samples > 1 ? "#define SAMPLES " + std::to_string(samples) + "\n" : std::string()));
    first.use();
    glProgramUniform2i(first.id(), first.uniform("image_size"), ctx.width, ctx.height);
    glBindTextureUnit(15, depth);
    glBindImageTexture(7, tex, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glDispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
    auto& down = gl.program({"render/depth_pyramid.comp"});
    down.use();
    for (int l = 1; l < s.levels; ++l) {
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        glBindImageTexture(6, tex, l - 1, GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
        glBindImageTexture(7, tex, l, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
        const int lw = std::max(1, w >> l), lh = std::max(1, h >> l);
        glDispatchCompute(GLuint((lw + 7) / 8), GLuint((lh + 7) / 8), 1);
    }
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

float lod_error(const FrameContext& ctx) {
    const LodSettings& l = ctx.opt.look.lod;
    if (!l.enabled) return 0.0f;
    return float(ctx.opt.moving ? std::max(l.error_px, l.moving_error_px) : l.error_px);
}

bool backface_ok(const FrameContext& ctx, const DrawItem& item) {
    // A closed surface seen from outside its bounds, uncut: what faces away is hidden behind what faces the eye.
    const glm::dvec3 e = ctx.camera.eye;
    const bool inside =
        glm::all(glm::greaterThanEqual(e, item.bounds.min)) && glm::all(glm::lessThanEqual(e, item.bounds.max));
    return item.closed && !ctx.opt.look.clip.active() && !inside;
}

// Without a last frame: the nearest distance of each sixteenth of the
// cells (each batch is tested against the pyramid of the nearer ones). On
// the 1024^3 phantom at 1920x1080 the first frame drew 6.6 M triangles in
// 1.4 s with 8 batches, 4.2 M in 1.0 s with 16, 3.3 M in 1.1 s with 32 (a
// pyramid costs about 10 ms).
constexpr std::size_t kBatches = 16;
std::array<float, kBatches + 1> batches(const FrameContext& ctx, const std::vector<const DrawItem*>& items) {
    std::vector<float> d;
    const glm::vec3 eye(ctx.camera.eye);
    for (const DrawItem* it : items)
        for (const auto& c : it->lod->cpu_cells) d.push_back(glm::length(eye - glm::clamp(eye, c.lo, c.hi)));
    std::sort(d.begin(), d.end());
    const float inf = std::numeric_limits<float>::infinity();
    std::array<float, kBatches + 1> b;
    b.fill(inf);
    b[0] = 0.0f;
    if (d.empty()) return b;
    for (std::size_t q = 1; q < kBatches; ++q) b[q] = d[d.size() * q / kBatches];
    return b;
}

// Occlusion culling costs a depth pyramid per phase (on llvmpipe about
// 10 ms at 1920x1080), worth it when the clustered surfaces have many more
// triangles than the image has pixels (measured with lod_bench: the bundled
// CT's bone resampled 3x, 0.7 M triangles at 1920x1080, drew faster without;
// the 1024^3 phantom, 32 M, four times faster with). Without it the clusters
// are still culled by level, frustum and back faces.
bool occlusion_pays(const FrameContext& ctx, const std::vector<DrawItem>& items) {
    std::size_t triangles = 0;
    for (const auto& it : items)
        if (it.lod) triangles += it.lod->full_triangles;
    return double(triangles) >= kOcclusionTrianglesPerPixel * double(ctx.width) * double(ctx.height);
}

// The G-buffer's surfaces in the two-pass occlusion scheme (lod_draw.hpp).
void draw_visible(const FrameContext& ctx, GlResources& gl, const std::vector<DrawItem>& items,
                  const std::function<void(const DrawItem&)>& bind, GLuint depth, int samples) {
    std::vector<const DrawItem*> lod;
    bool history = true;
    for (const auto& it : items)
        if (it.lod) {
            lod.push_back(&it);
            history = history && it.lod->frames > 0;
        }
    const auto b = batches(ctx, lod);
    const int phases = history ? 2 : int(kBatches);
    ctx.result->lod.phases = phases;
    CullState& pyramid = *ctx.cull;
    for (int phase = 0; phase < phases; ++phase) {
        if (phase > 0) build_pyramid(ctx, gl, pyramid, depth, samples);
        for (const auto& it : items) {
            if (!it.lod) {
                if (phase == 0) {
                    bind(it);
                    draw_whole(it);
                }
                continue;
            }
            CullCall c;
            c.mode = phase == 0 ? kModeFirst : kModeTest;
            c.slot = std::uint32_t(phase) % kPhaseSlots; // a phase's draws are read before the next one's cull writes
            c.history = history;
            c.backface = backface_ok(ctx, it);
            c.count_draws = true;
            c.max_error_px = lod_error(ctx);
            if (!history) c.batch = {b[std::size_t(phase)], b[std::size_t(phase) + 1]}; // with history: every distance
            cull(ctx, gl, *it.lod, c, phase > 0 ? &pyramid : nullptr);
            bind(it);
            draw_slot(it, *it.lod, c.slot);
        }
    }
    if (lod.empty()) return;
    build_pyramid(ctx, gl, pyramid, depth, samples);
    for (const DrawItem* it : lod) {
        // The cells' visible levels are this frame's from here on (lod_cull.comp's State).
        const GLuint zero = 0;
        glClearNamedBufferSubData(it->lod->state.id(), GL_R32UI, GLintptr(it->lod->cluster_count) * 4,
                                  GLsizeiptr(it->lod->cpu_cells.size()) * 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        CullCall c;
        c.mode = kModeFinal;
        c.slot = kSlots - 1;
        c.backface = backface_ok(ctx, *it);
        c.count_tests = true;
        c.max_error_px = lod_error(ctx);
        cull(ctx, gl, *it->lod, c, &pyramid);
        ++it->lod->frames;
    }
}

} // namespace

const lod::Proxy* moving_proxy(const FrameContext& ctx, const DrawItem& item) {
    if (!ctx.opt.moving || ctx.pick || !item.lod || !ctx.opt.look.lod.enabled) return nullptr;
    const float limit =
        lod::error_limit_mm(glm::vec3(ctx.camera.eye), glm::vec3(item.bounds.min), glm::vec3(item.bounds.max),
                            pixels_per_mm_at_1mm(ctx), lod_error(ctx), float(ctx.camera.near_plane));
    const auto& p = item.lod->proxies;
    for (auto it = p.rbegin(); it != p.rend(); ++it)
        if (it->error <= limit) return &*it;
    return nullptr;
}

GpuLod upload_lod(const lod::ClusterLod& c, std::uint32_t vao, gl::Buffer& indices) {
    GpuLod g;
    indices = gl::Buffer(c.indices.size() * 4, c.indices.data(), 0);
    glVertexArrayElementBuffer(vao, indices.id());
    g.cells = gl::Buffer(c.cells.size() * sizeof(lod::Cell), c.cells.data(), 0);
    g.clusters = gl::Buffer(c.clusters.size() * sizeof(lod::Cluster), c.clusters.data(), 0);
    g.order = gl::Buffer(std::max<std::size_t>(c.triangle_order.size(), 1) * 4, c.triangle_order.data(), 0);
    g.cluster_count = std::uint32_t(c.clusters.size());
    g.state = gl::Buffer((std::size_t(g.cluster_count) + c.cells.size() + 1) * 4, nullptr, 0); // lod_cull.comp's State
    g.state.clear_u32(0);
    g.commands = gl::Buffer(std::max<std::size_t>(g.cluster_count, 1) * kSlots * kCommandBytes, nullptr, 0);
    g.counts = gl::Buffer(kCountWords * 4, nullptr, 0);
    g.counts.clear_u32(0);
    g.cpu_cells = c.cells;
    g.full_triangles = c.level0_indices / 3;
    g.proxies = c.proxies;
    return g;
}

void draw_surfaces(const FrameContext& ctx, GlResources& gl, const std::vector<DrawItem>& all, DrawSet set,
                   const std::function<void(const DrawItem&)>& bind, std::uint32_t depth, int samples) {
    // Stand-ins first (a moving frame), then the rest as they would be drawn.
    std::vector<DrawItem> items;
    for (const auto& it : all) {
        const lod::Proxy* p = set == DrawSet::Complete ? nullptr : moving_proxy(ctx, it);
        if (!p) {
            items.push_back(it);
            continue;
        }
        if (ctx.result) ctx.result->lod.used = true;
        bind(it);
        draw_range(it, p->first_index, p->index_count);
    }
    const bool any_lod = std::any_of(items.begin(), items.end(), [](const DrawItem& d) { return d.lod != nullptr; });
    const bool culled = ctx.opt.look.lod.enabled && ctx.opt.look.lod.culling;
    if (any_lod && ctx.result) ctx.result->lod.used = true;
    if (set == DrawSet::Visible && any_lod && !ctx.pick && culled && ctx.cull && depth && occlusion_pays(ctx, items))
        return draw_visible(ctx, gl, items, bind, depth, samples);
    if (set == DrawSet::Visible && any_lod && ctx.result) ctx.result->lod.phases = 1;
    for (const auto& it : items) {
        if (!it.lod || (!ctx.pick && !ctx.opt.look.lod.enabled)) {
            bind(it);
            draw_whole(it);
            continue;
        }
        // A pick: level 0 in the pick region. Else the levels, in view
        // (translucent; the G-buffer without culling) or all (voxelization).
        CullCall c;
        c.slot = ctx.pick ? kPickSlot : set == DrawSet::Complete ? kCompleteSlot : kInViewSlot;
        c.max_error_px = ctx.pick ? 0.0f : lod_error(ctx);
        c.frustum = set != DrawSet::Complete && (culled || ctx.pick);
        c.backface = set == DrawSet::Visible && culled && !ctx.pick && backface_ok(ctx, it);
        c.count_tests = c.count_draws = set != DrawSet::Complete;
        cull(ctx, gl, *it.lod, c, nullptr);
        bind(it);
        draw_slot(it, *it.lod, c.slot);
    }
}

void bind_triangle_order(const DrawItem& item, std::uint32_t program) {
    const GLint loc = glGetUniformLocation(program, "reordered");
    if (loc >= 0) glProgramUniform1i(program, loc, item.lod ? 1 : 0);
    if (item.lod) item.lod->order.bind_base(GL_SHADER_STORAGE_BUFFER, 7);
}

} // namespace iso::passes
