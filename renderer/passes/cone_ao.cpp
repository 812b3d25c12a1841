// Cone AO: traces equal-measure cones through the slicemap (compute), into a
// history image that accumulates new jitter sets while nothing changes.
#include "io/error.hpp"
#include "renderer/ao/cone_pattern.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

ConeTrace cone_ao(graph::FrameGraph& fg, const FrameContext& ctx, const AoPlanRef& plan, const GBuffer& gb,
                  const AoResources& in, graph::TextureHandle target) {
    struct Data {
        graph::TextureHandle depth, normal, slicemap, ao;
        graph::BufferHandle range, pattern, params;
    };
    const Data& out = fg.add_pass<Data>(
        "cone_ao",
        [&](graph::FrameGraph::Builder& b, Data& d) {
            d.depth = b.read(gb.depth);
            d.normal = b.read(gb.normal);
            d.slicemap = b.read(in.slicemap);
            d.range = b.read(in.zrange);
            d.pattern = b.write(b.create("cone_pattern", graph::BufferDesc{plan->pattern_bytes}));
            d.ao = b.write(target);
            d.params = params_buffer<ConeParams>(b, "cone_params");
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
                throw Error("cone_ao pass",
                            "pattern of " + std::to_string(pattern.size()) + " vec4s does not fit its buffer");
            glNamedBufferSubData(gl.buffer(r, d.pattern), 0, GLsizeiptr(pattern.size() * sizeof(glm::vec4)),
                                 pattern.data());
            auto& prog = gl.program({"ao/cone.comp"}, "#define LAYERS " + std::to_string(st.layers) + "\n" +
                                                          (plan->coarse ? "#define COARSE 1\n" : ""));
            prog.use();
            glBindTextureUnit(0, gl.texture(r, d.depth));
            glBindTextureUnit(1, gl.texture(r, d.normal));
            glBindTextureUnit(2, gl.texture(r, d.slicemap));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gl.buffer(r, d.range));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gl.buffer(r, d.pattern));
            glBindImageTexture(0, gl.texture(r, d.ao), 0, GL_FALSE, 0, GL_READ_WRITE,
                               plan->coarse ? GL_RGBA32F : GL_R32F);
            ConeParams p;
            p.world_to_view = std140::mat3(ctx.world_to_view);
            p.proj_scale = plan->proj_scale;
            p.sm_proj_scale = plan->sm_scale * plan->proj_scale;
            p.size = {ctx.width, ctx.height};
            p.grid = {plan->grid_w, plan->grid_h};
            p.ao_size = {plan->ao_w, plan->ao_h};
            p.near_plane = plan->near_plane;
            p.far_plane = plan->far_plane;
            p.scene_far = plan->scene_far;
            p.near_margin = plan->near_margin;
            p.radius = plan->radius;
            p.strength = float(st.strength);
            p.persistence = float(st.persistence);
            p.attenuation = float(st.attenuation);
            p.bias = float(st.bias);
            p.ray_weight = float(st.ray_weight);
            p.axis_weight = float(st.axis_weight);
            p.history_weight = history_weight;
            p.cones = st.cones;
            p.spheres = st.spheres;
            p.samples = st.samples;
            p.sets = st.jitter_sets;
            bind_params(gl, r, d.params, p);
            glDispatchCompute(GLuint((plan->ao_w + 7) / 8), GLuint((plan->ao_h + 7) / 8), 1);
            glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                            GL_TEXTURE_UPDATE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        });
    return {out.ao, out.pattern, out.params};
}

} // namespace iso::passes
