// Cone AO: traces equal-measure cones through the slicemap (compute), into a
// history image that accumulates new jitter sets while nothing changes.
#include "io/error.hpp"
#include "renderer/passes/frame.hpp"
#include "renderer/passes/gl_resources.hpp"

namespace iso::passes {

graph::TextureHandle cone_ao(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const GBuffer& gb,
                             const AoResources& in, graph::TextureHandle target) {
    struct Data {
        graph::TextureHandle depth, normal, slicemap, ao;
        graph::BufferHandle range, pattern;
    };
    return fg.add_pass<Data>(
                 "cone_ao",
                 [&](graph::FrameGraph::Builder& b, Data& d) {
                     d.depth = b.read(gb.depth);
                     d.normal = b.read(gb.normal);
                     d.slicemap = b.read(in.slicemap);
                     d.range = b.read(in.zrange);
                     d.pattern = b.write(b.create("cone_pattern", graph::BufferDesc{plan->pattern_bytes}));
                     d.ao = b.write(target);
                 },
                 [&ctx, plan](const Data& d, const graph::Resources& r) {
                     GlResources& gl = *ctx.gl;
                     const ConeAoSettings& st = plan->settings;
                     AoHistory& S = *ctx.ao;
                     // A new slicemap, new settings or a new image restart the accumulation.
                     if (plan->voxelize || r.fresh(d.ao) || !(st == S.settings) || !st.temporal) S.frames = 0;
                     S.settings = st;
                     const std::uint32_t frame = std::uint32_t(S.frames);
                     const float history_weight = float(frame) / float(frame + 1);
                     ctx.result->ao_frames = ++S.frames;
                     ctx.result->ao_guard = plan->guard;
                     // This frame's cones and jitter sets (new sets for each still frame).
                     const auto pattern = cone_pattern(st, frame);
                     if (pattern.size() * sizeof(glm::vec4) != plan->pattern_bytes)
                         throw Error("cone_ao pass", "pattern of " + std::to_string(pattern.size()) + " vec4s does not fit its buffer");
                     glNamedBufferSubData(gl.buffer(r, d.pattern), 0, GLsizeiptr(pattern.size() * sizeof(glm::vec4)), pattern.data());
                     auto& prog = gl.program({"ao/cone.comp"},
                                             "#define LAYERS " + std::to_string(st.layers) + "\n" + (plan->coarse ? "#define COARSE 1\n" : ""));
                     prog.use();
                     glBindTextureUnit(0, gl.texture(r, d.depth));
                     glBindTextureUnit(1, gl.texture(r, d.normal));
                     glBindTextureUnit(2, gl.texture(r, d.slicemap));
                     glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.range));
                     glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.pattern));
                     glBindImageTexture(0, gl.texture(r, d.ao), 0, GL_FALSE, 0, GL_READ_WRITE, plan->coarse ? GL_RGBA32F : GL_R32F);
                     glUniformMatrix3fv(prog.uniform("world_to_view"), 1, GL_FALSE, &ctx.world_to_view[0][0]);
                     glUniform2f(prog.uniform("proj_scale"), plan->proj_scale.x, plan->proj_scale.y);
                     glUniform2f(prog.uniform("sm_proj_scale"), plan->sm_scale.x * plan->proj_scale.x, plan->sm_scale.y * plan->proj_scale.y);
                     glUniform1f(prog.uniform("near_plane"), plan->near_plane);
                     glUniform1f(prog.uniform("far_plane"), plan->far_plane);
                     glUniform1f(prog.uniform("scene_far"), plan->scene_far);
                     glUniform1f(prog.uniform("near_margin"), plan->near_margin);
                     glUniform2i(prog.uniform("size"), ctx.width, ctx.height);
                     glUniform2i(prog.uniform("ao_size"), plan->ao_w, plan->ao_h);
                     glUniform2i(prog.uniform("grid"), plan->grid_w, plan->grid_h);
                     glUniform1f(prog.uniform("radius"), plan->radius);
                     glUniform1f(prog.uniform("strength"), float(st.strength));
                     glUniform1f(prog.uniform("persistence"), float(st.persistence));
                     glUniform1f(prog.uniform("attenuation"), float(st.attenuation));
                     glUniform1f(prog.uniform("bias"), float(st.bias));
                     glUniform1f(prog.uniform("ray_weight"), float(st.ray_weight));
                     glUniform1i(prog.uniform("cones"), st.cones);
                     glUniform1i(prog.uniform("spheres"), st.spheres);
                     glUniform1i(prog.uniform("samples"), st.samples);
                     glUniform1i(prog.uniform("sets"), st.jitter_sets);
                     glUniform1f(prog.uniform("history_weight"), history_weight);
                     glDispatchCompute(GLuint((plan->ao_w + 7) / 8), GLuint((plan->ao_h + 7) / 8), 1);
                     glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
                 })
        .ao;
}

} // namespace iso::passes
