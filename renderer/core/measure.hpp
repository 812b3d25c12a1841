// Measurements through the core API (docs/measure.md), so the CLI and the GUI
// share them: per surface of a scene (area, enclosed volume or a lower bound,
// closed/open, components, uncertainty), and points (distance, angle, the
// volume's value at a point), with their JSON and their 3D Slicer markups.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "io/markups.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/surface/analysis.hpp"

namespace iso::core {

struct SurfaceMeasurement {
    SurfaceId surface = 0;
    std::string name;
    SurfaceInfo::Kind kind = SurfaceInfo::Kind::Mesh;
    double value = 0; // iso value or label
    SurfaceMeasures measures;
};

// Measures the given surfaces (empty: all): isosurfaces of the scene's
// volume with their discretization uncertainty (measure_isosurface), other
// surfaces as meshes (measure_surface: no uncertainty).
std::vector<SurfaceMeasurement> measure_surfaces(const Scene& scene, const std::vector<SurfaceId>& ids = {});

// A mesh measured as measure_surfaces measures a surface described by
// `info` (its kind, value and post-processing), before it is in the scene.
SurfaceMeasures measure_surface_mesh(const Scene& scene, const SurfaceInfo& info, const Mesh& mesh);

// The volume's value at an LPS point, with its voxel; none outside the grid.
// Throws iso::Error("value at a point", ...) when the scene has no volume.
std::optional<VolumeSample> value_at(const Scene& scene, const glm::dvec3& lps);

// "x,y,z" (LPS mm) -> point; throws iso::Error(what, ...) naming the text.
glm::dvec3 parse_point(const std::string& what, const std::string& text);

struct PointMeasurements {
    std::vector<std::array<glm::dvec3, 2>> distances;
    std::vector<std::array<glm::dvec3, 3>> angles; // the angle at the middle point
    std::vector<glm::dvec3> values;                // the volume's value at each
};

// JSON of `isoscope measure --json`: "surfaces" (per surface: name, iso,
// area_mm2, volume_ml, cavity, volume_kind, closed, boundary, components,
// uncertainty, warnings; volumes never negative: the wall of a cavity gives
// the cavity's volume and cavity true, encloses_cavity), "distances",
// "angles", "values" (per point: point,
// value, unit (value_unit; null without one or without a value), voxel).
nlohmann::json measure_json(const Scene& scene, const std::vector<SurfaceMeasurement>& surfaces,
                            const PointMeasurements& points);

// The points as 3D Slicer markups (LPS): one Line per distance (with its
// length), one Angle per angle (with its value), one point list for the
// values (each point's description holds the value).
MarkupsFile point_markups(const Scene& scene, const PointMeasurements& points);

} // namespace iso::core
