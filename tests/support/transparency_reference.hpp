// Ground truth for transparency (VOIT, docs/voit.md): along each pixel's
// ray (through the pixel centre, as the rasterizer samples), every surface
// hit is found with Embree (an intersection filter that records each hit and
// lets the ray go on), sorted front to back (ties by object, then triangle,
// as the GPU breaks them), and composited in double precision with flat
// shading (each hit is its surface's albedo): C = sum T_i a_i c_i,
// T_{i+1} = T_i (1 - a_i), over the background. Hits nearer than the near
// plane or beyond the far plane are clipped as the rasterizer clips them.
// Exact: no early exit, no pool limit.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "io/image.hpp"
#include "io/mesh.hpp"
#include "renderer/frame/camera.hpp"

namespace iso {

struct ReferenceSurface {
    const Mesh* mesh = nullptr;
    glm::vec3 color{1.0f}; // linear albedo
    float opacity = 1.0f;
};

struct TransparencyImage {
    int width = 0, height = 0;
    std::vector<glm::dvec3> linear;       // composited linear RGB, rows top to bottom
    std::vector<std::uint8_t> foreground; // 1 where the ray hit any surface
    std::vector<std::uint32_t> hits;      // surfaces crossed per pixel (depth complexity)
};

TransparencyImage transparency_reference(const std::vector<ReferenceSurface>& surfaces, const Camera& camera, int width,
                                         int height, const glm::dvec3& background_linear, int threads = 0);

// sRGB encoding of a linear value (the renderer's, in double).
double srgb_encode(double linear);

} // namespace iso
