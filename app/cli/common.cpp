// The parts of the command line that every command uses (common.hpp).
#include "app/cli/common.hpp"

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <unistd.h>

#include "renderer/core/api.hpp"
#include "renderer/core/stream_mesh.hpp"
#include "renderer/frame/ao_settings.hpp"

namespace iso::cli {

std::string human_bytes(double b) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (b >= 1024.0 && u < 4) {
        b /= 1024.0;
        ++u;
    }
    std::ostringstream os;
    os << std::fixed << std::setprecision(u ? 1 : 0) << b << ' ' << unit[u];
    return os.str();
}

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

namespace {
// The flag of a setting or operation the core names in `where` (unchanged if none).
std::string flag_of(std::string where) {
    static const std::pair<std::string, std::string> flags[] = {
        {"patient view", "--view"},
        {"AOV", "--aov"},
        {"ao AOV", "--aov ao"},
        {"ambient occlusion", "--ao"},
        {"ray-traced AO", "--ao raytraced"},
        {"ambient occlusion frames", "--ao-frames"},
        {"ambient occlusion rays", "--ao-rays"},
        {"ambient occlusion error", "--ao-error"},
        {"cone AO setting radius", "--ao-radius"},
        {"disk AO setting blend_min", "--ao-disk-blend"},
        {"disk AO setting blend_max", "--ao-disk-blend"},
        {"anti-aliasing samples", "--aa-samples"},
        {"anti-aliasing frames", "--aa-frames"},
        {"anti-aliasing tolerance", "--aa-tolerance"},
        {"transparency epsilon", "--oit-epsilon"},
        {"transparency memory", "--oit-memory"},
        {"background", "--background"},
        {"smoothing factor", "--smooth"},
        {"decimation fraction", "--decimate"},
        {"largest component", "--largest"},
        {"DICOM series", "--series"},
        // Volume rendering (renderer/volume/transfer_function.hpp).
        {"transfer function", "--volume"},
        {"volume mode", "--volume-mode"},
        {"volume step", "--volume-step"},
        {"clip", "--clip"},
        // The streaming engine's settings (renderer/surface/stream_plan.cpp).
        {"memory budget", "--memory"},
        {"chunk size", "--chunk"},
    };
    // The AO settings' tables (renderer/frame/ao_settings.hpp) name each setting's option.
    const auto map_table = [&where](const auto& table, const std::string& prefix) {
        if (where.rfind(prefix, 0) != 0) return;
        for (const auto& t : table)
            if (where.substr(prefix.size()) == t.name && *t.option) where = std::string("--") + t.option;
    };
    map_table(iso::cone_ao_settings(), iso::kConeAoSettingPrefix);
    map_table(iso::disk_ao_settings(), iso::kDiskAoSettingPrefix);
    for (const auto& [core, flag] : flags)
        if (where == core) where = flag;
    return where;
}
} // namespace

// The core names operations and settings in its errors; on the command line
// they are flags.
std::string cli_message(const iso::Error& e) {
    const std::string where = flag_of(e.where());
    return where.empty() ? e.reason() : where + ": " + e.reason();
}

std::string cli_text(const std::string& message) {
    const auto colon = message.find(": ");
    if (colon == std::string::npos) return message;
    return flag_of(message.substr(0, colon)) + message.substr(colon);
}

std::size_t memory_bytes_option(double mib) {
    return mib > 0 ? std::size_t(mib * 1048576.0) : iso::core::default_memory_budget();
}

void print_warnings(const std::vector<std::string>& warnings, const std::string& prefix) {
    for (const auto& w : warnings) std::cerr << "warning: " << (prefix.empty() ? "" : prefix + ": ") << w << "\n";
}

void add_look_options(CLI::App* cmd, Look& l) {
    cmd->add_option("--opacity", l.opacity,
                    "Surface opacity 0..1, repeatable in the order of --iso (translucent: VOIT)")
        ->check(CLI::Range(0.0, 1.0))
        ->allow_extra_args(false);
    cmd->add_option("--color", l.color, "Surface colour '#rrggbb' (sRGB), repeatable in the order of --iso")
        ->allow_extra_args(false);
    cmd->add_option("--background", l.background, "Background colour '#rrggbb' (sRGB)");
    cmd->add_option("--shading", l.shading, "lit, or flat (each surface its colour: no lighting, no AO)")
        ->check(CLI::IsMember({"lit", "flat"}));
}

glm::vec3 hex_option(const std::string& flag, const std::string& text) {
    try {
        return iso::core::linear_from_hex(text);
    } catch (const iso::Error& e) {
        throw iso::Error(flag, e.reason());
    }
}

// Opens the input of `render` and `view`: a mesh, or a volume and its
// isosurfaces (--iso required), and gives the surfaces their look.
void open_input(iso::core::Scene& scene, const std::string& input, const std::string& series,
                const std::vector<double>& isos, const Look& look, const std::string& command, bool volume_rendering) {
    iso::LoadOptions lo;
    lo.series = series;
    lo.progress = progress_bar();
    scene.open(input, lo);
    std::vector<iso::core::SurfaceId> in_order; // as the user gave them
    if (scene.has_volume()) {
        for (const auto& w : scene.volume().meta.warnings) std::cerr << "warning: " << w << "\n";
        if (isos.empty() && !volume_rendering)
            throw iso::Error("isoscope " + command, input + " is a volume: give --iso V (repeatable) or --volume TF");
        const auto ids =
            isos.empty() ? std::vector<iso::core::SurfaceId>{} : scene.add_isosurfaces(isos, {}, {}, progress_bar());
        for (const auto id : ids)
            for (const auto& w : scene.mesh(id).warnings)
                std::cerr << "warning: " << scene.info(id).name << ": " << w << "\n";
        for (const double v : isos)
            for (const auto id : ids)
                if (scene.info(id).value == v) in_order.push_back(id);
    } else {
        in_order = scene.surfaces();
    }
    const auto per_surface = [&](const char* flag, std::size_t n) {
        if (n > in_order.size())
            throw iso::Error(flag, std::to_string(n) + " given for " + std::to_string(in_order.size()) + " surface(s)");
    };
    per_surface("--opacity", look.opacity.size());
    per_surface("--color", look.color.size());
    for (std::size_t i = 0; i < look.opacity.size(); ++i) scene.info(in_order[i]).opacity = float(look.opacity[i]);
    for (std::size_t i = 0; i < look.color.size(); ++i)
        scene.info(in_order[i]).color = hex_option("--color", look.color[i]);
}

} // namespace iso::cli
