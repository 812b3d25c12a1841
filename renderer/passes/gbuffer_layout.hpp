// The G-buffer's colour channels in one table (Falcor's GBufferRaster is the
// model): the gbuffer pass creates, attaches and clears them from it, the
// fragment shader gets their output locations from it (gbuffer_defines():
// "#define GB_NORMAL 0" ...), and the frame finds which channel an AOV reads
// in it. Adding a channel is one row here and one output in gbuffer.frag.
#pragma once

#include <string>

#include "renderer/passes/build_frame.hpp"

namespace iso::passes {

struct GBufferChannel {
    const char* name; // resource name; GLSL define GB_<NAME>
    graph::Format format;
    Aov aov;                               // the AOV that reads it (None: no AOV)
    graph::TextureHandle GBuffer::*handle; // where the pass returns it
};

inline const GBufferChannel kGBufferLayout[] = {
    // world (LPS) normal, w = 1 on geometry
    {"normal", graph::Format::RGBA16F, Aov::Normal, &GBuffer::normal},
    {"id", graph::Format::R32UI, Aov::Id, &GBuffer::id},               // object id, 0 = background
    {"albedo", graph::Format::RGBA8, Aov::None, &GBuffer::albedo}, // linear albedo
};

std::string gbuffer_defines();
bool is_integer(graph::Format f);

} // namespace iso::passes
