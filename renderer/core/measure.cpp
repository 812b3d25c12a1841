#include "renderer/core/measure.hpp"

#include <cmath>
#include <cstdio>

#include "io/error.hpp"
#include "renderer/core/value_unit.hpp"
#include "renderer/surface/box_clip.hpp"

namespace iso::core {

SurfaceMeasures measure_surface_mesh(const Scene& scene, const SurfaceInfo& info, const Mesh& mesh) {
    // Isosurfaces of the volume get the uncertainty from coarser grids;
    // label surfaces and meshes are measured as they are.
    if (info.kind == SurfaceInfo::Kind::Iso && scene.has_volume()) {
        MeasureOptions opt;
        opt.components_only = info.post.keep_largest || kept_at(info.post) || info.post.keep_within;
        // A part cut by a box or an outline is compared with the coarse
        // isosurfaces cut the same way (the pieces kept are matched by components).
        std::vector<PartStep> cuts = info.post.steps;
        for (PartStep& c : cuts) c.keep_at.reset();
        if (info.post.keep_within || !cuts.empty())
            opt.coarse_post = [box = info.post.keep_within, cuts](const Mesh& m) {
                return apply_steps(box ? clip_to_box(m, *box) : m, cuts);
            };
        return measure_isosurface(scene.volume(), info.value, mesh, opt);
    }
    return measure_surface(mesh);
}

std::vector<SurfaceMeasurement> measure_surfaces(const Scene& scene, const std::vector<SurfaceId>& ids) {
    std::vector<SurfaceMeasurement> out;
    for (const SurfaceId id : ids.empty() ? scene.surfaces() : ids) {
        const SurfaceInfo& info = scene.info(id);
        SurfaceMeasurement m;
        m.surface = id;
        m.name = info.name;
        m.kind = info.kind;
        m.value = info.value;
        m.measures = measure_surface_mesh(scene, info, scene.mesh(id));
        out.push_back(std::move(m));
    }
    return out;
}

std::optional<VolumeSample> value_at(const Scene& scene, const glm::dvec3& lps) {
    if (!scene.has_volume()) throw Error("value at a point", "the input is a mesh: there is no volume to sample");
    return sample_volume(scene.volume(), lps);
}

glm::dvec3 parse_point(const std::string& what, const std::string& text) {
    double x = 0, y = 0, z = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &x, &y, &z, &tail) != 3 || !std::isfinite(x) || !std::isfinite(y) ||
        !std::isfinite(z))
        throw Error(what, "expected a point x,y,z in LPS mm, got '" + text + "'");
    return {x, y, z};
}

namespace {

nlohmann::json vec(const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }
// NaN is not JSON: an absent uncertainty is null.
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// A signed volume as shown: its size (a cavity's wall: the cavity's, with
// "cavity" true; encloses_cavity), never negative.
nlohmann::json size(double signed_volume) { return number(std::abs(signed_volume)); }

nlohmann::json part_json(const SurfacePart& p) {
    return {{"triangles", p.triangles},
            {"area_mm2", p.area_mm2},
            {"volume_ml", size(p.volume_ml)},
            {"cavity", encloses_cavity(p.volume_ml)},
            {"volume_kind", volume_kind_name(p.volume_kind)},
            {"closed", p.closed},
            {"boundary_loops", p.boundary_loops},
            {"boundary_length_mm", p.boundary_length_mm},
            {"bounds_lps", {vec(p.bounds_min), vec(p.bounds_max)}},
            {"area_uncertainty_mm2", number(p.area_uncertainty_mm2)},
            {"volume_uncertainty_ml", number(p.volume_uncertainty_ml)}};
}

} // namespace

