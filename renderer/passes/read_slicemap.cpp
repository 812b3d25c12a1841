// Slicemap read-back (tests, the voxel-grid reference): the bits and the z
// range into RenderResult::slicemap.
#include <algorithm>
#include <cstring>

#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

void read_slicemap(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const AoResources& in) {
    side_effect_pass(fg, "read_slicemap", {{in.slicemap}, {in.zrange}},
                     [&ctx, plan](const Reads& d, const graph::Resources& r) {
                         GlResources& gl = *ctx.gl;
                         SliceMap& sm = ctx.result->slicemap;
                         const int gw = plan->grid_w, gh = plan->grid_h, layers = plan->settings.layers;
                         sm.width = gw;
                         sm.height = gh;
                         sm.layers = layers;
                         sm.view = ctx.camera.view();
                         sm.projection = plan->sm_projection;
                         const std::size_t texels = std::size_t(gw) * std::size_t(gh);
                         std::vector<std::uint32_t> raw(texels * std::size_t(layers) * 4);
                         glGetTextureImage(gl.texture(r, d.textures[0]), 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                                           GLsizei(raw.size() * 4), raw.data());
                         // GL returns layer after layer; SliceMap keeps a texel's layers together.
                         sm.words.resize(raw.size());
                         for (int l = 0; l < layers; ++l)
                             for (std::size_t t = 0; t < texels; ++t)
                                 for (int c = 0; c < 4; ++c)
                                     sm.words[(t * std::size_t(layers) + std::size_t(l)) * 4 + std::size_t(c)] =
                                         raw[(std::size_t(l) * texels + t) * 4 + std::size_t(c)];
                         GLuint bits[2];
                         glGetNamedBufferSubData(gl.buffer(r, d.buffers[0]), 0, 8, bits);
                         float zn, zx;
                         std::memcpy(&zn, &bits[0], 4);
                         std::memcpy(&zx, &bits[1], 4);
                         sm.z_near = std::max(double(zn) - double(plan->near_margin), 0.0);
                         sm.z_far = std::max(double(std::min(plan->scene_far, zx + plan->radius)), sm.z_near + 1e-3);
                     });
}

} // namespace iso::passes
