// `isoscope measure`: surfaces (area, volume, closed/open, components,
// uncertainty) and points (distance, angle, value) through the core's
// measurements (core::measure_surfaces; docs/measure.md).
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/cli/commands.hpp"
#include "app/cli/common.hpp"
#include "io/atomic_file.hpp"
#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/session.hpp"
#include "renderer/core/structures.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::cli {

namespace {

struct MeasureArgs {
    std::string in, series, out, label_map, session;
    std::vector<double> isos;
    std::vector<std::string> distance, angle, values;
    std::vector<std::string> component_at, surface_distance, within;
    std::vector<std::string> grow_from, grow_range, grow_within;
    bool json = false;
};

// A surface named on the command line: "x,y,z" is the component of the
// visible surface nearest to that point, anything else a surface's name.
struct SurfaceChoice {
    iso::core::SurfaceId surface = 0;
    std::optional<glm::dvec3> at;
};

SurfaceChoice choose_surface(const iso::core::Scene& scene, const std::string& text) {
    try {
        const glm::dvec3 p = iso::core::parse_point("--surface-distance", text);
        return {iso::core::surface_at(scene, p).surface, p};
    } catch (const iso::Error&) {}
    std::string names;
    for (const auto id : scene.surfaces()) {
        if (scene.info(id).name == text) return {id, std::nullopt};
        names += (names.empty() ? "" : ", ") + scene.info(id).name;
    }
    throw iso::Error("--surface-distance",
                     "no surface is named '" + text + "' (the scene has: " + names + "), and it is not a point x,y,z");
}

// The i-th of option `what`'s values, given once for all `n` values of
// option `per` or once each.
const std::string& one_or_each(const std::vector<std::string>& v, std::size_t i, std::size_t n, const char* what,
                               const char* per) {
    if (v.size() != 1 && v.size() != n)
        throw iso::Error(what, std::string("give one (for every ") + per + ") or one per " + per + ", not " +
                                   std::to_string(v.size()) + " for " + std::to_string(n));
    return v[v.size() == 1 ? 0 : i];
}

// A box option's value: "box=x0,y0,z0,x1,y1,z1" (LPS mm) or "none".
std::optional<iso::LpsBox> box_option(const char* what, const std::string& t) {
    if (t == "none") return std::nullopt;
    if (t.rfind("box=", 0) != 0)
        throw iso::Error(what, "expected box=x0,y0,z0,x1,y1,z1 (LPS mm) or none, got '" + t + "'");
    return iso::parse_box(what, t.substr(4));
}

// The box of the i-th --component-at (none without --within).
std::optional<iso::LpsBox> within_box(const MeasureArgs& a, std::size_t i) {
    if (a.within.empty()) return std::nullopt;
    return box_option("--within", one_or_each(a.within, i, a.component_at.size(), "--within", "--component-at"));
}

// The regions grown from --grow-from seeds (core::grow_structure).
void grow_structures(iso::core::Scene& scene, const MeasureArgs& a, nlohmann::json& j,
                     std::vector<iso::core::SurfaceId>& made) {
    j["grown"] = nlohmann::json::array();
    if (a.grow_from.empty()) {
        if (!a.grow_range.empty() || !a.grow_within.empty()) throw iso::Error("--grow-range", "needs --grow-from");
        return;
    }
    if (a.grow_range.empty()) throw iso::Error("--grow-from", "needs --grow-range LO,HI (the values grown through)");
    for (std::size_t i = 0; i < a.grow_from.size(); ++i) {
        iso::GrowOptions o;
        const std::string& range = one_or_each(a.grow_range, i, a.grow_from.size(), "--grow-range", "--grow-from");
        char tail = 0;
        if (std::sscanf(range.c_str(), "%lf,%lf%c", &o.lo, &o.hi, &tail) != 2)
            throw iso::Error("--grow-range", "expected LO,HI, got '" + range + "'");
        if (!a.grow_within.empty())
            o.within = box_option("--grow-within",
                                  one_or_each(a.grow_within, i, a.grow_from.size(), "--grow-within", "--grow-from"));
        const glm::dvec3 seed = iso::core::parse_point("--grow-from", a.grow_from[i]);
        const auto g = iso::core::grow_structure(scene, seed, o);
        j["grown"].push_back(iso::core::grown_json(scene, g));
        made.push_back(g.surface);
    }
}

// The structures asked for: isolated components (or their parts within
// boxes) and distances between surfaces (core/structures.hpp). The parts
// come first: a distance can name one ("iso 300 component 1 within box").
nlohmann::json measure_structures(iso::core::Scene& scene, const MeasureArgs& a, iso::MarkupsFile& markups) {
    nlohmann::json j{{"components", nlohmann::json::array()}, {"surface_distances", nlohmann::json::array()}};
    if (!a.within.empty() && a.component_at.empty()) throw iso::Error("--within", "needs --component-at");
    std::vector<iso::core::SurfaceId> made; // the structures, in order: their labels in --label-map
    for (std::size_t i = 0; i < a.component_at.size(); ++i) {
        const glm::dvec3 p = iso::core::parse_point("--component-at", a.component_at[i]);
        const auto c =
            iso::core::isolate_component(scene, iso::core::surface_at(scene, p).surface, p, within_box(a, i));
        j["components"].push_back(iso::core::component_json(scene, c));
        made.push_back(c.surface);
    }
    grow_structures(scene, a, j, made);
    if (!a.label_map.empty()) {
        if (made.empty()) throw iso::Error("--label-map", "needs structures: --component-at or --grow-from");
        const auto map = iso::core::structures_label_map(scene, made);
        const std::string table = iso::core::save_label_map(map, a.label_map);
        j["label_map"] = {{"file", a.label_map}, {"color_table", table}, {"labels", nlohmann::json::array()}};
        for (const auto& e : map.entries)
            j["label_map"]["labels"].push_back({{"label", e.label}, {"name", e.name}, {"voxels", e.voxels}});
    }
    std::vector<iso::core::SurfaceGap> gaps;
    for (std::size_t i = 0; i + 1 < a.surface_distance.size(); i += 2) {
        const SurfaceChoice x = choose_surface(scene, a.surface_distance[i]);
        const SurfaceChoice y = choose_surface(scene, a.surface_distance[i + 1]);
        gaps.push_back(iso::core::surface_gap(scene, x.surface, y.surface, x.at, y.at));
    }
    for (const auto& g : gaps) {
        j["surface_distances"].push_back(iso::core::gap_json(g));
        markups.markups.push_back(iso::core::gap_markup(g));
    }
    return j;
}

// "volume X mL" or, for the wall of a cavity, "encloses a cavity of X mL"
// (">= X" for a lower bound), from a surface's or component's JSON.
std::string volume_text(const nlohmann::json& s) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(3);
    o << (s["cavity"].get<bool>() ? "encloses a cavity of " : "volume ")
      << (s["volume_kind"].get<std::string>() == "lower bound" ? ">= " : "") << s["volume_ml"].get<double>() << " mL";
    return o.str();
}

