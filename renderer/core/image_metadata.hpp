// The metadata an exported frame carries (docs/rendering.md, "Metadata"):
// what was drawn (inputs and their SHA-256, iso values, surfaces, markups
// and the measurements shown, the session file), how (camera, matrices,
// shading, transparency, the AOV, ambient occlusion and every one of its
// settings) and by what (version, GL renderer). Built after the frame by
// render_image(); internal to the core.
#pragma once

#include "io/image.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/raytraced_ao.hpp"

namespace iso::core {

// Everything of one rendered frame the metadata describes.
struct FrameRecord {
    const Scene& scene;
    const RenderRequest& req;
    const RenderOptions& options;
    const Camera& camera;
    const RenderResult& result;
    const Annotations* annotations;         // drawn over the colour image; null: an AOV or none
    const RaytracedAo* raytraced = nullptr; // the ray-traced AO term the frame was lit with
};

ImageMetadata frame_metadata(const FrameRecord& f);

// What a frame's ray-traced AO depends on in the scene, one a line: the
// inputs' SHA-256, the iso values, the visible surfaces, the camera (a
// cache key's part).
std::string scene_key_text(const Scene& scene, const Camera& cam);

} // namespace iso::core
