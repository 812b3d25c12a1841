// `isoscope pick`: what is seen at a pixel of the image `render` writes
// with the same options (core::pick; docs/picking.md).
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/cli/commands.hpp"
#include "app/cli/frame_options.hpp"
#include "renderer/core/pick.hpp"
#include "renderer/core/value_unit.hpp"

namespace iso::cli {

namespace {

struct PickArgs {
    FrameArgs frame;
    std::string at, rect;
    double threshold = 0.5;
    bool all_layers = false, json = false;
};

std::vector<int> ints(const std::string& flag, const std::string& text, std::size_t n) {
    std::vector<int> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            std::size_t used = 0;
            v.push_back(std::stoi(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            v.clear();
            break;
        }
    }
    if (v.size() != n)
        throw iso::Error(flag, "expected " + std::to_string(n) + " integers separated by commas, got '" + text + "'");
    return v;
}

int run_pick(const PickArgs& a) {
    const iso::core::RenderRequest req = frame_request(a.frame);
    iso::core::PickRequest p;
    const auto at = ints("--at", a.at, 2);
    p.x = at[0];
    p.y = at[1];
    if (!a.rect.empty()) {
        const auto r = ints("--rect", a.rect, 4);
        if (r[2] < 1 || r[3] < 1)
            throw iso::Error("--rect", "width and height must be at least 1, got '" + a.rect + "'");
        p.rect = {r[0], r[1], r[2], r[3]};
    }
    p.threshold = a.threshold;
    p.all_layers = a.all_layers;
    iso::core::Scene scene;
    open_input(scene, a.frame.in, req.series, req.isos, a.frame.look, "pick", req.look.volume.enabled);
    const auto r = iso::core::pick(scene, req, p);
    if (!r.complete) std::cerr << "warning: the pick's lists overflowed: some layers are missing\n";
    if (a.json) {
        std::cout << iso::core::pick_json(r).dump(2) << "\n";
        return 0;
    }
    std::cout << "pixel " << r.x << "," << r.y << " of " << r.width << "x" << r.height << ": ";
    if (!r.visible)
        std::cout << "background\n";
    else
        std::cout << r.layers[*r.visible].name << "\n";
    std::cout << std::fixed;
    for (std::size_t i = 0; i < r.layers.size(); ++i) {
        const auto& l = r.layers[i];
        std::cout << (r.visible && *r.visible == i ? "* " : "  ") << std::setw(10) << std::left << l.name << std::right
                  << std::setprecision(2) << " LPS (" << l.lps.x << ", " << l.lps.y << ", " << l.lps.z << ") mm, depth "
                  << l.depth_mm << " mm, alpha " << std::setprecision(3) << l.alpha;
        if (!l.volume) std::cout << ", share " << l.share; // the volume's layer is a point inside it, not a fragment
        if (l.value) std::cout << ", " << iso::core::value_readout(*l.value, l.unit);
        if (l.voxel) std::cout << ", voxel (" << (*l.voxel)[0] << ", " << (*l.voxel)[1] << ", " << (*l.voxel)[2] << ")";
        if (!l.volume) std::cout << ", triangle " << l.triangle;
        std::cout << "\n";
    }
    if (r.rect.width > 0) std::cout << r.triangles.size() << " triangles visible in the rectangle\n";
    return 0;
}

} // namespace

RunFn add_pick(CLI::App& cmd, char*) {
    const auto args = std::make_shared<PickArgs>();
    PickArgs& a = *args;
    CLI::App* c = &cmd;
    add_frame_options(c, a.frame);
    c->add_option("--at", a.at, "Pixel X,Y from the image's top-left")->required();
    c->add_option("--rect", a.rect, "Also list the triangles visible in the rectangle X,Y,W,H");
    c->add_option(
         "--threshold", a.threshold,
         "Where the click lands: the first surface whose own opacity reaches this, else the nearest (default 0.5)")
        ->check(CLI::Range(0.0, 1.0));
    c->add_flag("--all-layers", a.all_layers, "List every layer down to the first opaque one");
    c->add_flag("--json", a.json, "Print JSON");
    return [args] { return run_pick(*args); };
}

} // namespace iso::cli
