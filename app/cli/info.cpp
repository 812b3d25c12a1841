// `isoscope info`: what a volume is (dimensions, type, spacing, range,
// index -> LPS), from its samples or from its header alone.
#include <iomanip>
#include <iostream>
#include <memory>

#include "app/cli/commands.hpp"
#include "app/cli/common.hpp"
#include "renderer/core/api.hpp"
#include "renderer/core/stream_mesh.hpp"

namespace iso::cli {

namespace {

void print_info(const nlohmann::json& j, std::ostream& os) {
    os << "source:    " << j["source"].get<std::string>() << "\n";
    os << "format:    " << j["format"].get<std::string>() << " (" << j["storage"].get<std::string>() << ")\n";
    os << "dims:      " << j["dims"][0] << " x " << j["dims"][1] << " x " << j["dims"][2] << "\n";
    os << "type:      " << j["type"].get<std::string>() << "\n";
    os << std::setprecision(6);
    os << "spacing:   " << j["spacing"][0].get<double>() << " x " << j["spacing"][1].get<double>() << " x "
       << j["spacing"][2].get<double>() << " mm\n";
    if (j["range"].is_null())
        os << "range:     not read (header only)\n";
    else
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
               << s["modality"].get<std::string>() << " #" << s["number"] << " " << s["dims"][0] << "x" << s["dims"][1]
               << "x" << s["dims"][2] << " (" << s["files"] << " files) " << s["description"].get<std::string>() << "  "
               << s["uid"].get<std::string>() << "\n";
            for (const auto& w : s["warnings"]) os << "       warning: " << w.get<std::string>() << "\n";
            ++i;
        }
    }
    for (const auto& w : j["warnings"]) os << "warning: " << w.get<std::string>() << "\n";
}

struct InfoArgs {
    std::string path, series;
    bool json = false, header_only = false;
    double memory_mib = 0;
};

int run_info(const InfoArgs& a) {
    if (a.header_only || iso::core::exceeds_budget(a.path, memory_bytes_option(a.memory_mib))) {
        const auto j = iso::core::describe_header(a.path);
        if (a.json)
            std::cout << j.dump(2) << "\n";
        else
            print_info(j, std::cout);
        return 0;
    }
    iso::LoadOptions opt;
    opt.series = a.series;
    opt.progress = progress_bar();
    const auto j = iso::core::describe(iso::core::open_volume(a.path, opt));
    if (a.json)
        std::cout << j.dump(2) << "\n";
    else
        print_info(j, std::cout);
    return 0;
}

} // namespace

RunFn add_info(CLI::App& cmd, char*) {
    const auto args = std::make_shared<InfoArgs>();
    InfoArgs& a = *args;
    CLI::App* c = &cmd;
    c->add_option("path", a.path, "Volume file or DICOM folder")->required();
    c->add_option("--series", a.series, "DICOM series to load: index in the listing or SeriesInstanceUID");
    c->add_flag("--json", a.json, "Print one JSON object");
    c->add_flag("--header-only", a.header_only,
                "Read only the header (NIfTI, NRRD, MetaImage; OpenVDB: metadata and topology): no value range");
    c->add_option("--memory", a.memory_mib,
                  "Volumes larger than this (MiB) are described from their header only "
                  "(default: a quarter of physical memory)")
        ->check(CLI::PositiveNumber);
    return [args] { return run_info(*args); };
}

} // namespace iso::cli