void print_structures(const nlohmann::json& j) {
    for (const auto& c : j["components"]) {
        std::cout << c["surface"].get<std::string>() << " (" << c["component"].get<std::size_t>() << " of "
                  << c["of_components"].get<std::size_t>() << " in " << c["from"].get<std::string>() << "): area "
                  << std::setprecision(1) << c["area_mm2"].get<double>() << " mm2";
        if (!c["area_uncertainty_mm2"].is_null()) std::cout << " +- " << c["area_uncertainty_mm2"].get<double>();
        if (c["volume_ml"].is_null())
            std::cout << ", volume undefined";
        else
            std::cout << ", " << volume_text(c) << std::setprecision(3);
        if (!c["volume_uncertainty_ml"].is_null()) std::cout << " +- " << c["volume_uncertainty_ml"].get<double>();
        std::cout << (c["closed"].get<bool>() ? ", closed" : ", open");
        std::cout << ", largest diameter " << std::setprecision(1) << c["largest_diameter_mm"].get<double>() << " mm";
        if (!c["centroid_lps"].is_null())
            std::cout << ", centroid LPS (" << c["centroid_lps"][0].get<double>() << ", "
                      << c["centroid_lps"][1].get<double>() << ", " << c["centroid_lps"][2].get<double>() << ")";
        if (c.contains("within")) {
            std::cout << ", within the box";
            for (const auto& f : c["within"]["faces_cut"])
                std::cout << ", cut at its " << f["face"].get<std::string>() << " face (cap " << std::setprecision(1)
                          << f["cap_area_mm2"].get<double>() << " mm2)";
        }
        std::cout << ", bounds LPS";
        for (const auto& b : c["bounds_lps"])
            std::cout << " (" << std::setprecision(1) << b[0].get<double>() << ", " << b[1].get<double>() << ", "
                      << b[2].get<double>() << ")";
        std::cout << "\n";
    }
    for (const auto& g : j["grown"]) {
        std::cout << g["surface"].get<std::string>() << " (grown from (" << std::setprecision(1)
                  << g["seed_lps"][0].get<double>() << ", " << g["seed_lps"][1].get<double>() << ", "
                  << g["seed_lps"][2].get<double>() << ") through " << g["range"][0].get<double>() << " to "
                  << g["range"][1].get<double>() << "): " << g["voxels"].get<std::size_t>() << " voxels, volume "
                  << std::setprecision(3) << g["volume_ml"].get<double>() << " mL +- "
                  << g["partial_volume_ml"].get<double>() << " (partial volume), surface " << std::setprecision(1)
                  << g["surface_area_mm2"].get<double>() << " mm2 enclosing " << std::setprecision(3)
                  << g["surface_volume_ml"].get<double>() << " mL, largest diameter " << std::setprecision(1)
                  << g["largest_diameter_mm"].get<double>() << " mm"
                  << (g["reached_box"].get<bool>() ? ", stopped at the box" : "")
                  << (g["reached_volume_border"].get<bool>() ? ", reached the volume's edge" : "") << "\n";
    }
    for (const auto& g : j["surface_distances"]) {
        const auto& p = g["points"];
        std::cout << "distance " << g["surfaces"][0].get<std::string>() << " to " << g["surfaces"][1].get<std::string>()
                  << ": " << std::setprecision(3) << g["distance_mm"].get<double>() << " mm"
                  << (g["touching"].get<bool>() ? " (they touch or cross)" : "") << ", between ("
                  << p[0][0].get<double>() << ", " << p[0][1].get<double>() << ", " << p[0][2].get<double>()
                  << ") and (" << p[1][0].get<double>() << ", " << p[1][1].get<double>() << ", "
                  << p[1][2].get<double>() << ")\n";
    }
}

