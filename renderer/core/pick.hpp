// Picking through the core API (docs/picking.md): what the user sees at a
// pixel of the image render_image() would write with the same request, and
// every layer behind it. The pick rides on that frame (its geometry passes
// list the fragments); positions are then exact: the pixel's ray meets the
// listed triangle in double precision (not a depth buffer unprojected), and
// from the LPS point come the normal, the voxel and the volume's value there
// with its unit (value_unit: HU for CT).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "renderer/core/api.hpp"
#include "renderer/core/scene.hpp"

namespace iso::core {

struct PickRequest {
    // The pixel, from the image's top-left corner (of the image render_image
    // writes with the same RenderRequest).
    int x = 0, y = 0;
    // Optional rectangle (image pixels from the top-left): every triangle
    // visible in it is listed too. Empty (width or height 0): none.
    PickRegion rect{0, 0, 0, 0};
    // Where a click lands (the visible layer): the first surface along the
    // ray whose own opacity reaches this, else the nearest surface hit.
    double threshold = 0.5;
    // List every layer (down to the first opaque one), not only those up to the visible one.
    bool all_layers = false;
};

struct PickLayer {
    // A surface's layer, or the volume's (volume rendering: where the
    // volume's own accumulated opacity along the ray reaches 0.5; surface 0,
    // name "volume", no triangle or normal).
    bool volume = false;
    SurfaceId surface = 0;
    std::string name; // "iso 500", a mesh file's name
    SurfaceInfo::Kind kind = SurfaceInfo::Kind::Mesh;
    double surface_value = 0;    // the surface's iso value or label (Iso, Label surfaces)
    std::uint32_t triangle = 0;  // index into the surface's mesh
    glm::dvec3 lps{0.0};         // where the pixel's ray meets the triangle, LPS mm
    glm::dvec3 normal{0.0};      // the surface's normal there (interpolated), LPS, unit
    glm::dvec3 barycentric{0.0}; // of lps in the triangle
    bool on_triangle = true; // false: the ray passes just outside (an edge the rasterizer gave it); lps is on its plane
    double depth_mm = 0;     // distance along the view axis
    double alpha = 1;        // the surface's opacity
    double share = 0;        // of the pixel's colour: transmittance in front x alpha
    double accumulated_alpha = 0;                     // 1 - transmittance behind this layer
    std::optional<double> value;                      // the volume's value there (trilinear, after rescale)
    std::string unit;                                 // value's unit (value_unit): "HU" for CT, else empty
    std::optional<std::array<std::int64_t, 3>> voxel; // the nearest voxel
};

// A triangle visible somewhere in the pick rectangle, with its pixel count.
struct PickedTriangle {
    SurfaceId surface = 0;
    std::uint32_t triangle = 0;
    std::size_t pixels = 0;
};

struct PickResult {
    int x = 0, y = 0, width = 0, height = 0; // the pixel and the image size
    std::optional<std::size_t> visible;      // index into layers; none: background, or nothing opaque enough
    std::vector<PickLayer> layers;           // front to back
    PickRegion rect{0, 0, 0, 0};             // clipped to the image
    std::vector<PickedTriangle> triangles;   // visible in rect (with a rect), most pixels first
    glm::dmat4 view{1.0}, projection{1.0};   // as in the image metadata
    double frame_ms = 0;                     // request to result, the frame it rides on included
    bool complete = true;                    // false: the pick's list pool overflowed (some layers missing)
};

// Renders `req` with the pick riding on the frame and resolves it. Throws
// iso::Error: a pixel outside the image, a threshold outside (0, 1].
// A one-off: render_image uploads the scene and frees its GPU data again.
PickResult pick(Scene& scene, const RenderRequest& req, const PickRequest& p);

// The region a frame must list (RenderOptions::pick) to resolve `p`: its
// pixel and its rectangle. Not clipped (the frame clips to the image).
PickRegion pick_region(const PickRequest& p);

// The pick of a live view, which draws `scene` with its own GL context
// (Scene::render): with that context current, renders one frame of `opt`
// (the view's own options: size, target framebuffer, present, AO, ...) with
// the pick riding on it (opt.pick is set to pick_region(p)) and resolves it.
// The scene's GPU data stays uploaded, as the view's frames leave it.
// Throws iso::Error as pick().
PickResult pick_in_frame(Scene& scene, const Camera& camera, RenderOptions opt, const PickRequest& p);

// Resolves the lists of a frame already rendered with `camera` at
// width x height (with RenderOptions::pick covering pick_region(p)): each
// listed triangle meets the pixel's ray (Camera::pixel_ray) in double
// precision; the value and voxel there come from the scene's volume.
// pick() and pick_in_frame() both end here. frame_ms is left 0. Throws
// iso::Error: a pixel outside the image, a threshold outside (0, 1], a
// list whose region does not hold the pixel and rectangle, a triangle the
// surface's mesh does not have.
// With `look` ray casting the volume (look->volume.enabled), the volume's
// layer is added (add_volume_layer).
PickResult resolve_pick(const Scene& scene, const Camera& camera, int width, int height, const PickList& list,
                        const PickRequest& p, const FrameLook* look = nullptr);

// The volume as a layer of a resolved pick (pick_volume.cpp): the pixel's
// ray marched on the CPU through the stated model (renderer/volume/
// reference.hpp) with the surfaces of the frame's list at their depths; the
// layer lies where the volume's own accumulated opacity reaches 0.5 (MIP /
// MinIP: at the extreme value when its opacity reaches 0.5), with its LPS
// point, value, unit and voxel. By the click's rule (the first layer whose
// own opacity reaches the threshold, else the nearest) it is the visible
// layer when it lies in front of a visible surface that reaches the
// threshold, or when no surface does; layers behind it are then dropped
// unless all are asked for. Nothing when the ray never gets there.
void add_volume_layer(PickResult& r, const Scene& scene, const Camera& camera, const PickList& list,
                      const PickRequest& p, const FrameLook& look);

// The JSON `isoscope pick --json` prints: visible, layers (surface, iso,
// lps, normal, triangle, depth_mm, alpha, share, value, unit (null when
// none), voxel), view and projection (column-major, as the image metadata),
// and the rectangle's triangles when asked.
nlohmann::json pick_json(const PickResult& r);

} // namespace iso::core
