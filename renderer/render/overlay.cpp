#include "renderer/render/overlay.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/glm.hpp>

#include <stb/stb_easy_font.h>

namespace iso {

std::string orientation_letter(const glm::dvec3& d) {
    const glm::dvec3 a = glm::abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x > 0 ? "L" : "R";
    if (a.y >= a.z) return d.y > 0 ? "P" : "A";
    return d.z > 0 ? "S" : "I";
}

double scale_bar_mm(const Camera& cam, int width, int height) {
    // mm per pixel at the target's depth, and a round length near 1/5 of the width.
    const double dist = glm::length(cam.target - cam.eye);
    const double mm_per_px = 2.0 * dist * std::tan(glm::radians(cam.fov_y_degrees) * 0.5) / double(height);
    const double want = 0.2 * width * mm_per_px;
    const double p = std::pow(10.0, std::floor(std::log10(want)));
    for (double m : {5.0, 2.0, 1.0})
        if (m * p <= want) return m * p;
    return p;
}

namespace {

struct Builder {
    std::vector<OverlayVertex>& out;
    void quad(glm::vec2 a, glm::vec2 b, glm::vec2 c, glm::vec2 d, glm::vec4 col) {
        out.insert(out.end(), {{a, col}, {b, col}, {c, col}, {a, col}, {c, col}, {d, col}});
    }
    void rect(glm::vec2 lo, glm::vec2 hi, glm::vec4 col) { quad(lo, {hi.x, lo.y}, hi, {lo.x, hi.y}, col); }
    void line(glm::vec2 a, glm::vec2 b, float w, glm::vec4 col) {
        glm::vec2 d = b - a;
        const float l = glm::length(d);
        if (l <= 0) return rect(a - w * 0.5f, a + w * 0.5f, col);
        const glm::vec2 n = glm::vec2(-d.y, d.x) / l * (w * 0.5f);
        quad(a + n, b + n, b - n, a - n, col);
    }
    // stb_easy_font: quads of 4 vertices (x, y, z, color) per glyph stroke, 10 px tall at scale 1.
    void text(const std::string& s, glm::vec2 at, float size, glm::vec4 col) {
        thread_local std::vector<char> buf(1 << 17);
        const int quads = stb_easy_font_print(0, 0, const_cast<char*>(s.c_str()), nullptr, buf.data(), int(buf.size()));
        const float* v = reinterpret_cast<const float*>(buf.data());
        for (int q = 0; q < quads; ++q) {
            glm::vec2 p[4];
            for (int k = 0; k < 4; ++k) p[k] = at + glm::vec2(v[(q * 4 + k) * 4], v[(q * 4 + k) * 4 + 1]) * size;
            quad(p[0], p[1], p[2], p[3], col);
        }
    }
    void shadowed_text(const std::string& s, glm::vec2 at, float size) {
        text(s, at + glm::vec2(size * 0.6f), size, {0, 0, 0, 0.75f});
        text(s, at, size, {1, 1, 0.92f, 1});
    }
};

float text_width(const std::string& s, float size) { return float(stb_easy_font_width(const_cast<char*>(s.c_str()))) * size; }

} // namespace

std::vector<OverlayVertex> build_overlay(const Annotations& a, const Camera& cam, int W, int H, float scale) {
    std::vector<OverlayVertex> out;
    Builder b{out};
    const float s = std::max(scale, 0.1f);
    const double aspect = double(W) / double(H);
    const glm::dmat4 vp = cam.projection(aspect) * cam.view();
    auto project = [&](const glm::dvec3& p, glm::vec2& px) {
        const glm::dvec4 c = vp * glm::dvec4(p, 1.0);
        if (c.w <= 0) return false;
        px = glm::vec2(float((c.x / c.w + 1) * 0.5 * W), float((1 - c.y / c.w) * 0.5 * H));
        return true;
    };
    const glm::vec4 line_color(1.0f, 0.85f, 0.2f, 1.0f);
    for (const auto& l : a.lines) {
        glm::vec2 p, q;
        if (project(l.a, p) && project(l.b, q)) b.line(p, q, 2.0f * s, line_color);
    }
    for (const auto& p : a.points) {
        glm::vec2 px;
        if (project(p, px)) {
            b.rect(px - 4.0f * s, px + 4.0f * s, {0, 0, 0, 0.8f});
            b.rect(px - 3.0f * s, px + 3.0f * s, line_color);
        }
    }
    for (const auto& l : a.labels) {
        glm::vec2 px;
        if (project(l.at, px)) b.shadowed_text(l.text, px + glm::vec2(6, -6) * s, 1.6f * s);
    }
    if (a.orientation) {
        const glm::dvec3 f = cam.forward(), right = glm::normalize(glm::cross(f, cam.up)), up = glm::cross(right, f);
        const float size = 2.4f * s, h = 10 * size, margin = 8 * s;
        const std::string r = orientation_letter(right), l = orientation_letter(-right), t = orientation_letter(up),
                          bo = orientation_letter(-up);
        b.shadowed_text(r, {W - margin - text_width(r, size), H * 0.5f - h * 0.5f}, size);
        b.shadowed_text(l, {margin, H * 0.5f - h * 0.5f}, size);
        b.shadowed_text(t, {W * 0.5f - text_width(t, size) * 0.5f, margin}, size);
        b.shadowed_text(bo, {W * 0.5f - text_width(bo, size) * 0.5f, H - margin - h}, size);
    }
    if (a.scale_bar) {
        const double mm = scale_bar_mm(cam, W, H);
        const double dist = glm::length(cam.target - cam.eye);
        const double px_per_mm = double(H) / (2.0 * dist * std::tan(glm::radians(cam.fov_y_degrees) * 0.5));
        const float len = float(mm * px_per_mm), x0 = 16 * s, y0 = H - 20 * s;
        b.rect({x0 - s, y0 - 4 * s - s}, {x0 + len + s, y0 + s}, {0, 0, 0, 0.75f});
        b.rect({x0, y0 - 4 * s}, {x0 + len, y0}, {1, 1, 0.92f, 1});
        char txt[32];
        std::snprintf(txt, sizeof txt, "%g mm", mm);
        b.shadowed_text(txt, {x0, y0 - 4 * s - 16 * s}, 1.4f * s);
    }
    return out;
}

} // namespace iso