// The input's scene: a session's (--session: its surfaces and the parts
// made in it, made again), or INPUT with the --iso surfaces.
std::unique_ptr<iso::core::Scene> open_scene(const MeasureArgs& a) {
    if (!a.session.empty()) {
        if (!a.in.empty())
            throw iso::Error("--session", "the session names its input: give INPUT or --session, not both");
        if (!a.isos.empty())
            throw iso::Error("--session", "the session names its surfaces: --iso is not taken with it");
        return std::move(iso::core::open_session(a.session, progress_bar()).scene);
    }
    if (a.in.empty()) throw iso::Error("isoscope measure", "give INPUT (a volume, DICOM folder or mesh) or --session");
    auto scene = std::make_unique<iso::core::Scene>();
    // Values at points, distances, angles and grown regions need no isosurface.
    const bool without_surfaces = !a.grow_from.empty() || !a.values.empty() || !a.distance.empty() || !a.angle.empty();
    open_input(*scene, a.in, a.series, a.isos, {}, "measure", without_surfaces);
    return scene;
}

// Each surface that is a part (a session's: isolated, cut, grown) gets its
// making and shape as "part" (core::part_json).
void add_parts(const iso::core::Scene& scene, const std::vector<iso::core::SurfaceMeasurement>& surfaces,
               nlohmann::json& j) {
    for (std::size_t i = 0; i < surfaces.size(); ++i)
        if (auto part = iso::core::part_json(scene, surfaces[i].surface, surfaces[i].measures.closed); !part.is_null())
            j["surfaces"][i]["part"] = std::move(part);
}

