// Volume ray casting (docs/volume.md; shaders/render/volume_march.glsl):
// the pass that composites the volume over the lit opaque image when no
// translucent surface is drawn, and the bindings the VOIT resolve shares
// when it marches the volume between its fragments.
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "renderer/ao/sequences.hpp"
#include "renderer/passes/build_frame.hpp"
#include "renderer/passes/gl_resources.hpp"
#include "renderer/passes/std140.hpp"

namespace iso::passes {

namespace {

constexpr std::size_t kClipSlots = 16;       // clip_planes[16] in volume_march.glsl (and clip.glsl)
constexpr std::size_t kCounterBytes = 4 * 4; // VolumeCounters

// The frame's clip as the shaders take it: half-spaces (normal, offset), at most kClipSlots.
std::vector<glm::vec4> clip_planes(const FrameContext& ctx) {
    std::vector<glm::vec4> planes;
    for (const auto& h : ctx.opt.look.clip.half_spaces())
        if (planes.size() < kClipSlots) planes.push_back(glm::vec4(glm::vec3(h.normal), float(h.offset)));
    return planes;
}

// The tables buffer: the clip's half-spaces, the transfer function's tables.
std::vector<glm::vec4> volume_tables(const FrameContext& ctx) {
    std::vector<glm::vec4> t(kClipSlots, glm::vec4(0.0f));
    const auto planes = clip_planes(ctx);
    std::copy(planes.begin(), planes.end(), t.begin());
    const auto& tb = *ctx.volume->tables;
    t.insert(t.end(), tb.classification().begin(), tb.classification().end());
    t.insert(t.end(), tb.integrals().begin(), tb.integrals().end());
    return t;
}

std::size_t tables_bytes() { return (kClipSlots + 2 * TransferTables::kTexels) * sizeof(glm::vec4); }

// The transfer function's tables as the march reads them (volume_march.glsl).
void set_tables(VolumeParams& p, const TransferTables& t) {
    const double w = t.width();
    p.tf_lut =
        glm::vec4(float(t.lo()), w > 0 ? float(1.0 / w) : 0.0f, float(TransferTables::kTexels - 1), float(t.hi()));
    p.tf_low_end = glm::vec4(t.low_end());
    p.tf_high_end = glm::vec4(t.high_end());
    p.tf_top = t.integrals().back();
    p.tf_clear = glm::vec2(float(std::max(t.clear_below(), -3.0e38)), float(std::min(t.clear_above(), 3.0e38)));
    // One point only: every piece takes the integrals' slope (no difference of them).
    p.tf_width = w > 0 ? float(w) : 3.0e38f;
}

VolumeParams volume_params(const FrameContext& ctx) {
    const VolumeInput& v = *ctx.volume;
    const VolumeLook& look = ctx.opt.look.volume;
    VolumeParams p;
    p.inverse_view_projection = glm::inverse(ctx.raster_view_projection);
    const glm::dmat4 to_index = glm::inverse(v.index_to_lps);
    p.lps_to_index = glm::mat4(to_index);
    p.gradient_to_view = std140::mat3(ctx.world_to_view * glm::transpose(glm::mat3(glm::dmat3(to_index))));
    p.eye = glm::vec4(glm::vec3(ctx.camera.eye), 1.0f);
    p.forward = glm::vec4(glm::vec3(ctx.camera.forward()), 0.0f);
    p.dims_max = glm::vec4(glm::vec3(v.dims - 1), float(v.chunk_size));
    p.chunk_counts = glm::vec4(glm::vec3(v.chunk_counts), 0.0f);
    p.texel = glm::vec4(1.0f / glm::vec3(v.dims), 0.0f);
    p.vol_near_far = {float(ctx.camera.near_plane), float(ctx.camera.far_plane)};
    p.value_map = v.value_map;
    set_tables(p, *v.tables);
    p.vol_image_size = {ctx.width, ctx.height};
    p.step_mm = float(volume_step_mm(ctx));
    p.vol_epsilon = ctx.opt.look.oit_epsilon;
    p.gradient_ref = float(gradient_reference(look.tf, v.min_spacing));
    // The first frame (and every frame not accumulated) samples midpoints,
    // the stated model; the later frames of an average spread the samples
    // over their steps (0.5, 0, 0.75, 0.25, ...: van der Corput, shifted).
    const double spread = ctx.aa && ctx.aa_frame > 0 ? sequences::radical_inverse2(std::uint32_t(ctx.aa_frame)) : 0.0;
    p.sample_offset = float(std::fmod(0.5 + spread, 1.0));
    p.mode = look.mode == VolumeMode::Mip ? 1u : look.mode == VolumeMode::Minip ? 2u : 0u;
    p.clip_count = std::uint32_t(clip_planes(ctx).size());
    p.skip_empty = look.skip_empty ? 1u : 0u;
    return p;
}

} // namespace

std::string volume_variant(const FrameContext& ctx) {
    const VolumeLook& look = ctx.opt.look.volume;
    std::string d;
    if (look.shading && !ctx.opt.look.flat_shading) d += "#define VOLUME_SHADING 1\n";
    if (look.integration == VolumeIntegration::Preintegrated) d += "#define VOLUME_PREINTEGRATED 1\n";
    return d;
}

std::string clip_define(const FrameContext& ctx) { return ctx.opt.look.clip.active() ? "#define CLIP 1\n" : ""; }

void set_clip(const FrameContext& ctx, iso::gl::Program& prog) {
    if (!ctx.opt.look.clip.active()) return;
    const auto planes = clip_planes(ctx);
    glUniform4fv(prog.uniform("clip_planes"), GLsizei(planes.size()), &planes[0].x);
    glUniform1i(prog.uniform("clip_count"), GLint(planes.size()));
}

double volume_step_mm(const FrameContext& ctx) {
    const VolumeLook& look = ctx.opt.look.volume;
    return (ctx.opt.moving ? look.moving_step : look.step) * (ctx.volume ? ctx.volume->min_spacing : 1.0);
}

VolumeBindings declare_volume(graph::FrameGraph::Builder& b, const FrameContext& ctx, const GBuffer& gb) {
    VolumeBindings v;
    v.depth = b.read(gb.depth);
    v.tables = b.write(b.create("volume_tables", graph::BufferDesc{tables_bytes()}));
    v.counters = b.write(b.create("volume_counters", graph::BufferDesc{kCounterBytes}));
    v.params = params_buffer<VolumeParams>(b, "volume_params");
    return v;
}

void bind_volume(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const VolumeBindings& v) {
    const auto tables = volume_tables(ctx);
    glNamedBufferSubData(gl.buffer(r, v.tables), 0, GLsizeiptr(tables.size() * sizeof(glm::vec4)), tables.data());
    const GLuint zero = 0;
    glClearNamedBufferData(gl.buffer(r, v.counters), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    bind_params(gl, r, v.params, volume_params(ctx));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 11, gl.buffer(r, v.tables));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 12, gl.buffer(r, v.counters));
    glBindTextureUnit(4, ctx.volume->texture);
    glBindTextureUnit(5, ctx.volume->occupancy);
    glBindTextureUnit(6, gl.texture(r, v.depth));
}

