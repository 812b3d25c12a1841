#include "renderer/render/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "io/error.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/render/overlay.hpp"

namespace iso {

Aov aov_from_name(const std::string& n) {
    if (n == "depth") return Aov::Depth;
    if (n == "normal") return Aov::Normal;
    if (n == "id") return Aov::Id;
    if (n == "ao") return Aov::Ao;
    if (n.empty() || n == "none") return Aov::None;
    throw Error("--aov", "unknown AOV '" + n + "' (depth, normal, id, ao)");
}

namespace {

GLenum gl_format(graph::Format f) {
    switch (f) {
    case graph::Format::RGBA8: return GL_RGBA8;
    case graph::Format::RGBA16F: return GL_RGBA16F;
    case graph::Format::RGBA32F: return GL_RGBA32F;
    case graph::Format::R32F: return GL_R32F;
    case graph::Format::RG16F: return GL_RG16F;
    case graph::Format::R32UI: return GL_R32UI;
    case graph::Format::RGBA32UI: return GL_RGBA32UI;
    case graph::Format::Depth32F: return GL_DEPTH_COMPONENT32F;
    }
    return GL_RGBA8;
}

// The pass graph's resources as GL objects.
class GlBackend : public graph::Backend {
public:
    std::uint64_t create_texture(const graph::TextureDesc& d, const std::string& name) override {
        auto t = gl::Texture::create_2d(gl_format(d.format), d.width, d.height);
        glObjectLabel(GL_TEXTURE, t.id(), GLsizei(name.size()), name.c_str());
        const auto id = next_++;
        textures_.emplace(id, std::move(t));
        return id;
    }
    std::uint64_t create_buffer(const graph::BufferDesc& d, const std::string& name) override {
        gl::Buffer b(d.bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
        glObjectLabel(GL_BUFFER, b.id(), GLsizei(name.size()), name.c_str());
        const auto id = next_++;
        buffers_.emplace(id, std::move(b));
        return id;
    }
    void destroy(std::uint64_t id) override {
        textures_.erase(id);
        buffers_.erase(id);
    }
    GLuint texture(std::uint64_t id) const { return textures_.at(id).id(); }
    GLuint buffer(std::uint64_t id) const { return buffers_.at(id).id(); }
    // Persistent resources (kept across frames, imported into each frame's graph).
    std::uint64_t adopt(gl::Texture t) {
        const auto id = next_++;
        textures_.emplace(id, std::move(t));
        return id;
    }
    std::uint64_t adopt(gl::Buffer b) {
        const auto id = next_++;
        buffers_.emplace(id, std::move(b));
        return id;
    }

private:
    std::uint64_t next_ = 1;
    std::map<std::uint64_t, gl::Texture> textures_;
    std::map<std::uint64_t, gl::Buffer> buffers_;
};

struct GpuMesh {
    gl::VertexArray vao;
    gl::Buffer vertices, indices;
    GLsizei count = 0;
    SceneObject object;
    Bounds bounds;
};

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
    gl::Program gbuffer = gl::Program::from_files({"render/gbuffer.vert", "render/gbuffer.frag"});
    gl::Program lighting = gl::Program::from_files({"render/fullscreen.vert", "render/lighting.frag"});
    gl::Program overlay = gl::Program::from_files({"render/overlay.vert", "render/overlay.frag"});
    gl::Program zrange = gl::Program::from_files({"ao/zrange.comp"});
    gl::Program ao_upsample = gl::Program::from_files({"ao/ao_upsample.comp"});
    gl::VertexArray empty_vao = gl::VertexArray::create();
    GlBackend backend;
    std::uint64_t geometry_version = 0;

    // Programs whose source depends on the slicemap's layer count.
    std::map<int, gl::Program> slicemap_programs, cone_programs;
    gl::Program& slicemap_program(int layers) {
        auto it = slicemap_programs.find(layers);
        if (it == slicemap_programs.end())
            it = slicemap_programs.emplace(layers, gl::Program::from_files({"ao/slicemap.vert", "ao/slicemap.frag"},
                                                                           "#define LAYERS " + std::to_string(layers) + "\n")).first;
        return it->second;
    }
    gl::Program& cone_program(int layers, bool coarse) {
        const int key = layers * 2 + (coarse ? 1 : 0);
        auto it = cone_programs.find(key);
        if (it == cone_programs.end())
            it = cone_programs
                     .emplace(key, gl::Program::from_files({"ao/cone.comp"}, "#define LAYERS " + std::to_string(layers) + "\n" +
                                                                                 (coarse ? "#define COARSE 1\n" : "")))
                     .first;
        return it->second;
    }

