// One move-only RAII type per GL object kind, created with GL 4.5 direct
// state access. Escape hatches: id() to use the name with raw GL, release()
// to take ownership away, and the explicit constructor from a name to adopt one.
// Include <epoxy/gl.h> (through this header) before any Qt OpenGL header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <epoxy/gl.h>

namespace iso::gl {

template <class Traits> class Object {
public:
    Object() = default;
    explicit Object(GLuint adopt) : id_(adopt) {}
    ~Object() { reset(); }
    Object(const Object&) = delete;
    Object& operator=(const Object&) = delete;
    Object(Object&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
    Object& operator=(Object&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, 0);
        }
        return *this;
    }
    GLuint id() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    GLuint release() { return std::exchange(id_, 0); }
    void reset() {
        if (id_) Traits::destroy(id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

struct BufferTraits {
    static void destroy(GLuint id) { glDeleteBuffers(1, &id); }
};
struct TextureTraits {
    static void destroy(GLuint id) { glDeleteTextures(1, &id); }
};
struct FramebufferTraits {
    static void destroy(GLuint id) { glDeleteFramebuffers(1, &id); }
};
struct VertexArrayTraits {
    static void destroy(GLuint id) { glDeleteVertexArrays(1, &id); }
};
struct ProgramTraits {
    static void destroy(GLuint id) { glDeleteProgram(id); }
};
struct QueryTraits {
    static void destroy(GLuint id) { glDeleteQueries(1, &id); }
};

// A buffer with immutable storage (glNamedBufferStorage).
class Buffer : public Object<BufferTraits> {
public:
    Buffer() = default;
    // `flags`: GL_DYNAMIC_STORAGE_BIT to allow upload(), GL_MAP_READ_BIT, ...
    Buffer(std::size_t bytes, const void* data = nullptr, GLbitfield flags = GL_DYNAMIC_STORAGE_BIT);
    template <class T> static Buffer from(std::span<const T> v, GLbitfield flags = GL_DYNAMIC_STORAGE_BIT) {
        return Buffer(v.size_bytes(), v.data(), flags);
    }
    std::size_t size() const { return size_; }
    void upload(std::size_t offset, std::size_t bytes, const void* data);
    void clear_u32(std::uint32_t value = 0); // fills the whole buffer
    void read(std::size_t offset, std::size_t bytes, void* out) const;
    template <class T> std::vector<T> read_all() const {
        std::vector<T> v(size_ / sizeof(T));
        read(0, v.size() * sizeof(T), v.data());
        return v;
    }
    void bind_base(GLenum target, GLuint index) const { glBindBufferBase(target, index, id()); }

private:
    std::size_t size_ = 0;
};

class Texture : public Object<TextureTraits> {
public:
    Texture() = default;
    // 2D texture with one level of `internal_format` (e.g. GL_RGBA8, GL_DEPTH_COMPONENT32F).
    static Texture create_2d(GLenum internal_format, int width, int height);
    // 2D texture with `levels` mip levels (nearest filtering; a depth pyramid).
    static Texture create_2d_levels(GLenum internal_format, int width, int height, int levels);
    // 2D array texture (layers >= 1), one level, nearest filtering.
    static Texture create_2d_array(GLenum internal_format, int width, int height, int layers);
    // 1D array texture (layers >= 1), one level, nearest filtering.
    static Texture create_1d_array(GLenum internal_format, int width, int layers);
    // 3D texture, one level, nearest filtering.
    static Texture create_3d(GLenum internal_format, int width, int height, int depth);
    // 2D multisample texture (fixed sample locations): `samples` per pixel.
    static Texture create_2d_multisample(GLenum internal_format, int width, int height, int samples);
    int width() const { return w_; }
    int height() const { return h_; }
    int depth() const { return d_; } // layers of an array texture, slices of a 3D one, else 1
    GLenum format() const { return format_; }

private:
    static Texture create(GLenum target, GLenum internal_format, int width, int height, int depth, int levels = 1);
    int w_ = 0, h_ = 0, d_ = 1;
    GLenum format_ = 0;
};

class Framebuffer : public Object<FramebufferTraits> {
public:
    static Framebuffer create();
    void attach(GLenum attachment, const Texture& t) { glNamedFramebufferTexture(id(), attachment, t.id(), 0); }
    // Throws iso::Error when incomplete.
    void check() const;
};

class VertexArray : public Object<VertexArrayTraits> {
public:
    static VertexArray create();
};

// A linked program. Sources come from shaders/ (embedded), with a #define
// block inserted after #version for variants.
class Program : public Object<ProgramTraits> {
public:
    Program() = default;
    // Stage files by name relative to shaders/, e.g. {"iso/mc.comp"}; the
    // stage is taken from the extension. Throws iso::Error with the log.
    static Program from_files(std::initializer_list<std::string> files, const std::string& defines = {});
    GLint uniform(const char* name) const { return glGetUniformLocation(id(), name); }
    void use() const { glUseProgram(id()); }
};

// Source of an embedded shader after #include expansion and #define
// insertion; throws iso::Error when missing.
std::string shader_source(const std::string& name, const std::string& defines = {});

} // namespace iso::gl
