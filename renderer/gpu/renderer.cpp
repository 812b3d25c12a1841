#include "renderer/gpu/renderer.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "io/error.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/gpu/gpu_volume.hpp"
#include "renderer/ao/disk_hierarchy.hpp"
#include "renderer/passes/disk_state.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/lod_draw.hpp"

namespace iso {

namespace {

constexpr std::size_t kOitMinNodes = 1 << 16; // the pool never shrinks below this

} // namespace

// A surface on the GPU: outside the anonymous namespace because
// Renderer::Impl (declared in the header) holds them, which g++ flags
// otherwise (-Wsubobject-linkage).
struct GpuMesh {
    gl::VertexArray vao;
    gl::Buffer vertices, indices;
    GLsizei count = 0;
    SceneObject object;
    Bounds bounds;
    // Disk AO builds its hierarchy once, on first use, from the mesh read
    // back from these buffers (renderer/passes/disk_ao.cpp); a new mesh gets
    // a new version.
    std::shared_ptr<const DiskHierarchy> disk;
    std::uint64_t version = 0;
    // Clusters and levels of detail (set_lod: core::SurfaceLod builds them;
    // docs/lod.md); the element buffer is then theirs.
    std::unique_ptr<passes::GpuLod> lod;
};

namespace {

std::vector<glm::vec3> vertex_normals(const Mesh& m) {
    std::vector<glm::vec3> n(m.positions.size(), glm::vec3(0.0f));
    for (const auto& t : m.triangles) {
        const glm::vec3 fn = glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]);
        for (auto v : t) n[v] += fn;
    }
    for (auto& x : n) {
        const float l = glm::length(x);
        x = l > 0 ? x / l : glm::vec3(0, 0, 1);
    }
    return n;
}

} // namespace

struct Renderer::Impl {
    std::vector<GpuMesh> meshes;
    // Declared before the pool: the pool gives its resources back through it.
    passes::GlResources gl;
    graph::ResourcePool pool{gl};
    std::uint64_t geometry_version = 0;
    passes::AoHistory ao;
    passes::AaHistory aa;
    int max_samples = 0; // multisample textures: the most samples every G-buffer format allows (0: not asked yet)
    passes::DiskState disk;
    std::uint64_t mesh_versions = 0;
    std::size_t oit_next_capacity = 0; // VOIT pool nodes for the next frame (0: none drawn yet)
    bool oit_cut = false;              // the last frame at the VOIT cap needed the depth cut: start with it
    GpuVolume volume;
    passes::CullState cull;
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;

namespace {
GpuMesh upload(const Mesh& m, const SceneObject& o) {
    GpuMesh g;
    g.object = o;
    const auto normals = m.normals.size() == m.positions.size() ? m.normals : vertex_normals(m);
    std::vector<float> interleaved;
    interleaved.reserve(m.positions.size() * 6);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const auto& p = m.positions[i];
        const auto& n = normals[i];
        interleaved.insert(interleaved.end(), {p.x, p.y, p.z, n.x, n.y, n.z});
        g.bounds.add(glm::dvec3(p));
    }
    g.vertices = gl::Buffer::from<float>(interleaved, 0);
    g.indices = gl::Buffer(m.triangles.size() * 12, m.triangles.data(), 0);
    g.count = GLsizei(m.triangles.size() * 3);
    g.vao = gl::VertexArray::create();
    const GLuint vao = g.vao.id();
    glVertexArrayVertexBuffer(vao, 0, g.vertices.id(), 0, 6 * sizeof(float));
    glVertexArrayElementBuffer(vao, g.indices.id());
    for (GLuint a = 0; a < 2; ++a) {
        glEnableVertexArrayAttrib(vao, a);
        glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
        glVertexArrayAttribBinding(vao, a, 0);
    }
    return g;
}
// The mesh as drawn (positions, the normals the G-buffer uses, triangles),
// read back from the GPU buffers. Disk AO needs it once per surface; reading
// it back then, instead of keeping a CPU copy of every surface in case a
// still picture asks for disk AO, keeps the renderer's memory at the GPU's.
Mesh read_back(const GpuMesh& g) {
    Mesh m;
    const auto v = g.vertices.read_all<float>();
    m.positions.resize(v.size() / 6);
    m.normals.resize(v.size() / 6);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        m.positions[i] = {v[6 * i], v[6 * i + 1], v[6 * i + 2]};
        m.normals[i] = {v[6 * i + 3], v[6 * i + 4], v[6 * i + 5]};
    }
    m.triangles.resize(std::size_t(g.count) / 3);
    g.indices.read(0, m.triangles.size() * 12, m.triangles.data());
    return m;
}
std::vector<const passes::DrawItem*> draws_of(const passes::FrameContext& ctx) {
    std::vector<const passes::DrawItem*> v;
    for (const auto& d : ctx.draws) v.push_back(&d);
    for (const auto& d : ctx.translucent) v.push_back(&d);
    return v;
}

