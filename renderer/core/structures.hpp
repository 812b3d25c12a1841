// Structures through the core API (docs/measure.md, "Structures"), so the CLI
// and the GUI share them: the connected component of a surface under a point
// made a surface of its own (the Isolate tool; 3D Slicer's "keep selected
// island"), measured as `measure` measures that component, and the exact
// shortest distance between two surfaces or two components (a BVH over
// each one's triangles: renderer/surface/closest.hpp).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "io/markups.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/surface/closest.hpp"
#include "renderer/surface/grow.hpp"
#include "renderer/surface/scissors.hpp"

namespace iso::core {

// The visible surface nearest to an LPS point (a picked point lies on its
// surface: distance 0), and where on it. Unpickable and hidden surfaces are
// left out. Throws iso::Error("surface at a point", ...) when the scene has
// no visible surface, or the point is not finite.
struct SurfacePoint {
    SurfaceId surface = 0;
    std::uint32_t triangle = 0;
    glm::dvec3 point{0.0}; // on the surface, LPS mm
    double distance_mm = 0;
};
SurfacePoint surface_at(const Scene& scene, const glm::dvec3& lps);
// The visible surfaces with a search tree each, for a caller that keeps the
// trees across queries (building one per query costs seconds at 30 M
// triangles: the desktop app's Measurements panel keeps them, off its GUI
// thread). surface_trees builds them for `scene` into `keep`.
struct SurfaceTree {
    SurfaceId id = 0;
    std::string name;
    const TriangleBvh* bvh = nullptr;
    double opacity = 1;
    bool pickable = true;
};
std::vector<SurfaceTree> surface_trees(const Scene& scene, std::vector<std::unique_ptr<TriangleBvh>>& keep);
SurfacePoint surface_at(const std::vector<SurfaceTree>& trees, const glm::dvec3& lps);

struct IsolatedComponent {
    SurfaceId surface = 0;       // the new surface
    SurfaceId from = 0;          // the surface it came from
    std::size_t component = 0;   // its index among the parent's components (measure's order: by volume)
    std::size_t components = 0;  // how many the parent has
    SurfaceMeasurement measured; // the new surface, as measure_surfaces measures it
};

// Makes the connected component of `surface` nearest to `at` a surface of
// its own: kind and value of the parent (an isosurface stays one, so its
// measurement has the isosurface's uncertainty and a session re-extracts it:
// PostProcessOptions::keep_at records the point), named "<parent>
// component <k>" (k: 1-based, by volume as `measure` lists them), in a
// colour of its own, opaque. The parent is left as it is (hide it to see
// the component alone). Throws iso::Error naming the surface for an unknown
// or empty one.
//
// With `within` (3D Slicer's islands within an ROI, made exact): only the
// part of that component inside the LPS box, cut at the box's faces and
// capped (clip_to_box), and of that part the piece nearest `at`: a
// structure cut off the tree it touches, measured as a closed surface
// (PostProcessOptions::keep_within records the box; named "... component
// <k> within box"). Throws iso::Error when nothing of the component is
// within the box.
IsolatedComponent isolate_component(Scene& scene, SurfaceId surface, const glm::dvec3& at,
                                    const std::optional<LpsBox>& within = {});

// isolate_component in two steps, for a caller that works off its GUI
// thread: plan_component only reads the scene (the surface's mesh and the
// volume) and does the work (components, measurement); add_component puts
// the planned surface into the scene.
struct ComponentPlan {
    SurfaceId from = 0;
    std::size_t component = 0, components = 0;
    Mesh mesh;
    SurfaceInfo info;
    SurfaceMeasures measures;
};
ComponentPlan plan_component(const Scene& scene, SurfaceId surface, const glm::dvec3& at,
                             const std::optional<LpsBox>& within = {});
IsolatedComponent add_component(Scene& scene, ComponentPlan plan);

// Scissors (surface/scissors.hpp: 3D Slicer's Scissors, exact): the part of
// `surface` inside (or outside) an outline drawn on a view of `camera` at
// width x height (image pixels from the top-left, closed), swept along the
// view's rays, cut at the swept walls and capped. A surface of its own,
// "<parent> scissors <n>" (a mesh: its measurement has no discretization
// uncertainty), in a colour of its own; its parent is left as it is (the
// desktop app hides it). Throws iso::Error: an unknown or empty surface, a
// bad outline (surface/scissors.hpp), nothing of the surface kept.
struct ScissorsRequest {
    std::vector<glm::dvec2> outline;
    Camera camera;
    int width = 0, height = 0;
    bool keep_inside = true;
};
ComponentPlan plan_scissors(const Scene& scene, SurfaceId surface, const ScissorsRequest& r);

// A region grown from a seed in the volume (surface/grow.hpp: the voxels
// joined to it within a value range, limited to a box), made a surface of
// its own: the boundary of its voxels (extract_labels: vertices at edge
// midpoints, closed), named "grown <n>", in a colour of its own. Measured
// twice: by its voxels (the count's volume, with the partial-volume
// uncertainty of its boundary voxels) and by its surface (area, enclosed
// volume, centroid, largest diameter). Throws iso::Error (no volume, and
// grow_region's errors).
struct GrownStructure {
    SurfaceId surface = 0;
    GrownRegion region; // its mask is dropped (empty) once the surface is made
    glm::dvec3 seed{0.0};
    GrowOptions options;
    SurfaceMeasures measures;
};
GrownStructure grow_structure(Scene& scene, const glm::dvec3& seed, const GrowOptions& options,
                              const ProgressFn& progress = {});
// grow_structure in two steps, for a caller that works off its GUI thread:
// plan_grown only reads the scene's volume and does the work (the region,
// its surface, the measures); grown_info names the surface as the scene
// stands when it is added ("grown <n>", its colour) and records how it was
// grown (SurfaceInfo::grown: a session grows it again).
struct GrownPlan {
    GrownStructure grown; // surface 0 until added
    Mesh mesh;
};
GrownPlan plan_grown(const Scene& scene, const glm::dvec3& seed, const GrowOptions& options,
                     const ProgressFn& progress = {});
SurfaceInfo grown_info(const Scene& scene, const GrownStructure& g);
nlohmann::json grown_json(const Scene& scene, const GrownStructure& g);

// Structures as a label map on the volume's grid (3D Slicer loads it as a
// segmentation: Add Data, a NIfTI as "Segmentation", with the colour table
// beside it): label k+1 for surfaces[k], set in the voxels whose centres
// the surface encloses (surface/voxelize.hpp); where two overlap, the later
// one's label. uint16, the volume's index -> LPS affine. Throws iso::Error
// without a volume, or for more than 65535 surfaces.
struct LabelMapEntry {
    SurfaceId surface = 0;
    std::uint16_t label = 0;
    std::string name;
    glm::vec3 color{0.0f}; // linear RGB
    std::size_t voxels = 0;
};
struct LabelMap {
    Volume labels;
    std::vector<LabelMapEntry> entries;
};
LabelMap structures_label_map(const Scene& scene, const std::vector<SurfaceId>& surfaces);
// Writes the label map (.nii or .nii.gz; never half-written) and, beside it,
// its colour table (the same name with .ctbl: Slicer's colour table file,
// "label name R G B A", names with spaces as underscores). Returns the
// table's path. Throws iso::Error naming the file.
std::string save_label_map(const LabelMap& m, const std::string& path);
// The colour table's path for a label map at `path`; throws iso::Error(what,
// ...) when `path` is not .nii or .nii.gz (the CLI asks before any work).
std::string label_map_table(const std::string& path, const std::string& what);

// The shortest distance between two surfaces, or between the components of
// them nearest to two points (`at_a`, `at_b`; none: the whole surface).
struct SurfaceGap {
    SurfaceId a = 0, b = 0;
    std::string name_a, name_b; // "iso 500", "iso 1150 component 2"
    SurfaceDistance distance;   // pair.a on a, pair.b on b
    // The components the points chose (none: the whole surface), and whether
    // both ends are one connected structure (one surface, the same
    // component or the whole of it twice): its distance to itself is 0, no
    // gap between two structures (the desktop app refuses it).
    std::optional<std::size_t> component_a, component_b;
    bool same_structure = false;
};
SurfaceGap surface_gap(const Scene& scene, SurfaceId a, SurfaceId b, const std::optional<glm::dvec3>& at_a = {},
                       const std::optional<glm::dvec3>& at_b = {});

// The surfaces a straight line between two points passes through (a
// ruler drawn inside the head): each crossing of a visible surface whose own
// opacity is at least `threshold` (the pick's rule: solid enough to hide
// what lies behind), strictly between the ends: crossings within
// `end_tolerance_mm` of either end are the surface the point lies on, and
// are left out. Sorted along the line.
struct LineCrossing {
    SurfaceId surface = 0;
    std::string name;
    glm::dvec3 point{0.0};
    double along_mm = 0; // from the first point
};
std::vector<LineCrossing> solid_crossings(const Scene& scene, const glm::dvec3& a, const glm::dvec3& b,
                                          double threshold = 0.5, double end_tolerance_mm = 0.5);
std::vector<LineCrossing> solid_crossings(const std::vector<SurfaceTree>& trees, const glm::dvec3& a,
                                          const glm::dvec3& b, double threshold = 0.5, double end_tolerance_mm = 0.5);

// JSON of a gap (surfaces, distance_mm, points LPS, triangles, touching) and
// of an isolated component (the measure JSON of its surface, plus its parent
// and index, its centroid and largest diameter (surface/shape.hpp), and for
// a part within a box how it was cut: the box, and the cap's area on each
// face it cuts).
nlohmann::json gap_json(const SurfaceGap& g);
nlohmann::json component_json(const Scene& scene, const IsolatedComponent& c);

// A part's making and shape, for `measure --session` (the parts a session
// holds: made in the desktop app, or by the CLI): how it was made
// ("made": the steps in order, each "component at", "within box",
// "scissors inside" or "scissors outside"; "grown_from" and "grown_range"
// for a grown region), its largest diameter and centroid. Null for a
// surface that is no part (a whole isosurface, label or mesh). `closed`:
// the surface is (its measurement says so): its centroid is a solid's.
nlohmann::json part_json(const Scene& scene, SurfaceId id, bool closed);
// The surface is a part: a component kept at a point, a part within a box,
// cut by steps, or a grown region (what the structures table lists).
bool is_part(const SurfaceInfo& info);

// The gap as a 3D Slicer line markup between the two closest points, named
// "<a> to <b>", its length the distance.
Markup gap_markup(const SurfaceGap& g);

} // namespace iso::core