    // AO state kept across frames: the slicemap is rebuilt only when the
    // geometry, the camera or the grid changed; the AO image accumulates new
    // jitter sets while nothing changed at all.
    struct AoState {
        std::uint64_t slicemap = 0, zrange = 0, ao_image = 0, ao_low = 0, pattern = 0; // backend ids (0: none yet)
        int grid_w = 0, grid_h = 0, layers = 0, width = 0, height = 0, low_w = 0, low_h = 0, samples_len = 0;
        std::vector<double> view_key;   // what the slicemap depends on
        ConeAoSettings settings;        // what the accumulated AO depends on too
        int frames = 0;
    } ao;
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;

std::uint32_t Renderer::add(const Mesh& m, const SceneObject& o) {
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
    impl_->meshes.push_back(std::move(g));
    ++impl_->geometry_version;
    return std::uint32_t(impl_->meshes.size());
}

std::size_t Renderer::object_count() const { return impl_->meshes.size(); }

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

RenderResult Renderer::render(const Camera& camera, const RenderOptions& opt) {
    if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
        throw Error("render", "image size " + std::to_string(opt.width) + "x" + std::to_string(opt.height) +
                                  " is out of range (1..16384)");
    RenderResult result;
    result.gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const int W = opt.width, H = opt.height;
    const double aspect = double(W) / double(H);
    const glm::mat4 view_projection = glm::mat4(camera.projection(aspect) * camera.view());
    const glm::mat3 world_to_view = glm::mat3(glm::mat4(camera.view()));
    Impl& im = *impl_;

    graph::FrameGraph fg;
    if (opt.time_passes) fg.set_pass_epilogue([] { glFinish(); });
    struct GBuffer {
        graph::TextureHandle depth, normal, id, albedo;
    };
    const auto& gb = fg.add_pass<GBuffer>(
        "gbuffer",
        [&](graph::FrameGraph::Builder& b, GBuffer& d) {
            d.depth = b.write(b.create("depth", {W, H, graph::Format::Depth32F}));
            d.normal = b.write(b.create("normal", {W, H, graph::Format::RGBA16F}));
            d.id = b.write(b.create("id", {W, H, graph::Format::R32UI}));
            d.albedo = b.write(b.create("albedo", {W, H, graph::Format::RGBA8}));
        },
        [&](const GBuffer& d, const graph::Resources& r) {
            auto fb = gl::Framebuffer::create();
            glNamedFramebufferTexture(fb.id(), GL_DEPTH_ATTACHMENT, im.backend.texture(r.get(d.depth)), 0);
            glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, im.backend.texture(r.get(d.normal)), 0);
            glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT1, im.backend.texture(r.get(d.id)), 0);
            glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT2, im.backend.texture(r.get(d.albedo)), 0);
            const GLenum bufs[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
            glNamedFramebufferDrawBuffers(fb.id(), 3, bufs);
            fb.check();
            glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
            glViewport(0, 0, W, H);
            const float zero[4] = {0, 0, 0, 0};
            const GLuint zero_u[4] = {0, 0, 0, 0};
            const float far_depth = 0.0f; // reversed Z
            glClearNamedFramebufferfv(fb.id(), GL_COLOR, 0, zero);
            glClearNamedFramebufferuiv(fb.id(), GL_COLOR, 1, zero_u);
            glClearNamedFramebufferfv(fb.id(), GL_COLOR, 2, zero);
            glClearNamedFramebufferfv(fb.id(), GL_DEPTH, 0, &far_depth);
            glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_GREATER);
            glDisable(GL_CULL_FACE); // open surfaces show both sides
            im.gbuffer.use();
            glUniformMatrix4fv(im.gbuffer.uniform("view_projection"), 1, GL_FALSE, &view_projection[0][0]);
            for (std::size_t i = 0; i < im.meshes.size(); ++i) {
                const auto& m = im.meshes[i];
                if (!m.object.visible || m.count == 0) continue;
                glUniform1ui(im.gbuffer.uniform("object_id"), GLuint(i + 1));
                glUniform3fv(im.gbuffer.uniform("albedo"), 1, &m.object.color.x);
                glBindVertexArray(m.vao.id());
                glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
            }
            glBindVertexArray(0);
            glDisable(GL_DEPTH_TEST);
            glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        });

