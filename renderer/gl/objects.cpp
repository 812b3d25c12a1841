#include "renderer/gl/objects.hpp"

#include <cstring>
#include <sstream>

#include "io/error.hpp"

namespace iso::gl {

const char* embedded_shader(std::string_view name); // generated: shaders/embed.cmake

Buffer::Buffer(std::size_t bytes, const void* data, GLbitfield flags) : size_(bytes) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    static_cast<Object<BufferTraits>&>(*this) = Object<BufferTraits>(id);
    glNamedBufferStorage(id, GLsizeiptr(bytes ? bytes : 4), data, flags);
}

void Buffer::upload(std::size_t offset, std::size_t bytes, const void* data) {
    glNamedBufferSubData(id(), GLintptr(offset), GLsizeiptr(bytes), data);
}

void Buffer::clear_u32(std::uint32_t value) {
    glClearNamedBufferData(id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &value);
}

void Buffer::read(std::size_t offset, std::size_t bytes, void* out) const {
    glGetNamedBufferSubData(id(), GLintptr(offset), GLsizeiptr(bytes), out);
}

// One level, nearest filtering, clamped: what the passes sample.
Texture Texture::create(GLenum target, GLenum internal_format, int width, int height, int depth, int levels) {
    GLuint id = 0;
    glCreateTextures(target, 1, &id);
    Texture t;
    static_cast<Object<TextureTraits>&>(t) = Object<TextureTraits>(id);
    if (target == GL_TEXTURE_2D || target == GL_TEXTURE_1D_ARRAY)
        glTextureStorage2D(id, levels, internal_format, width, height);
    else
        glTextureStorage3D(id, 1, internal_format, width, height, depth);
    // A texture with levels is read level by level (texelFetch): its
    // filter must be a mipmap one for the levels above 0 to count.
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, levels > 1 ? GL_NEAREST_MIPMAP_NEAREST : GL_NEAREST);
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(id, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    t.w_ = width;
    t.h_ = height;
    t.d_ = depth;
    t.format_ = internal_format;
    return t;
}

Texture Texture::create_1d_array(GLenum internal_format, int width, int layers) {
    Texture t = create(GL_TEXTURE_1D_ARRAY, internal_format, width, layers, 1);
    t.h_ = 1;
    t.d_ = layers;
    return t;
}

Texture Texture::create_2d(GLenum internal_format, int width, int height) {
    return create(GL_TEXTURE_2D, internal_format, width, height, 1);
}

Texture Texture::create_2d_levels(GLenum internal_format, int width, int height, int levels) {
    return create(GL_TEXTURE_2D, internal_format, width, height, 1, levels);
}

Texture Texture::create_2d_array(GLenum internal_format, int width, int height, int layers) {
    return create(GL_TEXTURE_2D_ARRAY, internal_format, width, height, layers);
}

Texture Texture::create_3d(GLenum internal_format, int width, int height, int depth) {
    return create(GL_TEXTURE_3D, internal_format, width, height, depth);
}

Texture Texture::create_2d_multisample(GLenum internal_format, int width, int height, int samples) {
    GLuint id = 0;
    glCreateTextures(GL_TEXTURE_2D_MULTISAMPLE, 1, &id);
    Texture t;
    static_cast<Object<TextureTraits>&>(t) = Object<TextureTraits>(id);
    glTextureStorage2DMultisample(id, samples, internal_format, width, height, GL_TRUE);
    t.w_ = width;
    t.h_ = height;
    t.format_ = internal_format;
    return t;
}

Framebuffer Framebuffer::create() {
    GLuint id = 0;
    glCreateFramebuffers(1, &id);
    Framebuffer f;
    static_cast<Object<FramebufferTraits>&>(f) = Object<FramebufferTraits>(id);
    return f;
}

void Framebuffer::check() const {
    const GLenum s = glCheckNamedFramebufferStatus(id(), GL_FRAMEBUFFER);
    if (s != GL_FRAMEBUFFER_COMPLETE) {
        std::ostringstream os;
        os << "framebuffer incomplete (status 0x" << std::hex << s << ")";
        throw Error("OpenGL", os.str());
    }
}