nlohmann::json measure_json(const Scene& scene, const std::vector<SurfaceMeasurement>& surfaces,
                            const PointMeasurements& points) {
    using nlohmann::json;
    json j;
    j["coordinates"] = "LPS mm";
    json ss = json::array();
    for (const auto& s : surfaces) {
        const SurfaceMeasures& m = s.measures;
        json o;
        o["surface"] = s.name;
        o["iso"] = s.kind == SurfaceInfo::Kind::Iso ? json(s.value) : json(nullptr);
        if (s.kind == SurfaceInfo::Kind::Label) o["label"] = s.value;
        o["triangles"] = m.triangles;
        o["area_mm2"] = m.area_mm2;
        o["volume_ml"] = size(m.volume_ml);
        o["cavity"] = encloses_cavity(m.volume_ml);
        o["volume_kind"] = volume_kind_name(m.volume_kind);
        o["closed"] = m.closed;
        o["boundary"] = {{"edges", m.boundary_edges}, {"loops", m.boundary_loops}, {"length_mm", m.boundary_length_mm}};
        o["non_manifold_edges"] = m.non_manifold_edges;
        o["misoriented_edges"] = m.misoriented_edges;
        o["degenerate_triangles"] = m.degenerate_triangles;
        o["bounds_lps"] = {vec(m.bounds_min), vec(m.bounds_max)};
        o["area_uncertainty_mm2"] = number(m.area_uncertainty_mm2);
        o["volume_uncertainty_ml"] = number(m.volume_uncertainty_ml);
        o["area_extrapolated_mm2"] = number(m.area_extrapolated_mm2);
        o["volume_extrapolated_ml"] = size(m.volume_extrapolated_ml);
        json parts = json::array();
        for (const auto& p : m.components) parts.push_back(part_json(p));
        o["components"] = std::move(parts);
        o["warnings"] = m.warnings;
        ss.push_back(std::move(o));
    }
    j["surfaces"] = std::move(ss);
    json d = json::array(), a = json::array(), v = json::array();
    for (const auto& p : points.distances)
        d.push_back({{"points", {vec(p[0]), vec(p[1])}}, {"distance_mm", distance_mm(p[0], p[1])}});
    for (const auto& p : points.angles)
        a.push_back({{"points", {vec(p[0]), vec(p[1]), vec(p[2])}}, {"angle_deg", angle_deg(p[0], p[1], p[2])}});
    const std::string_view unit = value_unit(scene);
    for (const auto& p : points.values) {
        const auto s = value_at(scene, p);
        json o{{"point", vec(p)}};
        o["value"] = s ? number(s->value) : json(nullptr);
        o["unit"] = s && !unit.empty() ? json(std::string(unit)) : json(nullptr);
        o["voxel"] = s ? json::array({s->voxel[0], s->voxel[1], s->voxel[2]}) : json(nullptr);
        if (!s) o["note"] = "outside the volume";
        v.push_back(std::move(o));
    }
    j["distances"] = std::move(d);
    j["angles"] = std::move(a);
    j["values"] = std::move(v);
    return j;
}

MarkupsFile point_markups(const Scene& scene, const PointMeasurements& points) {
    MarkupsFile f;
    auto point = [](const glm::dvec3& p, std::string label) {
        MarkupControlPoint c;
        c.position = p;
        c.label = std::move(label);
        return c;
    };
    for (std::size_t i = 0; i < points.distances.size(); ++i) {
        Markup m;
        m.type = MarkupType::Line;
        m.name = "distance " + std::to_string(i + 1);
        m.points = {point(points.distances[i][0], m.name + "-1"), point(points.distances[i][1], m.name + "-2")};
        if (auto c = computed_measurement(m)) m.measurements.push_back(*c);
        f.markups.push_back(std::move(m));
    }
    for (std::size_t i = 0; i < points.angles.size(); ++i) {
        Markup m;
        m.type = MarkupType::Angle;
        m.name = "angle " + std::to_string(i + 1);
        for (int k = 0; k < 3; ++k)
            m.points.push_back(point(points.angles[i][std::size_t(k)], m.name + "-" + std::to_string(k + 1)));
        if (auto c = computed_measurement(m)) m.measurements.push_back(*c);
        f.markups.push_back(std::move(m));
    }
    if (!points.values.empty()) {
        Markup m;
        m.type = MarkupType::Fiducial;
        m.name = "values";
        for (std::size_t i = 0; i < points.values.size(); ++i) {
            auto c = point(points.values[i], "V-" + std::to_string(i + 1));
            const auto s = value_at(scene, points.values[i]);
            char b[64];
            if (s && std::isfinite(s->value))
                std::snprintf(b, sizeof b, "value %.6g", s->value);
            else
                std::snprintf(b, sizeof b, "outside the volume");
            c.description = b;
            m.points.push_back(std::move(c));
        }
        f.markups.push_back(std::move(m));
    }
    return f;
}

} // namespace iso::core