// The frame's cluster statistics, read back from each surface's counters.
void lod_stats(const passes::FrameContext& ctx, LodStats& s) {
    for (const passes::DrawItem* d : draws_of(ctx)) {
        s.triangles_full += std::uint64_t(d->count) / 3;
        if (!d->lod || (!ctx.opt.look.lod.enabled && !ctx.pick)) {
            s.triangles_drawn += std::uint64_t(d->count) / 3;
            continue;
        }
        if (const lod::Proxy* p = passes::moving_proxy(ctx, *d)) { // drawn instead of its clusters
            s.triangles_drawn += p->index_count / 3;
            continue;
        }
        std::uint32_t w[passes::kCountWords] = {};
        d->lod->counts.read(0, sizeof w, w);
        const std::uint32_t* c = w + passes::kStatsWord; // lod_cull.comp's C_SELECTED ...
        s.clusters += d->lod->cluster_count;
        s.tested += c[0];
        s.culled_frustum += c[1];
        s.culled_backface += c[2];
        s.culled_occlusion += c[3];
        s.drawn += c[4];
        s.triangles_drawn += c[5];
    }
}

} // namespace

std::uint32_t Renderer::add(const Mesh& m, const SceneObject& o) {
    impl_->meshes.push_back(upload(m, o));
    impl_->meshes.back().version = ++impl_->mesh_versions;
    ++impl_->geometry_version;
    return std::uint32_t(impl_->meshes.size());
}

void Renderer::replace(std::uint32_t id, const Mesh& m) {
    auto& slot = impl_->meshes.at(id - 1);
    slot = upload(m, slot.object);
    slot.version = ++impl_->mesh_versions;
    ++impl_->geometry_version;
}

void Renderer::remove(std::uint32_t id) {
    auto& slot = impl_->meshes.at(id - 1);
    SceneObject o = slot.object;
    o.visible = false;
    slot = GpuMesh{};
    slot.object = o;
    ++impl_->geometry_version;
}

std::size_t Renderer::object_count() const { return impl_->meshes.size(); }

void Renderer::set_lod(std::uint32_t id, const lod::ClusterLod& c) {
    auto& g = impl_->meshes.at(id - 1);
    if (c.level0_indices != std::size_t(g.count))
        throw Error("levels of detail", "object " + std::to_string(id) + " has " + std::to_string(g.count / 3) +
                                            " triangles, its levels " + std::to_string(c.level0_indices / 3));
    g.lod = std::make_unique<passes::GpuLod>(passes::upload_lod(c, g.vao.id(), g.indices));
}

bool Renderer::has_lod(std::uint32_t id) const {
    return id >= 1 && id <= impl_->meshes.size() && impl_->meshes[id - 1].lod != nullptr;
}

void Renderer::set_volume(std::shared_ptr<const Volume> v, std::shared_ptr<const ChunkIndex> index) {
    impl_->volume.set(std::move(v), std::move(index));
    ++impl_->geometry_version;
}

SceneObject& Renderer::object(std::uint32_t id) { return impl_->meshes.at(id - 1).object; }

Bounds Renderer::bounds() const {
    Bounds b;
    for (const auto& m : impl_->meshes)
        if (m.object.visible && !m.bounds.empty()) {
            b.add(m.bounds.min);
            b.add(m.bounds.max);
        }
    return b;
}

