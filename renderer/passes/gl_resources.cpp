#include "renderer/passes/gl_resources.hpp"

#include "io/error.hpp"

namespace iso::passes {

GLenum gl_format(graph::Format f) {
    switch (f) {
    case graph::Format::RGBA8: return GL_RGBA8;
    case graph::Format::RGBA16F: return GL_RGBA16F;
    case graph::Format::RGBA32F: return GL_RGBA32F;
    case graph::Format::R32F: return GL_R32F;
    case graph::Format::RG16F: return GL_RG16F;
    case graph::Format::R32UI: return GL_R32UI;
    case graph::Format::RG32UI: return GL_RG32UI;
    case graph::Format::RGBA32UI: return GL_RGBA32UI;
    case graph::Format::Depth32F: return GL_DEPTH_COMPONENT32F;
    }
    return GL_RGBA8;
}

std::uint64_t GlResources::create_texture(const graph::TextureDesc& d, const std::string& name) {
    const bool array = d.array || d.layers > 1;
    if (array && d.depth > 1)
        throw Error("GlResources::create_texture", "'" + name + "' asks for both layers and depth");
    if (d.samples > 1 && (array || d.depth > 1))
        throw Error("GlResources::create_texture", "'" + name + "' asks for samples with layers or depth");
    gl::Texture t = d.samples > 1 ? gl::Texture::create_2d_multisample(gl_format(d.format), d.width, d.height, d.samples)
                    : d.depth > 1 ? gl::Texture::create_3d(gl_format(d.format), d.width, d.height, d.depth)
                    : array     ? gl::Texture::create_2d_array(gl_format(d.format), d.width, d.height, d.layers)
                                : gl::Texture::create_2d(gl_format(d.format), d.width, d.height);
    glObjectLabel(GL_TEXTURE, t.id(), GLsizei(name.size()), name.c_str());
    const auto id = next_++;
    textures_.emplace(id, std::move(t));
    ++created_;
    return id;
}

std::uint64_t GlResources::create_buffer(const graph::BufferDesc& d, const std::string& name) {
    gl::Buffer b(d.bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
    glObjectLabel(GL_BUFFER, b.id(), GLsizei(name.size()), name.c_str());
    const auto id = next_++;
    buffers_.emplace(id, std::move(b));
    ++created_;
    return id;
}

void GlResources::destroy(std::uint64_t id) {
    const auto t = textures_.find(id);
    if (t != textures_.end()) {
        // Framebuffers that draw into it go too (GL may reuse the name).
        const GLuint name = t->second.id();
        for (auto it = framebuffers_.begin(); it != framebuffers_.end();) {
            bool uses = it->first.second == name;
            for (const auto& a : it->first.first) uses |= a.texture == name;
            it = uses ? framebuffers_.erase(it) : std::next(it);
        }
        textures_.erase(t);
        return;
    }
    buffers_.erase(id);
}

GLuint GlResources::texture_id(std::uint64_t id) const {
    const auto it = textures_.find(id);
    if (it == textures_.end()) throw Error("GlResources::texture_id", "no texture with id " + std::to_string(id));
    return it->second.id();
}

GLuint GlResources::buffer_id(std::uint64_t id) const {
    const auto it = buffers_.find(id);
    if (it == buffers_.end()) throw Error("GlResources::buffer_id", "no buffer with id " + std::to_string(id));
    return it->second.id();
}

GLuint GlResources::framebuffer(const std::vector<Attachment>& colors, GLuint depth) {
    auto key = std::make_pair(colors, depth);
    auto it = framebuffers_.find(key);
    if (it != framebuffers_.end()) return it->second.id();
    auto fb = gl::Framebuffer::create();
    std::vector<GLenum> bufs;
    for (std::size_t i = 0; i < colors.size(); ++i) {
        const GLenum at = GLenum(GL_COLOR_ATTACHMENT0 + i);
        if (colors[i].layer < 0)
            glNamedFramebufferTexture(fb.id(), at, colors[i].texture, 0);
        else
            glNamedFramebufferTextureLayer(fb.id(), at, colors[i].texture, 0, colors[i].layer);
        bufs.push_back(at);
    }
    if (depth) glNamedFramebufferTexture(fb.id(), GL_DEPTH_ATTACHMENT, depth, 0);
    glNamedFramebufferDrawBuffers(fb.id(), GLsizei(bufs.size()), bufs.data());
    if (!bufs.empty()) glNamedFramebufferReadBuffer(fb.id(), GL_COLOR_ATTACHMENT0);
    fb.check();
    ++created_;
    return framebuffers_.emplace(std::move(key), std::move(fb)).first->second.id();
}

gl::Program& GlResources::program(std::initializer_list<std::string> files, const std::string& defines) {
    std::string key;
    for (const auto& f : files) key += f + ";";
    key += defines;
    auto it = programs_.find(key);
    if (it == programs_.end()) {
        it = programs_.emplace(key, gl::Program::from_files(files, defines)).first;
        ++created_;
    }
    return it->second;
}

GLuint GlResources::vertex_array(const std::string& purpose) {
    auto it = vertex_arrays_.find(purpose);
    if (it == vertex_arrays_.end()) {
        it = vertex_arrays_.emplace(purpose, gl::VertexArray::create()).first;
        ++created_;
    }
    return it->second.id();
}

} // namespace iso::passes
