// Renders meshes headlessly (or into the GUI's context) through the pass
// graph: the frame is renderer/passes/build_frame (G-buffer, cone AO,
// lighting, VOIT for translucent objects, overlay, read-back or present;
// docs/pass_graph.md), its GPU resources kept across frames in a
// ResourcePool. AOVs (depth, normal, id, ao) are other read-backs of the same
// frame. Needs a current GL 4.5 context; front ends use it through
// core::Scene.
#pragma once

#include <cstdint>
#include <memory>

#include "io/mesh.hpp"
#include "io/volume.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"
#include "renderer/graph/resource_pool.hpp"

namespace iso {

class ChunkIndex;
namespace lod {
struct ClusterLod;
}

class Renderer {
public:
    Renderer();
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    // Uploads a mesh (positions LPS mm, normals optional: computed if absent).
    // Returns the object's id (1-based; 0 is the background in the id AOV).
    std::uint32_t add(const Mesh& m, const SceneObject& o);
    // Uploads a new mesh for object `id` in place (its properties and id stay).
    void replace(std::uint32_t id, const Mesh& m);
    // Frees object `id`'s GPU buffers; the id stays taken (later objects keep
    // theirs) and draws nothing from now on.
    void remove(std::uint32_t id);
    std::size_t object_count() const;
    // Hands object `id` its clusters and levels of detail (built from its
    // mesh: docs/lod.md); its element buffer becomes theirs. Frames with
    // look.lod draw by them. A new mesh (replace) drops them.
    void set_lod(std::uint32_t id, const lod::ClusterLod& c);
    bool has_lod(std::uint32_t id) const;
    // The volume that frames with look.volume.enabled ray cast (null: none),
    // with its range index (per-chunk min/max) when one was made (else the
    // renderer makes one); uploaded as a 3D texture on the first such frame
    // and kept.
    void set_volume(std::shared_ptr<const Volume> v, std::shared_ptr<const ChunkIndex> index = nullptr);
    Bounds bounds() const;
    SceneObject& object(std::uint32_t id);

    RenderResult render(const Camera& camera, const RenderOptions& opt, const RenderHooks& hooks = {});

    // GPU resources kept across frames (renderer/graph/resource_pool.hpp),
    // and all GL objects made so far: in a steady view neither grows.
    const graph::ResourcePool& pool() const;
    std::size_t gl_objects_created() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace iso
