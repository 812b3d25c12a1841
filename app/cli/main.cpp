// isoscope command-line interface. Parses arguments, calls the core API,
// prints. No algorithms live here.
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "renderer/core/api.hpp"

namespace {

std::string human_bytes(double b) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (b >= 1024.0 && u < 4) { b /= 1024.0; ++u; }
    std::ostringstream os;
    os << std::fixed << std::setprecision(u ? 1 : 0) << b << ' ' << unit[u];
    return os.str();
}

void print_info(const nlohmann::json& j, std::ostream& os) {
    os << "source:    " << j["source"].get<std::string>() << "\n";
    os << "format:    " << j["format"].get<std::string>() << " (" << j["storage"].get<std::string>() << ")\n";
    os << "dims:      " << j["dims"][0] << " x " << j["dims"][1] << " x " << j["dims"][2] << "\n";
    os << "type:      " << j["type"].get<std::string>() << "\n";
    os << std::setprecision(6);
    os << "spacing:   " << j["spacing"][0].get<double>() << " x " << j["spacing"][1].get<double>() << " x "
       << j["spacing"][2].get<double>() << " mm\n";
    os << "range:     [" << j["range"][0].get<double>() << ", " << j["range"][1].get<double>() << "]\n";
    os << "memory:    " << human_bytes(j["memory_bytes"].get<double>()) << "\n";
    os << "index -> LPS (mm):\n";
    for (const auto& row : j["index_to_lps"]) {
        os << "  ";
        for (const auto& x : row) os << std::setw(12) << std::fixed << std::setprecision(5) << x.get<double>() << ' ';
        os << "\n";
    }
    os << std::defaultfloat;
    const auto& m = j["metadata"];
    for (const char* key : {"modality", "patient_name", "patient_id", "series_uid", "series_description"})
        if (!m[key].get<std::string>().empty()) os << key << ": " << m[key].get<std::string>() << "\n";
    if (j.contains("series")) {
        os << "series in " << j["source"].get<std::string>() << ":\n";
        int i = 0;
        for (const auto& s : j["series"]) {
            os << (i == j["selected_series"].get<int>() ? " *" : "  ") << "[" << i << "] "
               << s["modality"].get<std::string>() << " #" << s["number"] << " " << s["dims"][0] << "x"
               << s["dims"][1] << "x" << s["dims"][2] << " (" << s["files"] << " files) "
               << s["description"].get<std::string>() << "  " << s["uid"].get<std::string>() << "\n";
            ++i;
        }
    }
    for (const auto& w : j["warnings"]) os << "warning: " << w.get<std::string>() << "\n";
}

// A progress bar on stderr when it is a terminal; silent otherwise.
iso::ProgressFn progress_bar() {
    if (!isatty(STDERR_FILENO)) return {};
    return [last = -1](double f, std::string_view stage) mutable {
        int pct = static_cast<int>(f * 100.0 + 0.5);
        if (pct == last) return true;
        last = pct;
        const int width = 30, filled = pct * width / 100;
        std::fprintf(stderr, "\r%-24.*s [%.*s%*s] %3d%%", static_cast<int>(stage.size()), stage.data(), filled,
                     "##############################", width - filled, "", pct);
        if (pct >= 100) std::fputc('\n', stderr);
        std::fflush(stderr);
        return true;
    };
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"isoscope: inspect CT volumes, reconstruct and render isosurfaces"};
    app.set_version_flag("--version", std::string("isoscope ") + iso::core::version());
    app.require_subcommand(1);

    std::string info_path, info_series;
    bool info_json = false;
    auto* info = app.add_subcommand("info", "Describe a volume: dimensions, type, spacing, range, index->LPS affine");
    info->add_option("path", info_path, "Volume file or DICOM folder")->required();
    info->add_option("--series", info_series, "DICOM series to load: index in the listing or SeriesInstanceUID");
    info->add_flag("--json", info_json, "Print one JSON object");

    CLI11_PARSE(app, argc, argv);

    try {
        if (*info) {
            iso::LoadOptions opt;
            opt.series = info_series;
            opt.progress = progress_bar();
            const auto v = iso::core::open_volume(info_path, opt);
            const auto j = iso::core::describe(v);
            if (info_json)
                std::cout << j.dump(2) << "\n";
            else
                print_info(j, std::cout);
        }
    } catch (const iso::Error& e) {
        std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "isoscope: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