RenderResult Renderer::render(const Camera& camera, const RenderOptions& opt, const RenderHooks& hooks) {
    if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
        throw Error("render", "image size " + std::to_string(opt.width) + "x" + std::to_string(opt.height) +
                                  " is out of range (1..16384)");
    validate(opt.look);
    Impl& im = *impl_;
    std::vector<passes::DrawItem> draws;
    for (std::size_t i = 0; i < im.meshes.size(); ++i) {
        auto& m = im.meshes[i];
        if (!m.object.visible || m.count == 0) continue;
        draws.push_back({m.vao.id(), m.count, std::uint32_t(i + 1), m.object.color,
                         opt.look.transparency ? std::clamp(m.object.opacity, 0.0f, 1.0f) : 1.0f, m.bounds, m.lod.get(),
                         m.object.closed});
    }
    const Bounds b = bounds();
    // The VOIT pool: sized from the last frame's fragment count; a frame that
    // overflows it is drawn again with a pool large enough, up to the cap.
    const std::size_t cap_max = std::size_t(opt.look.oit_memory_mib * 1048576.0) / passes::kOitNodeBytes;
    // A first frame guesses two fragments per pixel.
    const std::size_t first_guess =
        std::bit_ceil(std::max(kOitMinNodes, 2 * std::size_t(opt.width) * std::size_t(opt.height)));
    std::size_t capacity = std::min(im.oit_next_capacity ? im.oit_next_capacity : first_guess, cap_max);
    passes::FrameContext ctx = passes::make_context(camera, opt, std::move(draws), b);
    ctx.hooks = hooks;
    ctx.gl = &im.gl;
    ctx.pool = &im.pool;
    ctx.geometry_version = im.geometry_version;
    if (ctx.aa_samples > 1) { // llvmpipe, for one, stops at 4
        if (im.max_samples == 0) {
            GLint color = 1, depth = 1, integer = 1;
            glGetIntegerv(GL_MAX_COLOR_TEXTURE_SAMPLES, &color);
            glGetIntegerv(GL_MAX_DEPTH_TEXTURE_SAMPLES, &depth);
            glGetIntegerv(GL_MAX_INTEGER_SAMPLES, &integer);
            im.max_samples = std::max(1, std::min({color, depth, integer}));
        }
        ctx.aa_samples = std::min(ctx.aa_samples, im.max_samples);
    }
    ctx.ao = &im.ao;
    ctx.disk = &im.disk;
    ctx.cull = &im.cull;
    // The volume serves the colour image only (picks march it on the CPU: core/pick.hpp).
    if (opt.look.volume.enabled && opt.image && opt.aov == Aov::None) ctx.volume = &im.volume.prepare(opt.look.volume);
    for (const auto& d : ctx.draws) {
        auto& m = im.meshes[d.id - 1];
        ctx.disk_surfaces.push_back({d.id, m.version, [&m] { return read_back(m); }, &m.disk});
    }
    // Accumulated frames: the next jitter of the running average, which
    // starts again when anything but the jitter changed.
    const bool accumulates = opt.accumulate && opt.image && opt.aov == Aov::None;
    if (accumulates) {
        auto key = passes::accumulation_key(ctx);
        if (key != im.aa.key || opt.restart_accumulation) {
            im.aa.key = std::move(key);
            im.aa.frames = 0;
        }
        ctx.aa = &im.aa;
        ctx.aa_frame = im.aa.frames;
        // The frames after the first take one sample each: DSRAA's fixed
        // sub-sample pattern, moved by the jitter, would reach into the
        // neighbours' footprints and blur the average; one jittered sample
        // per frame averages to exact coverage.
        if (ctx.aa_frame > 0) ctx.aa_samples = 1;
        passes::set_jitter(ctx, opt.jitter ? *opt.jitter : passes::jitter_offset(im.aa.frames));
    }
    for (int redraws = 0;; ++redraws) {
        // A frame drawn again (the VOIT pool was too small) starts the average again.
        if (redraws > 0) ctx.aa_frame = 0;
        RenderResult result;
        result.aa_samples = ctx.aa_samples;
        result.gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        ctx.result = &result;
        ctx.oit_capacity = capacity;
        ctx.oit_merge = capacity >= cap_max;
        ctx.oit_cut = ctx.oit_merge && im.oit_cut;
        graph::FrameGraph fg;
        if (opt.time_passes) fg.set_pass_epilogue([] { glFinish(); });
        passes::build_frame(fg, ctx);
        for (const auto& d : draws_of(ctx))
            if (d->lod) d->lod->counts.clear_u32(0);
        result.stats = fg.execute(im.pool);
        lod_stats(ctx, result.lod);
        // Without an image the resolve did not run: no fragment count to size the pool from, nothing to redraw.
        if (ctx.translucent.empty() || !opt.image) return result;
        // Sizes are powers of two and shrink only when four times too large,
        // so a moving view keeps its pool instead of remaking it each frame.
        const std::size_t n = std::size_t(result.oit.fragments);
        const auto fit = [&](std::size_t need) {
            return std::min(cap_max, std::max(kOitMinNodes, std::bit_ceil(need)));
        };
        if (n > capacity)
            im.oit_next_capacity = fit(n + n / 4);
        else if (n < capacity / 4)
            im.oit_next_capacity = fit(2 * n);
        else
            im.oit_next_capacity = capacity;
        result.oit.redraws = redraws;
        // At the cap, a frame with more fragments than fit is drawn again
        // with the depth cut (so the farthest are merged, not the last
        // rasterized), and so are the following frames until they fit.
        const bool over = result.oit.merged > 0;
        if (capacity >= cap_max) {
            const bool was_cut = ctx.oit_cut;
            im.oit_cut = over;
            if (!over || was_cut) return result;
        } else if (!over) {
            return result;
        }
        capacity = im.oit_next_capacity;
    }
}

const graph::ResourcePool& Renderer::pool() const { return impl_->pool; }
std::size_t Renderer::gl_objects_created() const { return impl_->gl.objects_created(); }

} // namespace iso
