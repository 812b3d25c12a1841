// RAII GL wrappers on a real context: moving transfers ownership, the
// moved-from object owns nothing, destruction deletes the GL object; shader
// errors name the file; and the GL test fixture itself fails a test that
// leaves a GL error behind.
#include "renderer/gl/objects.hpp"

#include <gtest/gtest-spi.h>

#include "gl_test.hpp"
#include "io/error.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using GlObjects = test::GlTest;
using GlFixture = test::GlTest;

TEST_F(GlObjects, BufferMoveAndDestroy) {
    GLuint name = 0;
    {
        const std::uint32_t data[4] = {1, 2, 3, 4};
        gl::Buffer a(sizeof data, data, GL_DYNAMIC_STORAGE_BIT);
        name = a.id();
        ASSERT_TRUE(glIsBuffer(name));
        gl::Buffer b = std::move(a);
        EXPECT_EQ(a.id(), 0u);
        EXPECT_EQ(b.id(), name);
        EXPECT_EQ(b.read_all<std::uint32_t>(), (std::vector<std::uint32_t>{1, 2, 3, 4}));
        gl::Buffer c;
        c = std::move(b);
        EXPECT_EQ(c.id(), name);
        EXPECT_TRUE(glIsBuffer(name));
    }
    EXPECT_FALSE(glIsBuffer(name)) << "destroyed with its last owner";
}

TEST_F(GlObjects, TextureFramebufferProgramLifetimes) {
    GLuint tex = 0, fbo = 0, prog = 0;
    {
        auto t = gl::Texture::create_2d(GL_RGBA8, 8, 4);
        EXPECT_EQ(t.width(), 8);
        auto f = gl::Framebuffer::create();
        f.attach(GL_COLOR_ATTACHMENT0, t);
        EXPECT_NO_THROW(f.check());
        auto p = gl::Program::from_files({"render/overlay.vert", "render/overlay.frag"});
        tex = t.id();
        fbo = f.id();
        prog = p.id();
        EXPECT_TRUE(glIsTexture(tex) && glIsFramebuffer(fbo) && glIsProgram(prog));
        // release() hands ownership out: the object survives this scope.
        GLuint kept = gl::Texture::create_2d(GL_R32F, 2, 2).release();
        EXPECT_TRUE(glIsTexture(kept));
        glDeleteTextures(1, &kept);
    }
    EXPECT_FALSE(glIsTexture(tex));
    EXPECT_FALSE(glIsFramebuffer(fbo));
    EXPECT_FALSE(glIsProgram(prog));
}

TEST_F(GlObjects, ShaderErrorsNameTheFile) {
    try {
        gl::Program::from_files({"no/such.comp"});
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no/such.comp"), std::string::npos);
    }
    // A variant that does not compile reports the log with the file name. The
    // log must be that of our #error (a real newline puts it on its own
    // line), not of some other compile error.
    try {
        gl::Program::from_files({"iso/mc.comp"}, "#define PASS 1\n#error deliberate");
        FAIL();
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("iso/mc.comp"), std::string::npos) << what;
        EXPECT_NE(what.find("deliberate"), std::string::npos) << what;
    }
    // A driver may also report the failed compile as a GL debug error
    // (llvmpipe does not): expected here, so taken before the fixture checks.
    test::take_gl_errors();
}

namespace {
// Runs the fixture's end-of-test check on demand.
struct FixtureProbe : test::GlTest {
    void TestBody() override {}
    using test::GlTest::TearDown;
};
} // namespace

TEST_F(GlFixture, FailsATestThatLeavesAGlError) {
    const GLenum bogus_target = 0xDEAD;
    // 1. Through GL_KHR_debug: the bad call is counted in the debug log.
    ASSERT_EQ(gl::debug_log().errors(), 0u);
    glBindTexture(bogus_target, 0);
    EXPECT_EQ(gl::debug_log().errors(), 1u);
    ASSERT_FALSE(gl::debug_log().messages().empty());
    EXPECT_NE(gl::debug_log().messages().back().find("GL error"), std::string::npos)
        << gl::debug_log().messages().back();
    EXPECT_EQ(glGetError(), GLenum(GL_INVALID_ENUM)); // taken: only the debug log still has it
    {
        FixtureProbe probe;
        EXPECT_NONFATAL_FAILURE(probe.TearDown(), "GL debug errors: 1");
    }
    EXPECT_EQ(gl::debug_log().errors(), 0u) << "the check forgets what it reported";
    // 2. Through glGetError() alone (debug output off, as in a non-debug context).
    glDisable(GL_DEBUG_OUTPUT);
    glBindTexture(bogus_target, 0);
    glEnable(GL_DEBUG_OUTPUT);
    EXPECT_EQ(gl::debug_log().errors(), 0u);
    {
        FixtureProbe probe;
        EXPECT_NONFATAL_FAILURE(probe.TearDown(), "glGetError: 0x500");
    }
    // 3. Clearing by hand: what a test that provokes an error on purpose does.
    glBindTexture(bogus_target, 0);
    const auto taken = test::take_gl_errors();
    EXPECT_EQ(taken.debug_errors, 1u);
    EXPECT_EQ(taken.get_error_codes, "0x500 ");
    EXPECT_EQ(gl::debug_log().errors(), 0u);
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    // Nothing left: this test passes.
}
