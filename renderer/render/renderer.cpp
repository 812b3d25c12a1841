#include "renderer/render/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include <glm/glm.hpp>

#include "io/error.hpp"
#include "renderer/gl/objects.hpp"
#include "renderer/render/overlay.hpp"

namespace iso {

Aov aov_from_name(const std::string& n) {
    if (n == "depth") return Aov::Depth;
    if (n == "normal") return Aov::Normal;
    if (n == "id") return Aov::Id;
    if (n.empty() || n == "none") return Aov::None;
    throw Error("--aov", "unknown AOV '" + n + "' (depth, normal, id)");
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
    gl::VertexArray empty_vao = gl::VertexArray::create();
    GlBackend backend;
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

    struct Lit {
        graph::TextureHandle color;
    };
    const auto& lit = fg.add_pass<Lit>(
        "lighting",
        [&](graph::FrameGraph::Builder& b, Lit& d) {
            b.read(gb.normal);
            b.read(gb.albedo);
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
