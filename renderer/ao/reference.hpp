// Ground truth for ambient occlusion, by ray tracing with Embree:
// the cosine-weighted visibility of the hemisphere around the normal,
// limited to distance R (a ray that hits nothing within R counts as
// unoccluded), 1 = unoccluded. This is the one AO definition every method is
// measured against (docs/ao.md, "Definition and ground truth").
//
// Directions are cosine-distributed (Malley: uniform points of the unit disk
// lifted to the hemisphere), so the estimate is the plain fraction of
// unoccluded rays; its standard error is at most 0.5 / sqrt(N).
#pragma once

#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "io/image.hpp"
#include "io/mesh.hpp"
#include "renderer/frame/ao_settings.hpp"
#include "renderer/frame/camera.hpp"

namespace iso {

struct AoReferenceOptions {
    double radius_mm = 10.0; // R
    int rays = 1024;         // N per point
    unsigned seed = 1;
    int threads = 0; // 0: all
};

class AoReference {
public:
    // Builds the ray-tracing scene (Embree BVH) over the meshes, in LPS mm.
    explicit AoReference(const std::vector<const Mesh*>& meshes);
    ~AoReference();
    AoReference(const AoReference&) = delete;
    AoReference& operator=(const AoReference&) = delete;

    // AO at one point with unit normal `n` (rays leave from slightly above it).
    double at(const glm::dvec3& p, const glm::dvec3& n, const AoReferenceOptions& opt, unsigned pixel_seed = 0) const;

    // AO for every pixel of a view, from the renderer's depth AOV (mm along the
    // view axis, +inf for background) and normal AOV (LPS). Background pixels
    // are NaN. One float channel.
    Image image(const Camera& cam, const Image& depth, const Image& normal, const AoReferenceOptions& opt) const;

    // Scale of the scene (bounding-box diagonal), for ray offsets.
    double scene_size() const { return scene_size_; }
    // How far above a surface AO rays leave it (mm): 5e-6 of the scene's size
    // (1.5 um on the head CT), far above float precision at hit points
    // computed on their triangle, and small enough that x10 or x0.1 of it
    // changes AO by less than its noise (docs/ao.md).
    double ray_offset() const { return 5e-6 * scene_size_; }

    // The nearest triangle along org + t * dir, t in [tnear, tfar] (dir as
    // given, not normalised): hit, its t, the point on the triangle
    // (computed in double from the barycentrics: (1 - u - v) p0 + u p1 +
    // v p2) and its unit geometric normal (the triangle's own, as its
    // corners wind; not flipped); which mesh (its index in the
    // constructor's list) and triangle.
    struct Hit {
        bool hit = false;
        double t = 0;
        glm::dvec3 point{0.0};
        glm::dvec3 normal{0.0};
        unsigned mesh = 0, triangle = 0;
        double u = 0, v = 0;
    };
    Hit intersect(const glm::dvec3& org, const glm::dvec3& dir, double tnear, double tfar) const;
    // Whether a triangle lies along org + t * dir for t in [0, tfar] (dir unit).
    bool occluded(const glm::dvec3& org, const glm::dvec3& dir, double tfar) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    double scene_size_ = 1.0;
};

// The second reference: the same AO traced through the slicemap itself
// (voxel by voxel along each ray, above the same raised tangent plane as the
// cone tracer with bias factor `bias`), so that the cone tracer's error
// splits into voxelization error (this vs AoReference) and cone error (cone
// vs this). Every `stride`-th pixel in x and y; NaN elsewhere.
Image voxel_ao_image(const SliceMap& sm, const Camera& cam, const Image& depth, const Image& normal,
                     const AoReferenceOptions& opt, double bias = 1.0, int stride = 1);

} // namespace iso
