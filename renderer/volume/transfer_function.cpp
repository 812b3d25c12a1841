// Transfer functions, presets, modes and clips (transfer_function.hpp).
#include "renderer/volume/transfer_function.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <glm/glm.hpp>

#include "io/color.hpp"
#include "io/error.hpp"

namespace iso {

namespace {

const char* const kWhere = "transfer function";

// Shortest text that reads back as the same double; plain decimals (no
// exponent) for the values transfer functions and clips hold.
std::string short_number(double v) {
    char buf[64];
    const bool plain = std::abs(v) >= 1e-4 && std::abs(v) < 1e15;
    for (int digits = plain ? 0 : 1; digits <= 17; ++digits) {
        std::snprintf(buf, sizeof buf, plain ? "%.*f" : "%.*g", digits, v);
        if (std::strtod(buf, nullptr) == v) break;
    }
    return buf;
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::string part;
    std::istringstream in(s);
    while (std::getline(in, part, sep)) out.push_back(part);
    if (!s.empty() && s.back() == sep) out.emplace_back();
    return out;
}

std::string trimmed(const std::string& s) {
    const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

double number(const std::string& text, const std::string& what, const std::string& where) {
    const std::string t = trimmed(text);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v))
        throw Error(where, what + " '" + t + "' is not a finite number");
    return v;
}

// CT presets in HU, modelled on 3D Slicer's CT-Bone, CT-AAA, CT-Skin and
// CT-Muscle, with opacities per millimetre.
struct Preset {
    const char* name;
    const char* text;
};
constexpr Preset kPresets[] = {
    {"bone", "100:0:#bb4049,250:0.15:#d89a6c,641:0.7:#e5d190,3071:0.7:#ffffff"},
    {"vessels", "140:0:#bd3412,170:0.5:#c8402a,215:0.6:#ffd6a8,420:0.8:#fff8f0,3071:0.8:#ffffff"},
    {"skin", "-700:0:#c58c6e,-300:0.08:#d9a58c,100:0.12:#e6bca4,3071:0.12:#fff0e0"},
    {"soft tissue", "-150:0:#8a2a1a,20:0.03:#c45a46,80:0.08:#e08c78,180:0:#e8c0b0"},
};

} // namespace

TransferFunction::TransferFunction(std::vector<TfPoint> points) : points_(std::move(points)) {
    if (points_.empty()) throw Error(kWhere, "has no points");
    for (std::size_t i = 0; i < points_.size(); ++i) {
        const TfPoint& p = points_[i];
        const std::string at = "point " + std::to_string(i + 1);
        if (!std::isfinite(p.value)) throw Error(kWhere, at + ": the value is not a finite number");
        if (i > 0 && p.value < points_[i - 1].value)
            throw Error(kWhere, at + ": values must not decrease (" + short_number(p.value) + " after " +
                                    short_number(points_[i - 1].value) + ")");
        if (!(p.opacity >= 0.0 && p.opacity <= 1.0))
            throw Error(kWhere, at + ": opacity per mm must be in 0..1, got " + short_number(p.opacity));
        try {
            linear_.push_back(glm::dvec3(linear_from_hex(p.color)));
        } catch (const Error& e) {
            throw Error(kWhere, at + ": " + e.reason());
        }
    }
}

TransferFunction TransferFunction::parse(const std::string& text) {
    std::vector<TfPoint> points;
    for (const std::string& item : split(text, ',')) {
        const auto f = split(trimmed(item), ':');
        if (f.size() != 3)
            throw Error(kWhere, "'" + trimmed(item) + "' is not value:opacity:#rrggbb (e.g. 300:0.2:#f0e0d0)");
        points.push_back({number(f[0], "value", kWhere), number(f[1], "opacity", kWhere), trimmed(f[2])});
    }
    return TransferFunction(std::move(points));
}

std::string TransferFunction::text() const {
    std::string s;
    for (const auto& p : points_)
        s += (s.empty() ? "" : ",") + short_number(p.value) + ":" + short_number(p.opacity) + ":" + p.color;
    return s;
}

glm::dvec4 TransferFunction::at(double v) const {
    if (points_.empty()) return glm::dvec4(0.0);
    if (!(v > points_.front().value)) return glm::dvec4(linear_.front(), points_.front().opacity);
    if (v >= points_.back().value) return glm::dvec4(linear_.back(), points_.back().opacity);
    // The last point at or below v: equal values make a step (the later one wins above it).
    const auto it =
        std::upper_bound(points_.begin(), points_.end(), v, [](double x, const TfPoint& p) { return x < p.value; });
    const std::size_t i = std::size_t(it - points_.begin()) - 1;
    const TfPoint &a = points_[i], &b = points_[i + 1];
    const double t = (v - a.value) / (b.value - a.value);
    return glm::dvec4(glm::mix(linear_[i], linear_[i + 1], t), a.opacity + t * (b.opacity - a.opacity));
}

double TransferFunction::max_opacity(double lo, double hi) const {
    if (points_.empty()) return 0;
    double m = std::max(at(lo).a, at(hi).a);
    for (const auto& p : points_)
        if (p.value > lo && p.value < hi) m = std::max(m, p.opacity);
    return m;
}

std::vector<std::string> transfer_function_presets() {
    std::vector<std::string> names;
    for (const auto& p : kPresets) names.emplace_back(p.name);
    return names;
}