void print_part(const nlohmann::json& p) {
    std::cout << "  part:";
    for (const auto& step : p["made"]) std::cout << " " << step.begin().key();
    if (p.contains("grown_from"))
        std::cout << " grown from (" << std::setprecision(1) << p["grown_from"][0].get<double>() << ", "
                  << p["grown_from"][1].get<double>() << ", " << p["grown_from"][2].get<double>() << ") through "
                  << p["grown_range"][0].get<double>() << " to " << p["grown_range"][1].get<double>();
    std::cout << "; largest diameter " << std::setprecision(1) << p["largest_diameter_mm"].get<double>() << " mm";
    if (!p["centroid_lps"].is_null())
        std::cout << ", centroid LPS (" << p["centroid_lps"][0].get<double>() << ", "
                  << p["centroid_lps"][1].get<double>() << ", " << p["centroid_lps"][2].get<double>() << ")";
    std::cout << "\n";
}

int run_measure(const MeasureArgs& a) {
    iso::core::PointMeasurements points;
    for (std::size_t i = 0; i + 1 < a.distance.size(); i += 2)
        points.distances.push_back({iso::core::parse_point("--distance", a.distance[i]),
                                    iso::core::parse_point("--distance", a.distance[i + 1])});
    for (std::size_t i = 0; i + 2 < a.angle.size(); i += 3)
        points.angles.push_back({iso::core::parse_point("--angle", a.angle[i]),
                                 iso::core::parse_point("--angle", a.angle[i + 1]),
                                 iso::core::parse_point("--angle", a.angle[i + 2])});
    for (const auto& t : a.values) points.values.push_back(iso::core::parse_point("--value", t));
    if (!a.out.empty()) {
        const std::string suffix = ".mrk.json";
        if (a.out.size() < suffix.size() || a.out.compare(a.out.size() - suffix.size(), suffix.size(), suffix) != 0)
            throw iso::Error("--output", "markups are written as .mrk.json, got '" + a.out + "'");
        iso::check_writable_destination(a.out);
    }
    // Checked before any work: a wrong name fails at once, not after the structures.
    if (!a.label_map.empty()) {
        iso::core::label_map_table(a.label_map, "--label-map");
        iso::check_writable_destination(a.label_map);
    }
    std::unique_ptr<iso::core::Scene> owned = open_scene(a);
    iso::core::Scene& scene = *owned;
    const auto surfaces = iso::core::measure_surfaces(scene);
    auto j = iso::core::measure_json(scene, surfaces, points);
    add_parts(scene, surfaces, j);
    iso::MarkupsFile markups = iso::core::point_markups(scene, points);
    const auto structures = measure_structures(scene, a, markups);
    j["components"] = structures["components"];
    j["surface_distances"] = structures["surface_distances"];
    j["grown"] = structures["grown"];
    if (structures.contains("label_map")) j["label_map"] = structures["label_map"];
    if (!a.out.empty()) iso::save_markups(markups, a.out);
    if (a.json) {
        std::cout << j.dump(2) << "\n";
    } else {
        std::cout << std::fixed;
        for (const auto& s : j["surfaces"]) {
            std::cout << s["surface"].get<std::string>() << ": area " << std::setprecision(1)
                      << s["area_mm2"].get<double>() << " mm2";
            if (!s["area_uncertainty_mm2"].is_null()) std::cout << " +- " << s["area_uncertainty_mm2"].get<double>();
            const std::string kind = s["volume_kind"].get<std::string>();
            if (s["volume_ml"].is_null())
                std::cout << ", volume undefined (" << kind << ")";
            else
                std::cout << ", " << volume_text(s) << std::setprecision(3);
            if (!s["volume_uncertainty_ml"].is_null()) std::cout << " +- " << s["volume_uncertainty_ml"].get<double>();
            if (!s["volume_extrapolated_ml"].is_null() && kind == "enclosed")
                std::cout << " (extrapolated to zero voxel size: " << s["volume_extrapolated_ml"].get<double>() << ")";
            if (s["closed"].get<bool>())
                std::cout << ", closed";
            else
                std::cout << ", open (boundary " << std::setprecision(1) << s["boundary"]["length_mm"].get<double>()
                          << " mm)";
            std::cout << ", " << s["components"].size() << " component(s)\n";
            if (s.contains("part")) print_part(s["part"]);
            for (const auto& w : s["warnings"]) std::cout << "  note: " << w.get<std::string>() << "\n";
        }
        for (const auto& d : j["distances"])
            std::cout << "distance " << std::setprecision(3) << d["distance_mm"].get<double>() << " mm\n";
        for (const auto& an : j["angles"])
            std::cout << "angle " << std::setprecision(3) << an["angle_deg"].get<double>() << " deg\n";
        for (const auto& v : j["values"]) {
            if (v["value"].is_null()) {
                std::cout << "value: outside the volume\n";
            } else {
                const std::string unit = v["unit"].is_null() ? "" : v["unit"].get<std::string>();
                std::cout << iso::core::value_readout(v["value"].get<double>(), unit) << "\n";
            }
        }
        print_structures(structures);
        if (structures.contains("label_map")) {
            const auto& m = structures["label_map"];
            const std::size_t n = m["labels"].size();
            std::cout << "label map: " << m["file"].get<std::string>() << " (" << n << (n == 1 ? " label" : " labels")
                      << "), colour table " << m["color_table"].get<std::string>() << "\n";
        }
    }
    if (!a.out.empty()) std::cerr << "markups -> " << a.out << "\n";
    return 0;
}

