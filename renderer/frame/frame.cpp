// The frame vocabulary's names and checks (frame.hpp).
#include "renderer/frame/frame.hpp"

#include <cmath>
#include <utility>

#include "io/error.hpp"

namespace iso {

Aov aov_from_name(const std::string& n) {
    if (n == "depth") return Aov::Depth;
    if (n == "normal") return Aov::Normal;
    if (n == "id") return Aov::Id;
    if (n == "ao") return Aov::Ao;
    if (n.empty() || n == "none") return Aov::None;
    throw Error("AOV", "unknown AOV '" + n + "' (depth, normal, id, ao)");
}

namespace {

constexpr std::pair<AoMethod, const char*> kAoMethods[] = {
    {AoMethod::Off, "off"}, {AoMethod::Cone, "cone"}, {AoMethod::Disk, "disk"}, {AoMethod::Raytraced, "raytraced"}};

// A range check whose error names the setting and shows the number as given.
void check_range(const char* setting, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi))
        throw Error(setting, "expected " + number_text(lo) + ".." + number_text(hi) + ", got " + number_text(v));
}

} // namespace

const char* ao_method_name(AoMethod m) {
    for (const auto& [method, name] : kAoMethods)
        if (method == m) return name;
    return "off";
}

AoMethod ao_method_from_name(const std::string& name) {
    for (const auto& [method, n] : kAoMethods)
        if (name == n) return method;
    if (name == "reference") return AoMethod::Raytraced; // the former name
    throw Error("ambient occlusion", "method must be off, cone, disk or raytraced, got '" + name + "'");
}

void validate(const FrameLook& look) {
    for (const float c : {look.background.r, look.background.g, look.background.b})
        if (!std::isfinite(c)) throw Error("background", "colour components must be finite numbers");
    if (!(look.oit_epsilon >= 0.0f && look.oit_epsilon < 1.0f))
        throw Error("transparency epsilon", "must be at least 0 and below 1, got " + std::to_string(look.oit_epsilon));
    check_range("transparency memory", look.oit_memory_mib, 1.0, 65536.0);
    check_range("ambient occlusion frames", look.ao_frames, 1, 4096);
    check_range("ambient occlusion rays", look.ao_rays, 1, 1 << 20);
    const int s = look.aa.samples;
    if (s != 1 && s != 2 && s != 4 && s != 8)
        throw Error("anti-aliasing samples", "expected 1 (off), 2, 4 or 8, got " + std::to_string(s));
    check_range("anti-aliasing frames", look.aa.frames, 1, 4096);
    check_range("anti-aliasing view frames", look.aa.view_frames, 1, 4096);
    check_range("anti-aliasing tolerance", look.aa.tolerance, 0.0, 1.0);
    check_range("anti-aliasing normal cosine", look.aa.normal_cos, -1.0, 1.0);
    validate(look.volume);
    if (int(look.clip.half_spaces().size()) > kMaxClipHalfSpaces)
        throw Error("clip", "at most " + std::to_string(kMaxClipHalfSpaces - 6) + " planes");
    check_range("ambient occlusion error", look.ao_error, 1e-4, 0.5);
    check_range("level-of-detail error", look.lod.error_px, 0.01, 64.0);
    check_range("level-of-detail error while moving", look.lod.moving_error_px, 0.01, 64.0);
    // A method's settings are checked when it is asked for (the cone's
    // radius is every method's R; disk frames trace translucent surfaces'
    // AO with the cone's settings).
    if (look.ao != AoMethod::Off) validate(look.cone);
    if (look.ao == AoMethod::Disk) validate(look.disk);
}

} // namespace iso