TransferFunction transfer_function_from(const std::string& text) {
    for (const auto& p : kPresets)
        if (text == p.name) return TransferFunction::parse(p.text);
    if (text.find(':') == std::string::npos) {
        std::string names;
        for (const auto& p : kPresets) names += std::string(names.empty() ? "" : ", ") + p.name;
        throw Error(kWhere, "'" + text + "' is neither a preset (" + names + ") nor value:opacity:#rrggbb,...");
    }
    return TransferFunction::parse(text);
}

const char* volume_mode_name(VolumeMode m) {
    switch (m) {
    case VolumeMode::Mip: return "mip";
    case VolumeMode::Minip: return "minip";
    default: return "composite";
    }
}

VolumeMode volume_mode_from_name(const std::string& name) {
    if (name == "composite") return VolumeMode::Composite;
    if (name == "mip") return VolumeMode::Mip;
    if (name == "minip") return VolumeMode::Minip;
    throw Error("volume mode", "must be composite, mip or minip, got '" + name + "'");
}

const char* volume_integration_name(VolumeIntegration i) {
    return i == VolumeIntegration::Sampled ? "sampled" : "preintegrated";
}

VolumeIntegration volume_integration_from_name(const std::string& name) {
    if (name == "preintegrated") return VolumeIntegration::Preintegrated;
    if (name == "sampled") return VolumeIntegration::Sampled;
    throw Error("volume integration", "must be preintegrated or sampled, got '" + name + "'");
}

bool Clip::keeps(const glm::dvec3& p) const {
    for (const auto& h : half_spaces())
        if (glm::dot(h.normal, p) < h.offset) return false;
    return true;
}

std::vector<ClipPlane> Clip::half_spaces() const {
    std::vector<ClipPlane> out;
    if (box)
        for (int a = 0; a < 3; ++a) {
            glm::dvec3 n(0.0);
            n[a] = 1.0;
            out.push_back({n, box->first[a]});
            out.push_back({-n, -box->second[a]});
        }
    out.insert(out.end(), planes.begin(), planes.end());
    return out;
}

void Clip::add(const std::string& text) {
    const char* const where = "clip";
    const auto eq = text.find('=');
    const std::string kind = trimmed(text.substr(0, eq));
    if (eq == std::string::npos || (kind != "box" && kind != "plane"))
        throw Error(where, "'" + text + "' is neither box=x0,y0,z0,x1,y1,z1 nor plane=px,py,pz,nx,ny,nz (LPS mm)");
    const auto f = split(text.substr(eq + 1), ',');
    if (f.size() != 6) throw Error(where, "'" + text + "' needs 6 numbers, got " + std::to_string(f.size()));
    double v[6];
    for (int i = 0; i < 6; ++i) v[i] = number(f[std::size_t(i)], "number", where);
    const glm::dvec3 a(v[0], v[1], v[2]), b(v[3], v[4], v[5]);
    if (kind == "box") {
        if (box) throw Error(where, "only one clip box");
        if (!(a.x < b.x && a.y < b.y && a.z < b.z))
            throw Error(where, "box '" + text + "': each minimum must be below its maximum");
        box = std::pair{a, b};
        return;
    }
    const double len = glm::length(b);
    if (!(len > 0)) throw Error(where, "plane '" + text + "': the normal has no length");
    if (int(half_spaces().size()) >= kMaxClipHalfSpaces)
        throw Error(where, "at most " + std::to_string(kMaxClipHalfSpaces - 6) + " planes");
    planes.push_back({b / len, glm::dot(b / len, a)});
}

std::string Clip::text() const {
    std::string s;
    auto three = [](const glm::dvec3& p) {
        return short_number(p.x) + "," + short_number(p.y) + "," + short_number(p.z);
    };
    if (box) s = "box=" + three(box->first) + "," + three(box->second);
    for (const auto& p : planes)
        s += (s.empty() ? "" : "; ") + std::string("plane=") + three(p.normal * p.offset) + "," + three(p.normal);
    return s;
}

void validate(const VolumeLook& v) {
    if (!v.enabled) return;
    if (v.tf.empty()) throw Error("volume", "has no transfer function");
    if (!(v.step >= 0.01 && v.step <= 8.0))
        throw Error("volume step", "expected 0.01..8 voxels, got " + short_number(v.step));
    if (!(v.moving_step >= 0.01 && v.moving_step <= 16.0))
        throw Error("volume step while moving", "expected 0.01..16 voxels, got " + short_number(v.moving_step));
}

double transfer_table_texel(const TransferFunction& tf) {
    const auto& pts = tf.points();
    return pts.empty() ? 0.0 : (pts.back().value - pts.front().value) / double(kTransferTableTexels - 1);
}

double gradient_reference(const TransferFunction& tf, double min_spacing) {
    const auto& pts = tf.points();
    const double span = pts.empty() ? 1.0 : std::max(pts.back().value - pts.front().value, 1e-6);
    return 0.05 * span / min_spacing;
}

std::vector<unsigned char> occupied_chunks(const VolumeLook& v, std::span<const double> mins,
                                           std::span<const double> maxs) {
    std::vector<unsigned char> out(mins.size(), 1);
    if (v.mode != VolumeMode::Composite) return out;
    const double texel = transfer_table_texel(v.tf);
    for (std::size_t i = 0; i < mins.size(); ++i)
        out[i] = v.tf.max_opacity(mins[i] - texel, maxs[i] + texel) > 0.0 ? 1 : 0;
    return out;
}

} // namespace iso
