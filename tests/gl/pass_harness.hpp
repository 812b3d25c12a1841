// Exact read-back harness for compute passes (after Falcor's
// Tests/Core/BufferTests.cpp): tiny textures and storage buffers with known
// contents, one compute program from shaders/, one dispatch, and the results
// read back as they are, so a test can hold a shader to hand-derived values
// bit for bit. Needs a current context (tests/gl/gl_test.hpp).
//
//   test::ComputePass pass({"ao/zrange.comp"});
//   pass.texture(0, depth).storage<std::uint32_t>(0, {0x7F800000u, 0u}).set("size", glm::ivec2(5, 3));
//   pass.dispatch(1, 1);
//   const auto out = pass.read<std::uint32_t>(0);
#pragma once

#include <initializer_list>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <gtest/gtest.h>

#include "renderer/gl/objects.hpp"

namespace iso::test {

// A one-level 2D texture of `internal_format` holding `texels` (rows from
// y = 0; `format` and `type` as glTextureSubImage2D takes them, e.g.
// GL_DEPTH_COMPONENT, GL_FLOAT), rows tightly packed: width x height texels.
template <class T>
gl::Texture texture_2d(GLenum internal_format, int width, int height, GLenum format, GLenum type,
                       const std::vector<T>& texels) {
    auto t = gl::Texture::create_2d(internal_format, width, height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(t.id(), 0, 0, 0, width, height, format, type, texels.data());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    return t;
}

// Level 0 of a 2D texture as `format`/`type`, `components` values per texel.
template <class T> std::vector<T> read_texture(const gl::Texture& t, GLenum format, GLenum type, int components = 1) {
    std::vector<T> out(std::size_t(t.width()) * std::size_t(t.height()) * std::size_t(components));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(t.id(), 0, format, type, GLsizei(out.size() * sizeof(T)), out.data());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    return out;
}

// One compute program with its inputs and storage buffers.
class ComputePass {
public:
    explicit ComputePass(std::initializer_list<std::string> files, const std::string& defines = {})
        : program_(gl::Program::from_files(files, defines)) {}

    // Uniforms by name. A name the program lacks fails the test: a typo, or a
    // uniform the compiler removed, would otherwise be ignored silently.
    ComputePass& set(const char* name, int v) {
        return uniform(name, [&](GLint l) { glProgramUniform1i(program_.id(), l, v); });
    }
    ComputePass& set(const char* name, float v) {
        return uniform(name, [&](GLint l) { glProgramUniform1f(program_.id(), l, v); });
    }
    ComputePass& set(const char* name, glm::ivec2 v) {
        return uniform(name, [&](GLint l) { glProgramUniform2i(program_.id(), l, v.x, v.y); });
    }
    ComputePass& set(const char* name, glm::vec2 v) {
        return uniform(name, [&](GLint l) { glProgramUniform2f(program_.id(), l, v.x, v.y); });
    }

    // A pass's parameter block (renderer/passes/std140.hpp) as a uniform
    // buffer at its binding. A block the program lacks fails the test.
    template <class P> ComputePass& params(const P& p) {
        if (glGetProgramResourceIndex(program_.id(), GL_UNIFORM_BLOCK, P::name) == GL_INVALID_INDEX)
            ADD_FAILURE() << "the program has no uniform block '" << P::name << "'";
        uniform_buffers_[P::binding] = gl::Buffer(sizeof(P), &p, 0);
        return *this;
    }

    // A texture on a texture unit (the shader's `layout(binding = unit)`); not owned.
    ComputePass& texture(GLuint unit, const gl::Texture& t) {
        textures_.emplace_back(unit, t.id());
        return *this;
    }

    // A shader storage buffer at `binding` holding `initial`, owned by the pass.
    template <class T> ComputePass& storage(GLuint binding, const std::vector<T>& initial) {
        buffers_[binding] = gl::Buffer(initial.size() * sizeof(T), initial.data(), GL_DYNAMIC_STORAGE_BIT);
        return *this;
    }

    // Runs the program over groups_x x groups_y x groups_z workgroups and
    // waits for its writes to be visible to read().
    void dispatch(GLuint groups_x, GLuint groups_y = 1, GLuint groups_z = 1) {
        program_.use();
        for (const auto& [unit, tex] : textures_) glBindTextureUnit(unit, tex);
        for (const auto& [binding, buf] : buffers_) buf.bind_base(GL_SHADER_STORAGE_BUFFER, binding);
        for (const auto& [binding, buf] : uniform_buffers_) buf.bind_base(GL_UNIFORM_BUFFER, binding);
        glDispatchCompute(groups_x, groups_y, groups_z);
        glMemoryBarrier(GL_ALL_BARRIER_BITS);
        glUseProgram(0);
    }

    // The storage buffer at `binding`, whole.
    template <class T> std::vector<T> read(GLuint binding) const {
        const auto it = buffers_.find(binding);
        if (it == buffers_.end()) {
            ADD_FAILURE() << "no storage buffer at binding " << binding;
            return {};
        }
        return it->second.read_all<T>();
    }

    const gl::Program& program() const { return program_; }

private:
    template <class F> ComputePass& uniform(const char* name, F&& set_it) {
        const GLint loc = program_.uniform(name);
        if (loc < 0)
            ADD_FAILURE() << "the program has no active uniform '" << name << "'";
        else
            set_it(loc);
        return *this;
    }

    gl::Program program_;
    std::map<GLuint, gl::Buffer> buffers_, uniform_buffers_;
    std::vector<std::pair<GLuint, GLuint>> textures_;
};

} // namespace iso::test
