// RAII GL wrappers on a real context: moving transfers ownership, the
// moved-from object owns nothing, destruction deletes the GL object.
#include "renderer/gl/objects.hpp"

#include "io/error.hpp"
#include "renderer/gl/context.hpp"
#include "test_util.hpp"

using namespace iso;

namespace {
gl::HeadlessContext& context() {
    static gl::HeadlessContext ctx(true);
    return ctx;
}
} // namespace

TEST(GlObjects, BufferMoveAndDestroy) {
    context();
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

TEST(GlObjects, TextureFramebufferProgramLifetimes) {
    context();
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

TEST(GlObjects, ShaderErrorsNameTheFile) {
    context();
    try {
        gl::Program::from_files({"no/such.comp"});
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no/such.comp"), std::string::npos);
    }
    // A variant that does not compile reports the log with the file name.
    try {
        gl::Program::from_files({"iso/mc.comp"}, "#define PASS 1\\n#error deliberate");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("iso/mc.comp"), std::string::npos) << e.what();
    }
}
