// The GL test fixture (after Magnum's OpenGLTester): one shared headless
// debug context per test program, made current before each test; after each
// test, a GL error (glGetError) or a GL_KHR_debug message of type ERROR that
// the test left behind fails it, with the messages in the failure.
//
//   using Render = iso::test::GlTest;   // keeps the suite's name
//   TEST_F(Render, Something) { ... }
//
// A test that provokes errors on purpose takes them with take_gl_errors()
// (which also forgets them), so only unexpected ones fail it.
#pragma once

#include <cstdlib>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "renderer/gl/context.hpp"
#include "renderer/gl/objects.hpp"

namespace iso::test {

// The shared context: a debug context, so every GL error reaches
// gl::debug_log(). ISOSCOPE_GL_DEBUG is set first so that the context
// core::render_image() (and render_input) makes for itself (renderer/core/api.cpp) is a debug
// context too and reports to the same log. Messages are not echoed to stderr:
// the fixture reports them in the failure instead.
inline gl::HeadlessContext& gl_context() {
    static const bool configured = [] {
        ::setenv("ISOSCOPE_GL_DEBUG", "1", /*overwrite=*/0);
        gl::debug_log().set_echo(false);
        return true;
    }();
    (void)configured;
    static gl::HeadlessContext ctx(/*debug=*/true);
    return ctx;
}

// GL errors recorded since the last call, by both channels.
struct GlErrors {
    std::size_t debug_errors = 0; // GL_KHR_debug messages of type ERROR
    std::string debug_messages;   // the last few messages, one a line
    std::string get_error_codes;  // glGetError() codes, e.g. "0x500 "
    bool any() const { return debug_errors > 0 || !get_error_codes.empty(); }
};

// Reads and clears glGetError() on the current context and the debug log.
inline GlErrors take_gl_errors() {
    GlErrors e;
    std::ostringstream codes;
    // glGetError() returns one recorded flag per call; a context has a handful at most.
    for (int n = 0; n < 16; ++n) {
        const GLenum code = glGetError();
        if (code == GL_NO_ERROR) break;
        codes << "0x" << std::hex << code << " ";
    }
    e.get_error_codes = codes.str();
    e.debug_errors = gl::debug_log().errors();
    for (const auto& m : gl::debug_log().messages()) e.debug_messages += m + "\n";
    gl::debug_log().clear();
    return e;
}

class GlTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() { gl_context(); }

    void SetUp() override {
        gl_context().make_current();
        take_gl_errors(); // whatever an earlier test or suite set-up left is not this test's
    }

    void TearDown() override {
        // The test may have left another context current (core::render_image
        // makes its own): check that one, then the shared one.
        GlErrors e = take_gl_errors();
        gl_context().make_current();
        const GlErrors shared = take_gl_errors();
        e.debug_errors += shared.debug_errors;
        e.debug_messages += shared.debug_messages;
        e.get_error_codes += shared.get_error_codes;
        // One failure whatever went wrong, with both channels' figures.
        if (e.any())
            ADD_FAILURE() << "GL errors left by the test (GL debug errors: " << e.debug_errors
                          << "; glGetError: " << (e.get_error_codes.empty() ? "none" : e.get_error_codes) << ")\n"
                          << e.debug_messages;
    }
};

} // namespace iso::test