VertexArray VertexArray::create() {
    GLuint id = 0;
    glCreateVertexArrays(1, &id);
    VertexArray v;
    static_cast<Object<VertexArrayTraits>&>(v) = Object<VertexArrayTraits>(id);
    return v;
}

namespace {

std::string expand(const std::string& name, int depth) {
    if (depth > 8) throw Error(name, "shader #include nesting too deep");
    const char* text = embedded_shader(name);
    if (!text) throw Error(name, "no such shader (is it under shaders/?)");
    std::istringstream in(text);
    std::ostringstream out;
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("#extension GL_GOOGLE_include_directive", 0) == 0) {
            out << "\n"; // keeps line numbers; only glslangValidator needs it
            continue;
        }
        if (line.rfind("#include \"", 0) == 0) {
            const auto end = line.find('"', 10);
            std::string inc = line.substr(10, end - 10);
            const auto slash = name.rfind('/');
            if (slash != std::string::npos && !embedded_shader(inc)) inc = name.substr(0, slash + 1) + inc;
            out << expand(inc, depth + 1) << "\n";
            continue;
        }
        out << line << "\n";
    }
    return out.str();
}

// The info log of a shader or program (glGetShaderiv/glGetShaderInfoLog or
// glGetProgramiv/glGetProgramInfoLog).
template <class GetIv, class GetLog> std::string info_log(GLuint id, GetIv get_iv, GetLog get_log) {
    GLint len = 0;
    get_iv(id, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    get_log(id, len, nullptr, log.data());
    return log;
}

GLenum stage_of(const std::string& name) {
    auto ends = [&](const char* s) {
        return name.size() > std::strlen(s) && name.compare(name.size() - std::strlen(s), std::string::npos, s) == 0;
    };
    if (ends(".comp")) return GL_COMPUTE_SHADER;
    if (ends(".vert")) return GL_VERTEX_SHADER;
    if (ends(".frag")) return GL_FRAGMENT_SHADER;
    if (ends(".geom")) return GL_GEOMETRY_SHADER;
    throw Error(name, "unknown shader stage (expected .comp, .vert, .frag or .geom)");
}

} // namespace

std::string shader_source(const std::string& name, const std::string& defines) {
    std::string src = expand(name, 0);
    if (!defines.empty()) {
        const auto nl = src.find('\n');
        src.insert(nl == std::string::npos ? src.size() : nl + 1, defines + "\n#line 2\n");
    }
    return src;
}

Program Program::from_files(std::initializer_list<std::string> files, const std::string& defines) {
    const GLuint prog = glCreateProgram();
    Program p;
    static_cast<Object<ProgramTraits>&>(p) = Object<ProgramTraits>(prog);
    std::vector<GLuint> shaders;
    for (const auto& f : files) {
        const std::string src = shader_source(f, defines);
        const GLuint sh = glCreateShader(stage_of(f));
        const char* text = src.c_str();
        glShaderSource(sh, 1, &text, nullptr);
        glCompileShader(sh);
        GLint ok = 0;
        glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
        if (!ok) {
            const std::string log = info_log(sh, glGetShaderiv, glGetShaderInfoLog);
            glDeleteShader(sh);
            for (auto s : shaders) glDeleteShader(s);
            throw Error(f, "shader does not compile:\n" + log);
        }
        glAttachShader(prog, sh);
        shaders.push_back(sh);
    }
    glLinkProgram(prog);
    for (auto s : shaders) {
        glDetachShader(prog, s);
        glDeleteShader(s);
    }
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        const std::string log = info_log(prog, glGetProgramiv, glGetProgramInfoLog);
        std::string names;
        for (const auto& f : files) names += (names.empty() ? "" : ", ") + f;
        throw Error(names, "program does not link:\n" + log);
    }
    return p;
}

} // namespace iso::gl