    // ---- ambient occlusion: z range -> slicemap -> cone tracing ----------
    // Declared whenever AO is on; the graph culls them when nothing reads the
    // AO image (a depth AOV, for instance).
    const bool ao_on = opt.ao || opt.aov == Aov::Ao;
    graph::TextureHandle ao_image;
    bool voxelize_now = false;
    if (ao_on) {
        const ConeAoSettings st = opt.ao_settings;
        validate(st);
        auto& S = im.ao;
        // Guard band: occluders just outside the view still darken visible
        // points within R of them, so when the scene reaches beyond the
        // viewport the slicemap covers a margin around it (same texel
        // density), wide enough for R at the scene's nearest depth, at most
        // `guard` of the viewport per side. A scene wholly in view needs none.
        double guard = 0;
        {
            const Bounds sb = bounds();
            const glm::dmat4 vp = camera.projection(aspect) * camera.view();
            const glm::dmat4 v = camera.view();
            bool outside = false;
            double nearest = std::numeric_limits<double>::infinity();
            for (int c = 0; !sb.empty() && c < 8; ++c) {
                const glm::dvec4 w((c & 1) ? sb.max.x : sb.min.x, (c & 2) ? sb.max.y : sb.min.y, (c & 4) ? sb.max.z : sb.min.z, 1.0);
                const glm::dvec4 clip = vp * w;
                outside |= clip.w <= 0 || std::abs(clip.x) > clip.w || std::abs(clip.y) > clip.w;
                nearest = std::min(nearest, -(v * w).z);
            }
            if (outside && st.guard > 0) {
                const glm::dmat4 pr = camera.projection(aspect);
                const double d = std::max(nearest, camera.near_plane);
                guard = std::min(st.guard, 0.5 * st.radius_mm * std::max(pr[0][0], pr[1][1]) / d);
            }
        }
        // Whole texels of margin, so the texels stay aligned with those of
        // the viewport's own grid (a fractional shift would move every edge
        // by up to half a texel).
        const int gw0 = std::max(1, int(std::lround(W * st.grid_scale)));
        const int gh0 = std::max(1, int(std::lround(H * st.grid_scale)));
        const int gw = gw0 + 2 * int(std::ceil(guard * gw0));
        const int gh = gh0 + 2 * int(std::ceil(guard * gh0));
        const glm::vec2 sm_scale{float(gw0) / float(gw), float(gh0) / float(gh)}; // slicemap NDC per frame NDC
        result.ao_guard = guard;
        // Persistent resources, (re)made when their size changes.
        if (S.grid_w != gw || S.grid_h != gh || S.layers != st.layers) {
            if (S.slicemap) im.backend.destroy(S.slicemap);
            S.slicemap = im.backend.adopt(gl::Texture::create_2d_array(GL_RGBA32UI, gw, gh, st.layers));
            S.grid_w = gw;
            S.grid_h = gh;
            S.layers = st.layers;
            S.view_key.clear();
        }
        if (S.width != W || S.height != H) {
            if (S.ao_image) im.backend.destroy(S.ao_image);
            S.ao_image = im.backend.adopt(gl::Texture::create_2d(GL_R32F, W, H));
            S.width = W;
            S.height = H;
            S.view_key.clear();
        }
        // The cone pass's own image when it runs coarser than the frame
        // (--ao-resolution < 1); it keeps the still-frame history too.
        const int aw = std::max(1, int(std::lround(W * st.resolution)));
        const int ah = std::max(1, int(std::lround(H * st.resolution)));
        const bool coarse = aw != W || ah != H;
        if (coarse && (S.low_w != aw || S.low_h != ah)) {
            if (S.ao_low) im.backend.destroy(S.ao_low);
            S.ao_low = im.backend.adopt(gl::Texture::create_2d(GL_RGBA32F, aw, ah));
            S.low_w = aw;
            S.low_h = ah;
            S.view_key.clear();
        }
        if (!S.zrange) S.zrange = im.backend.adopt(gl::Buffer(8, nullptr, GL_DYNAMIC_STORAGE_BIT));
        // What the slicemap depends on: camera, viewport, grid, radius (its z
        // range), the geometry and which objects are visible.
        std::vector<double> key;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) key.push_back(double(view_projection[c][r]));
        key.insert(key.end(), {double(W), double(H), double(gw), double(gh), guard, double(st.layers), st.radius_mm,
                               double(im.geometry_version)});
        for (const auto& m : im.meshes) key.push_back(m.object.visible ? 1.0 : 0.0);
        voxelize_now = key != S.view_key || opt.ao_force_voxelize;
        if (voxelize_now || !(st == S.settings) || !st.temporal) S.frames = 0;
        S.view_key = key;
        S.settings = st;
        const std::uint32_t frame = std::uint32_t(S.frames);
        const float history_weight = float(frame) / float(frame + 1);
        ++S.frames;
        result.ao_frames = S.frames;
        result.voxelized = voxelize_now;
        // This frame's cones and jitter sets (new sets for each still frame).
        const auto pattern = cone_pattern(st, frame);
        if (S.pattern) im.backend.destroy(S.pattern);
        S.pattern = im.backend.adopt(gl::Buffer(pattern.size() * sizeof(glm::vec4), pattern.data(), 0));

