// `isoscope measure`: surfaces (area, volume, closed/open, components,
// uncertainty) and points (distance, angle, value) through the core's
// measurements (core::measure_surfaces; docs/measure.md).
#include <iomanip>
#include <iostream>
#include <memory>

#include "app/cli/commands.hpp"
#include "app/cli/common.hpp"
#include "io/atomic_file.hpp"
#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::cli {

namespace {

struct MeasureArgs {
    std::string in, series, out;
    std::vector<double> isos;
    std::vector<std::string> distance, angle, values;
    bool json = false;
};

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
    iso::core::Scene scene;
    open_input(scene, a.in, a.series, a.isos, {}, "measure");
    const auto surfaces = iso::core::measure_surfaces(scene);
    const auto j = iso::core::measure_json(scene, surfaces, points);
    if (!a.out.empty()) iso::save_markups(iso::core::point_markups(scene, points), a.out);
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
                std::cout << ", volume " << (kind == "lower bound" ? ">= " : "") << std::setprecision(3)
                          << s["volume_ml"].get<double>() << " mL";
            if (!s["volume_uncertainty_ml"].is_null()) std::cout << " +- " << s["volume_uncertainty_ml"].get<double>();
            if (!s["volume_extrapolated_ml"].is_null() && kind == "enclosed")
                std::cout << " (extrapolated to zero voxel size: " << s["volume_extrapolated_ml"].get<double>() << ")";
            if (s["closed"].get<bool>())
                std::cout << ", closed";
            else
                std::cout << ", open (boundary " << std::setprecision(1) << s["boundary"]["length_mm"].get<double>()
                          << " mm)";
            std::cout << ", " << s["components"].size() << " component(s)\n";
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
    }
    if (!a.out.empty()) std::cerr << "markups -> " << a.out << "\n";
    return 0;
}

} // namespace

RunFn add_measure(CLI::App& cmd, char*) {
    const auto args = std::make_shared<MeasureArgs>();
    MeasureArgs& a = *args;
    CLI::App* c = &cmd;
    c->add_option("input", a.in, "Volume file, DICOM folder, or mesh (" + iso::mesh_extensions_text() + ")")
        ->required();
    c->add_option("--iso", a.isos, "Iso value (repeatable) for volume inputs")->allow_extra_args(false);
    c->add_option("--series", a.series, "DICOM series to load: index or SeriesInstanceUID");
    c->add_option("--distance", a.distance, "Distance between two points: --distance X,Y,Z X,Y,Z (LPS mm; repeatable)")
        ->expected(2)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    c->add_option("--angle", a.angle, "Angle at the middle of three points: --angle P1 P2 P3 (repeatable)")
        ->expected(3)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    // --hu is the option's earlier name: scripts that use it keep working.
    c->add_option("--value,--hu", a.values, "The volume's value (HU for CT) at a point X,Y,Z (repeatable)")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    c->add_flag("--json", a.json, "Print JSON");
    c->add_option("-o,--output", a.out, "Write the points, distances and angles as 3D Slicer markups (.mrk.json, LPS)");
    return [args] { return run_measure(*args); };
}

} // namespace iso::cli
