// The GL side of one renderer's frames: the pass graph's textures and
// buffers as RAII GL objects (a graph::Backend under the graph's
// ResourcePool), plus what passes reuse across frames without the graph:
// framebuffers cached by attachments, vertex arrays and programs. After the
// first frame of a steady view nothing here creates a GL object:
// objects_created() counts them for the tests.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "renderer/gl/objects.hpp"
#include "renderer/graph/frame_graph.hpp"

namespace iso::passes {

GLenum gl_format(graph::Format f);

class GlResources : public graph::Backend {
public:
    std::uint64_t create_texture(const graph::TextureDesc& d, const std::string& name) override;
    std::uint64_t create_buffer(const graph::BufferDesc& d, const std::string& name) override;
    void destroy(std::uint64_t id) override;

    // The GL names behind graph handles (asserts the resource exists).
    GLuint texture(const graph::Resources& r, graph::TextureHandle h) const { return texture_id(r.get(h)); }
    GLuint buffer(const graph::Resources& r, graph::BufferHandle h) const { return buffer_id(r.get(h)); }
    GLuint texture_id(std::uint64_t id) const;
    GLuint buffer_id(std::uint64_t id) const;

    // A complete framebuffer drawing into these colour attachments (a whole
    // texture, or one layer of an array texture) and depth texture (0: none),
    // made once and kept while its textures live.
    struct Attachment {
        GLuint texture = 0;
        int layer = -1; // -1: the whole texture
        auto operator<=>(const Attachment&) const = default;
    };
    GLuint framebuffer(const std::vector<Attachment>& colors, GLuint depth = 0);

    // A program made once per key (shader files and #defines).
    gl::Program& program(std::initializer_list<std::string> files, const std::string& defines = {});
    // Vertex arrays kept for the life of the renderer (full-screen passes, overlay).
    GLuint vertex_array(const std::string& purpose);

    // GL objects made so far: textures, buffers, framebuffers, vertex arrays, programs.
    std::size_t objects_created() const { return created_; }

private:
    std::uint64_t next_ = 1;
    std::map<std::uint64_t, gl::Texture> textures_;
    std::map<std::uint64_t, gl::Buffer> buffers_;
    std::map<std::pair<std::vector<Attachment>, GLuint>, gl::Framebuffer> framebuffers_;
    std::map<std::string, gl::Program> programs_;
    std::map<std::string, gl::VertexArray> vertex_arrays_;
    std::size_t created_ = 0;
};

// A pass's parameter block (renderer/passes/std140.hpp): declared in setup
// as a graph buffer, filled and bound in execute.
template <class P> graph::BufferHandle params_buffer(graph::FrameGraph::Builder& b, const char* name) {
    return b.write(b.create(name, graph::BufferDesc{sizeof(P)}));
}
template <class P>
void bind_params(const GlResources& gl, const graph::Resources& r, graph::BufferHandle h, const P& p) {
    const GLuint buf = gl.buffer(r, h);
    glNamedBufferSubData(buf, 0, sizeof(P), &p);
    glBindBufferBase(GL_UNIFORM_BUFFER, P::binding, buf);
}

} // namespace iso::passes