        // The scene's far bound along the view axis (the slicemap's range).
        double scene_far = 0;
        const Bounds sb = bounds();
        if (!sb.empty())
            for (int c = 0; c < 8; ++c) {
                const glm::dvec3 corner((c & 1) ? sb.max.x : sb.min.x, (c & 2) ? sb.max.y : sb.min.y, (c & 4) ? sb.max.z : sb.min.z);
                scene_far = std::max(scene_far, -(camera.view() * glm::dvec4(corner, 1.0)).z);
            }
        const float scene_far_f = float(scene_far), radius_f = float(st.radius_mm);
        const float near_margin = guard > 0 ? radius_f : 0.0f;
        const float near_f = float(camera.near_plane), far_f = float(camera.far_plane);
        const glm::dmat4 proj = camera.projection(aspect);
        const glm::vec2 proj_scale{float(proj[0][0]), float(proj[1][1])};
        // The slicemap's projection: the frame's, its x and y shrunk by the guard band.
        const glm::dmat4 sm_proj = glm::scale(glm::dmat4(1.0), glm::dvec3(sm_scale.x, sm_scale.y, 1.0)) * proj;
        const glm::mat4 sm_view_projection = glm::mat4(sm_proj * camera.view());
        const glm::mat4 view_f = glm::mat4(camera.view());

