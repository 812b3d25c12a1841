// Present: copies the final image into the caller's framebuffer (a widget's).
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

void present(graph::FrameGraph& fg, const FrameContext& ctx, graph::TextureHandle color) {
    side_effect_pass(fg, "present", {{color}, {}}, [&ctx](const Reads& d, const graph::Resources& r) {
        GlResources& gl = *ctx.gl;
        const GLuint fb = gl.framebuffer({{gl.texture(r, d.textures[0])}});
        const int W = ctx.width, H = ctx.height;
        glBlitNamedFramebuffer(fb, ctx.opt.target_framebuffer, 0, 0, W, H, 0, 0, W, H, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    });
}

} // namespace iso::passes