// An option given any number of times, `values` values each time, all kept.
template <class T> void repeatable(CLI::App* c, const std::string& name, T& into, const std::string& help, int values) {
    c->add_option(name, into, help)->expected(values)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

} // namespace

RunFn add_measure(CLI::App& cmd, char*) {
    const auto args = std::make_shared<MeasureArgs>();
    MeasureArgs& a = *args;
    CLI::App* c = &cmd;
    c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")");
    c->add_option("--session", a.session,
                  "Measure a session's surfaces instead (a desktop app's .json): its isosurfaces and the parts made in "
                  "it (isolated, cut by a box or the scissors, grown), each part with how it was made, its largest "
                  "diameter and centroid");
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    repeatable(c, "--distance", a.distance, "Distance between two points: --distance X,Y,Z X,Y,Z (LPS mm; repeatable)",
               2);
    repeatable(c, "--angle", a.angle, "Angle at the middle of three points: --angle P1 P2 P3 (repeatable)", 3);
    // --hu is the option's earlier name: scripts that use it keep working.
    repeatable(c, "--value,--hu", a.values, "The volume's value (HU for CT) at a point X,Y,Z (repeatable)", 1);
    repeatable(c, "--component-at", a.component_at,
               "Isolate and measure the connected component of the surface nearest to X,Y,Z (LPS mm; repeatable)", 1);
    repeatable(c, "--within", a.within,
               "Of --component-at, only the part inside an LPS box, cut at its faces and capped: "
               "box=x0,y0,z0,x1,y1,z1 (mm), or none; one for every --component-at, or one each",
               1);
    repeatable(c, "--grow-from", a.grow_from,
               "Grow a region from the seed X,Y,Z (LPS mm) through the voxels joined to it whose values are in "
               "--grow-range, and measure it (named \"grown N\"; repeatable)",
               1);
    repeatable(c, "--grow-range", a.grow_range, "The values a region grows through: LO,HI (one for all, or one each)",
               1);
    repeatable(c, "--grow-within", a.grow_within,
               "Limit a grown region to an LPS box: box=x0,y0,z0,x1,y1,z1 or none (one for all, or one each)", 1);
    c->add_option(
        "--label-map", a.label_map,
        "Write the structures (--component-at, --grow-from) as a label map on the volume's grid, 1, 2, ... in "
        "order (NIfTI .nii/.nii.gz, LPS; 3D Slicer loads it as a segmentation), with its colour table (.ctbl)");
    repeatable(c, "--surface-distance", a.surface_distance,
               "Shortest distance between two surfaces: --surface-distance A B, each a surface's name (\"iso 500\") "
               "or a point X,Y,Z meaning the component nearest to it (repeatable)",
               2);
    c->add_flag("--json", a.json, "Print JSON");
    c->add_option("-o,--output", a.out, "Write the points, distances and angles as 3D Slicer markups (.mrk.json, LPS)");
    return [args] { return run_measure(*args); };
}

} // namespace iso::cli