        graph::BufferHandle zrange_h = fg.import("zrange", graph::BufferDesc{8}, S.zrange);
        graph::TextureHandle slicemap_h =
            fg.import("slicemap", graph::TextureDesc{gw, gh, graph::Format::RGBA32UI, st.layers}, S.slicemap);
        const graph::TextureHandle ao_h = fg.import("ao", graph::TextureDesc{W, H, graph::Format::R32F}, S.ao_image);
        const graph::TextureHandle cone_h =
            coarse ? fg.import("ao_coarse", graph::TextureDesc{aw, ah, graph::Format::RGBA32F}, S.ao_low) : ao_h;
        if (voxelize_now) {
            struct ZR {
                graph::BufferHandle range;
            };
            const auto& zr = fg.add_pass<ZR>(
                "zrange",
                [&](graph::FrameGraph::Builder& b, ZR& d) {
                    b.read(gb.depth);
                    d.range = b.write(zrange_h);
                },
                [&, near_f, far_f](const ZR& d, const graph::Resources& r) {
                    const GLuint buf = im.backend.buffer(r.get(d.range));
                    const GLuint init[2] = {0x7F800000u, 0u}; // +inf, 0
                    glNamedBufferSubData(buf, 0, 8, init);
                    im.zrange.use();
                    glBindTextureUnit(0, im.backend.texture(r.get(gb.depth)));
                    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
                    glUniform2i(im.zrange.uniform("size"), W, H);
                    glUniform1f(im.zrange.uniform("near_plane"), near_f);
                    glUniform1f(im.zrange.uniform("far_plane"), far_f);
                    glDispatchCompute(GLuint((W + 15) / 16), GLuint((H + 15) / 16), 1);
                    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                });
            zrange_h = zr.range;
            struct Vox {
                graph::TextureHandle slicemap;
            };
            const auto& vox = fg.add_pass<Vox>(
                "voxelize",
                [&](graph::FrameGraph::Builder& b, Vox& d) {
                    b.read(zrange_h);
                    d.slicemap = b.write(slicemap_h);
                },
                [&, gw, gh, layers = st.layers, scene_far_f, radius_f, view_f, zrange_h, sm_view_projection, near_margin](const Vox& d,
                                                                                                           const graph::Resources& r) {
                    const GLuint tex = im.backend.texture(r.get(d.slicemap));
                    auto fb = gl::Framebuffer::create();
                    std::vector<GLenum> bufs;
                    for (int l = 0; l < layers; ++l) {
                        glNamedFramebufferTextureLayer(fb.id(), GLenum(GL_COLOR_ATTACHMENT0 + l), tex, 0, l);
                        bufs.push_back(GLenum(GL_COLOR_ATTACHMENT0 + l));
                    }
                    glNamedFramebufferDrawBuffers(fb.id(), GLsizei(bufs.size()), bufs.data());
                    fb.check();
                    const GLuint zero[4] = {0, 0, 0, 0};
                    for (int l = 0; l < layers; ++l) glClearNamedFramebufferuiv(fb.id(), GL_COLOR, l, zero);
                    glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
                    glViewport(0, 0, gw, gh);
                    glDisable(GL_DEPTH_TEST);
                    glDisable(GL_CULL_FACE);
                    glEnable(GL_DEPTH_CLAMP);
                    glEnable(GL_COLOR_LOGIC_OP);
                    glLogicOp(GL_XOR);
                    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
                    auto& prog = im.slicemap_program(layers);
                    prog.use();
                    glUniformMatrix4fv(prog.uniform("view_projection"), 1, GL_FALSE, &sm_view_projection[0][0]);
                    glUniformMatrix4fv(prog.uniform("view"), 1, GL_FALSE, &view_f[0][0]);
                    glUniform1f(prog.uniform("scene_far"), scene_far_f);
                    glUniform1f(prog.uniform("near_margin"), near_margin);
                    glUniform1f(prog.uniform("radius"), radius_f);
                    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, im.backend.buffer(r.get(zrange_h)));
                    for (const auto& m : im.meshes) {
                        if (!m.object.visible || m.count == 0) continue;
                        glBindVertexArray(m.vao.id());
                        glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
                    }
                    glBindVertexArray(0);
                    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
                    glDisable(GL_COLOR_LOGIC_OP);
                    glDisable(GL_DEPTH_CLAMP);
                    glBindFramebuffer(GL_FRAMEBUFFER, 0);
                    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
                });
            slicemap_h = vox.slicemap;
        }
        struct Cone {
            graph::TextureHandle ao;
        };
        const auto& cone = fg.add_pass<Cone>(
            "cone_ao",
            [&](graph::FrameGraph::Builder& b, Cone& d) {
                b.read(gb.depth);
                b.read(gb.normal);
                b.read(slicemap_h);
                b.read(zrange_h);
                d.ao = b.write(cone_h);
            },
            [&, st, gw, gh, scene_far_f, near_margin, near_f, far_f, proj_scale, history_weight, slicemap_h, zrange_h,
             aw, ah, coarse, sm_scale, pattern_id = S.pattern](const Cone& d, const graph::Resources& r) {
                auto& prog = im.cone_program(st.layers, coarse);
                prog.use();
                glBindTextureUnit(0, im.backend.texture(r.get(gb.depth)));
                glBindTextureUnit(1, im.backend.texture(r.get(gb.normal)));
                glBindTextureUnit(2, im.backend.texture(r.get(slicemap_h)));
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, im.backend.buffer(r.get(zrange_h)));
                glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, im.backend.buffer(pattern_id));
                glBindImageTexture(0, im.backend.texture(r.get(d.ao)), 0, GL_FALSE, 0, GL_READ_WRITE, coarse ? GL_RGBA32F : GL_R32F);
                glUniformMatrix3fv(prog.uniform("world_to_view"), 1, GL_FALSE, &world_to_view[0][0]);
                glUniform2f(prog.uniform("proj_scale"), proj_scale.x, proj_scale.y);
                glUniform2f(prog.uniform("sm_proj_scale"), sm_scale.x * proj_scale.x, sm_scale.y * proj_scale.y);
                glUniform1f(prog.uniform("near_plane"), near_f);
                glUniform1f(prog.uniform("far_plane"), far_f);
                glUniform1f(prog.uniform("scene_far"), scene_far_f);
                glUniform1f(prog.uniform("near_margin"), near_margin);
                glUniform2i(prog.uniform("size"), W, H);
                glUniform2i(prog.uniform("ao_size"), aw, ah);
                glUniform2i(prog.uniform("grid"), gw, gh);
                glUniform1f(prog.uniform("radius"), float(st.radius_mm));
                glUniform1f(prog.uniform("strength"), float(st.strength));
                glUniform1f(prog.uniform("persistence"), float(st.persistence));
                glUniform1f(prog.uniform("attenuation"), float(st.attenuation));
                glUniform1f(prog.uniform("bias"), float(st.bias));
                glUniform1f(prog.uniform("ray_weight"), float(st.ray_weight));
                glUniform1i(prog.uniform("cones"), st.cones);
                glUniform1i(prog.uniform("spheres"), st.spheres);
                glUniform1i(prog.uniform("samples"), st.samples);
                glUniform1i(prog.uniform("sets"), st.jitter_sets);
                glUniform1f(prog.uniform("history_weight"), history_weight);
                glDispatchCompute(GLuint((aw + 7) / 8), GLuint((ah + 7) / 8), 1);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
            });
        ao_image = cone.ao;
        if (coarse) {
            struct Up {
                graph::TextureHandle ao;
            };
            const graph::TextureHandle coarse_h = cone.ao;
            const auto& up = fg.add_pass<Up>(
                "ao_upsample",
                [&](graph::FrameGraph::Builder& b, Up& d) {
                    b.read(gb.depth);
                    b.read(gb.normal);
                    b.read(coarse_h);
                    d.ao = b.write(ao_h);
                },
                [&, aw, ah, near_f, far_f, proj_scale, coarse_h](const Up& d, const graph::Resources& r) {
                    auto& prog = im.ao_upsample;
                    prog.use();
                    glBindTextureUnit(0, im.backend.texture(r.get(gb.depth)));
                    glBindTextureUnit(1, im.backend.texture(r.get(gb.normal)));
                    glBindTextureUnit(2, im.backend.texture(r.get(coarse_h)));
                    glBindImageTexture(0, im.backend.texture(r.get(d.ao)), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
                    glUniformMatrix3fv(prog.uniform("world_to_view"), 1, GL_FALSE, &world_to_view[0][0]);
                    glUniform2f(prog.uniform("proj_scale"), proj_scale.x, proj_scale.y);
                    glUniform1f(prog.uniform("near_plane"), near_f);
                    glUniform1f(prog.uniform("far_plane"), far_f);
                    glUniform2i(prog.uniform("size"), W, H);
                    glUniform2i(prog.uniform("ao_size"), aw, ah);
                    glDispatchCompute(GLuint((W + 7) / 8), GLuint((H + 7) / 8), 1);
                    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
                });
            ao_image = up.ao;
        }
        if (opt.read_slicemap) {
            struct ReadSm {
                graph::TextureHandle s;
            };
            fg.add_pass<ReadSm>(
                "read_slicemap",
                [&](graph::FrameGraph::Builder& b, ReadSm& d) {
                    d.s = b.read(slicemap_h);
                    b.read(zrange_h);
                    b.side_effect();
                },
                [&, gw, gh, layers = st.layers, scene_far_f, radius_f, zrange_h, sm_proj, near_margin](const ReadSm& d, const graph::Resources& r) {
                    SliceMap& sm = result.slicemap;
                    sm.width = gw;
                    sm.height = gh;
                    sm.layers = layers;
                    sm.view = camera.view();
                    sm.projection = sm_proj;
                    const std::size_t texels = std::size_t(gw) * std::size_t(gh);
                    std::vector<std::uint32_t> raw(texels * std::size_t(layers) * 4);
                    glGetTextureImage(im.backend.texture(r.get(d.s)), 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                                      GLsizei(raw.size() * 4), raw.data());
                    // GL returns layer after layer; SliceMap keeps a texel's layers together.
                    sm.words.resize(raw.size());
                    for (int l = 0; l < layers; ++l)
                        for (std::size_t t = 0; t < texels; ++t)
                            for (int c = 0; c < 4; ++c)
                                sm.words[(t * std::size_t(layers) + std::size_t(l)) * 4 + std::size_t(c)] =
                                    raw[(std::size_t(l) * texels + t) * 4 + std::size_t(c)];
                    GLuint bits[2];
                    glGetNamedBufferSubData(im.backend.buffer(r.get(zrange_h)), 0, 8, bits);
                    float zn, zx;
                    std::memcpy(&zn, &bits[0], 4);
                    std::memcpy(&zx, &bits[1], 4);
                    sm.z_near = std::max(double(zn) - double(near_margin), 0.0);
                    sm.z_far = std::max(double(std::min(scene_far_f, zx + radius_f)), sm.z_near + 1e-3);
                });
        }
    }

    struct Lit {
        graph::TextureHandle color;
    };
    const auto& lit = fg.add_pass<Lit>(
        "lighting",
        [&](graph::FrameGraph::Builder& b, Lit& d) {
            b.read(gb.normal);
            b.read(gb.albedo);
            if (opt.ao) b.read(ao_image);
            d.color = b.write(b.create("lit", {W, H, graph::Format::RGBA8}));
        },
        [&](const Lit& d, const graph::Resources& r) {
            auto fb = gl::Framebuffer::create();
            glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, im.backend.texture(r.get(d.color)), 0);
            fb.check();
            glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
            glViewport(0, 0, W, H);
            im.lighting.use();
            glBindTextureUnit(0, im.backend.texture(r.get(gb.normal)));
            glBindTextureUnit(1, im.backend.texture(r.get(gb.albedo)));
            glUniform1i(im.lighting.uniform("normal_tex"), 0);
            glUniform1i(im.lighting.uniform("albedo_tex"), 1);
            glUniform1i(im.lighting.uniform("use_ao"), opt.ao ? 1 : 0);
            if (opt.ao) {
                glBindTextureUnit(2, im.backend.texture(r.get(ao_image)));
                glUniform1i(im.lighting.uniform("ao_tex"), 2);
            }
            glUniformMatrix3fv(im.lighting.uniform("world_to_view"), 1, GL_FALSE, &world_to_view[0][0]);
            glUniform4fv(im.lighting.uniform("background"), 1, &opt.background.x);
            glBindVertexArray(im.empty_vao.id());
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glBindVertexArray(0);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        });

    // Annotations over the lit image: reads it and writes its next version.
    graph::TextureHandle final_color = lit.color;
    if (opt.annotations) {
        struct Ov {
            graph::TextureHandle color;
        };
        const auto verts = build_overlay(*opt.annotations, camera, W, H, opt.scale);
        const auto& ov = fg.add_pass<Ov>(
            "overlay",
            [&](graph::FrameGraph::Builder& b, Ov& d) { d.color = b.write(b.read(lit.color)); },
            [&, verts](const Ov& d, const graph::Resources& r) {
                if (verts.empty()) return;
                auto fb = gl::Framebuffer::create();
                glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, im.backend.texture(r.get(d.color)), 0);
                fb.check();
                glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
                glViewport(0, 0, W, H);
                gl::Buffer vb(verts.size() * sizeof(OverlayVertex), verts.data(), 0);
                auto vao = gl::VertexArray::create();
                glVertexArrayVertexBuffer(vao.id(), 0, vb.id(), 0, sizeof(OverlayVertex));
                glEnableVertexArrayAttrib(vao.id(), 0);
                glVertexArrayAttribFormat(vao.id(), 0, 2, GL_FLOAT, GL_FALSE, 0);
                glVertexArrayAttribBinding(vao.id(), 0, 0);
                glEnableVertexArrayAttrib(vao.id(), 1);
                glVertexArrayAttribFormat(vao.id(), 1, 4, GL_FLOAT, GL_FALSE, sizeof(glm::vec2));
                glVertexArrayAttribBinding(vao.id(), 1, 0);
                im.overlay.use();
                glUniform2f(im.overlay.uniform("viewport"), float(W), float(H));
                glEnable(GL_BLEND);
                // Colour blends; alpha accumulates so a transparent background keeps annotations opaque.
                glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
                glBindVertexArray(vao.id());
                glDrawArrays(GL_TRIANGLES, 0, GLsizei(verts.size()));
                glBindVertexArray(0);
                glDisable(GL_BLEND);
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
            });
        final_color = ov.color;
    }

    if (opt.present) {
        // Copy the final image into the caller's framebuffer (a widget's).
        struct Present {
            graph::TextureHandle source;
        };
        fg.add_pass<Present>(
            "present",
            [&](graph::FrameGraph::Builder& b, Present& d) {
                d.source = b.read(final_color);
                b.side_effect();
            },
            [&](const Present& d, const graph::Resources& r) {
                auto fb = gl::Framebuffer::create();
                glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, im.backend.texture(r.get(d.source)), 0);
                glNamedFramebufferReadBuffer(fb.id(), GL_COLOR_ATTACHMENT0);
                glBlitNamedFramebuffer(fb.id(), opt.target_framebuffer, 0, 0, W, H, 0, 0, W, H, GL_COLOR_BUFFER_BIT, GL_NEAREST);
            });
        result.stats = fg.execute(im.backend);
        return result;
    }

    // Read-back of what was asked for: the colour image or one AOV. The
    // passes that only the other outputs need are culled by the graph.
    struct Readback {
        graph::TextureHandle source;
    };
    fg.add_pass<Readback>(
        "readback",
        [&](graph::FrameGraph::Builder& b, Readback& d) {
            switch (opt.aov) {
            case Aov::None: d.source = b.read(final_color); break;
            case Aov::Depth: d.source = b.read(gb.depth); break;
            case Aov::Normal: d.source = b.read(gb.normal); break;
            case Aov::Id: d.source = b.read(gb.id); break;
            case Aov::Ao: d.source = b.read(ao_image); break;
            }
            b.side_effect();
        },
        [&](const Readback& d, const graph::Resources& r) {
            const GLuint tex = im.backend.texture(r.get(d.source));
            Image& img = result.image;
            img.width = W;
            img.height = H;
            const std::size_t n = std::size_t(W) * std::size_t(H);
            auto flip_rows = [&](auto& v, int ch) {
                for (int y = 0; y < H / 2; ++y)
                    std::swap_ranges(v.begin() + std::ptrdiff_t(y) * W * ch, v.begin() + std::ptrdiff_t(y + 1) * W * ch,
                                     v.begin() + std::ptrdiff_t(H - 1 - y) * W * ch);
            };
            glPixelStorei(GL_PACK_ALIGNMENT, 1);
            switch (opt.aov) {
            case Aov::None:
                img.channels = 4;
                img.bytes.resize(n * 4);
                glGetTextureImage(tex, 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(img.bytes.size()), img.bytes.data());
                flip_rows(img.bytes, 4);
                break;
            case Aov::Depth: {
                img.channels = 1;
                img.is_float = true;
                img.floats.resize(n);
                glGetTextureImage(tex, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(n * 4), img.floats.data());
                // Distance along the view axis in mm; background (depth 0) is +infinity.
                for (auto& z : img.floats)
                    z = z > 0.0f ? float(camera.linear_depth(z)) : std::numeric_limits<float>::infinity();
                flip_rows(img.floats, 1);
                break;
            }
            case Aov::Normal: {
                std::vector<float> rgba(n * 4);
                glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * 4), rgba.data());
                img.channels = 3;
                img.is_float = true;
                img.floats.resize(n * 3);
                for (std::size_t i = 0; i < n; ++i)
                    for (int c = 0; c < 3; ++c) img.floats[i * 3 + std::size_t(c)] = rgba[i * 4 + std::size_t(c)];
                flip_rows(img.floats, 3);
                break;
            }
            case Aov::Ao: {
                img.channels = 1;
                img.is_float = true;
                img.floats.resize(n);
                glGetTextureImage(tex, 0, GL_RED, GL_FLOAT, GLsizei(n * 4), img.floats.data());
                flip_rows(img.floats, 1); // NaN marks the background
                break;
            }
            case Aov::Id: {
                std::vector<GLuint> ids(n);
                glGetTextureImage(tex, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, GLsizei(n * 4), ids.data());
                img.channels = 1;
                img.is_float = true;
                img.floats.assign(ids.begin(), ids.end());
                flip_rows(img.floats, 1);
                break;
            }
            }
        });
    result.stats = fg.execute(im.backend);
    return result;
}

} // namespace iso