void report_volume(GlResources& gl, const graph::Resources& r, const FrameContext& ctx, const VolumeBindings& v) {
    GLuint c[4];
    glGetNamedBufferSubData(gl.buffer(r, v.counters), 0, kCounterBytes, c);
    VolumeStats& s = ctx.result->volume;
    const VolumeInput& in = *ctx.volume;
    s.drawn = true;
    s.step_mm = volume_step_mm(ctx);
    s.chunks = std::size_t(in.chunk_counts.x) * std::size_t(in.chunk_counts.y) * std::size_t(in.chunk_counts.z);
    s.empty_chunks = in.empty_chunks;
    s.rays = c[0];
    s.samples = c[1];
    s.skipped = c[2];
    s.terminated = c[3];
    s.texture_bytes = in.texture_bytes;
    s.uploaded = in.uploaded;
    for (int unit = 4; unit <= 6; ++unit) glBindTextureUnit(GLuint(unit), 0);
}

graph::TextureHandle volume(graph::FrameGraph& fg, const FrameContext& ctx, const GBuffer& gb,
                            graph::TextureHandle color) {
    struct Data {
        VolumeBindings vol;
        graph::TextureHandle color;
    };
    return fg
        .add_pass<Data>(
            "volume",
            [&](graph::FrameGraph::Builder& b, Data& d) {
                d.vol = declare_volume(b, ctx, gb);
                d.color = b.write(b.read(color));
            },
            [&ctx](const Data& d, const graph::Resources& r) {
                GlResources& gl = *ctx.gl;
                gl.program({"render/volume.comp"}, volume_variant(ctx)).use();
                bind_volume(gl, r, ctx, d.vol);
                glBindImageTexture(1, gl.texture(r, d.color), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA8);
                glDispatchCompute(GLuint((ctx.width + 7) / 8), GLuint((ctx.height + 7) / 8), 1);
                glMemoryBarrier(GL_ALL_BARRIER_BITS);
                report_volume(gl, r, ctx, d.vol);
            })
        .color;
}

} // namespace iso::passes
