#include "renderer/frame/annotations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
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
glm::vec3 default_markup_color(MarkupType t) {
    switch (t) {
    case MarkupType::Fiducial: return {1.0f, 0.5f, 0.5f}; // Slicer's default selected colour
    case MarkupType::Line: return {0.35f, 0.85f, 1.0f};
    case MarkupType::Angle: return {0.55f, 1.0f, 0.35f};
    case MarkupType::Curve:
    case MarkupType::ClosedCurve: return {1.0f, 0.65f, 0.25f};
    }
    return glm::vec3(1.0f);
}
} // namespace

std::string markup_measurement_text(const Markup& m) {
    const bool line = m.type == MarkupType::Line;
    if (!line && m.type != MarkupType::Angle) return {};
    // The file's value when it is in the units drawn; a disabled one is still a value Slicer computed.
    std::optional<double> value;
    for (const auto& meas : m.measurements) {
        const bool units =
            line ? (meas.units.empty() || meas.units == "mm")
                 : (meas.units.empty() || meas.units == "deg" || meas.units == "degree" || meas.units == "\xC2\xB0");
        if (meas.name == (line ? "length" : "angle") && meas.value && units) {
            value = meas.value;
            break;
        }
    }
    if (!value)
        if (const auto c = computed_measurement(m)) value = c->value;
    if (!value || !std::isfinite(*value)) return {};
    char b[64];
    std::snprintf(b, sizeof b, line ? "%.1f mm" : "%.1f\xC2\xB0", *value);
    return b;
}

glm::vec3 markup_color(const Markup& m, int point) {
    bool selected = false;
    if (point >= 0 && std::size_t(point) < m.points.size()) selected = m.points[std::size_t(point)].selected;
    if (point < 0)
        for (const auto& p : m.points) selected = selected || (p.selected && p.status == PositionStatus::Defined);
    const auto& c = selected ? m.selected_color : m.color;
    return c ? glm::clamp(glm::vec3(*c), 0.0f, 1.0f) : default_markup_color(m.type);
}

namespace {

// Text as stb_easy_font draws it: printable ASCII, the degree sign drawn
// by hand. Other bytes (UTF-8 in Slicer's labels) would index its tables
// out of bounds; each other character becomes one '?'.
struct TextRun {
    std::string ascii;
    bool degree_after = false; // a degree sign follows this run
};
std::vector<TextRun> text_runs(const std::string& s) {
    std::vector<TextRun> runs(1);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c == 0xC2 && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) == 0xB0) {
            runs.back().degree_after = true;
            runs.emplace_back();
            ++i;
        } else if (c >= 32 && c < 127) {
            runs.back().ascii += char(c);
        } else if (c < 0x80 || c >= 0xC0) { // a control character, or the first byte of a UTF-8 sequence
            runs.back().ascii += '?';
        }
    }
    return runs;
}
constexpr float kDegreeAdvance = 4.0f; // the hand-drawn degree sign: a 3x3 ring and a gap

float text_width(const std::string& s, float size) {
    float w = 0;
    for (auto& r : text_runs(s))
        w += float(stb_easy_font_width(r.ascii.data())) + (r.degree_after ? kDegreeAdvance : 0.0f);
    return w * size;
}

struct Builder {
    std::vector<OverlayVertex>& out;
    // What the vertices being added carry for the overlay pass's depth
    // comparison (OverlayVertex); the defaults are a 2D annotation's.
    glm::vec2 anchor{-1.0f};
    float inv_depth = 0.0f, hidden_alpha = 1.0f;

    void vertex(glm::vec2 p, glm::vec4 col) { out.push_back({p, col, anchor, inv_depth, -1.0f, hidden_alpha}); }
    void quad(glm::vec2 a, glm::vec2 b, glm::vec2 c, glm::vec2 d, glm::vec4 col) {
        for (const glm::vec2& p : {a, b, c, a, c, d}) vertex(p, col);
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
        float x = 0;
        for (auto& run : text_runs(s)) {
            const int quads = stb_easy_font_print(x, 0, run.ascii.data(), nullptr, buf.data(), int(buf.size()));
            const float* v = reinterpret_cast<const float*>(buf.data());
            for (int q = 0; q < quads; ++q) {
                glm::vec2 p[4];
                for (int k = 0; k < 4; ++k) p[k] = at + glm::vec2(v[(q * 4 + k) * 4], v[(q * 4 + k) * 4 + 1]) * size;
                quad(p[0], p[1], p[2], p[3], col);
            }
            x += float(stb_easy_font_width(run.ascii.data()));
            if (run.degree_after) { // a ring at the top of the line, as the font would draw it
                const auto r = [&](float x0, float y0, float x1, float y1) {
                    rect(at + glm::vec2(x + x0, y0) * size, at + glm::vec2(x + x1, y1) * size, col);
                };
                r(0, 0, 3, 1);
                r(0, 2, 3, 3);
                r(0, 1, 1, 2);
                r(2, 1, 3, 2);
                x += kDegreeAdvance;
            }
        }
    }
    // Text with a dark shadow; a markup's shadow vanishes when it is hidden.
    void shadowed_text(const std::string& s, glm::vec2 at, float size, glm::vec4 col = {1, 1, 0.92f, 1}) {
        const float keep = hidden_alpha;
        hidden_alpha = 0.0f;
        text(s, at + glm::vec2(size * 0.6f), size, {0, 0, 0, 0.75f});
        hidden_alpha = keep;
        text(s, at, size, col);
    }
};

// Draws markups into a Builder: every vertex carries the depth of the 3D
// point it draws, so the overlay pass can dim what a surface hides.
struct MarkupPainter {
    Builder& b;
    glm::dmat4 view, proj;
    int W, H;
    float s, hidden_opacity;
    double near_plane;

    // A point in the image: pixel from the top-left corner, and depth along the view axis (mm).
    struct Projected {
        glm::vec2 px;
        double depth;
    };
    Projected from_eye(const glm::dvec4& e) const {
        const glm::dvec4 c = proj * e;
        return {glm::vec2(float((c.x / c.w + 1) * 0.5 * W), float((1 - c.y / c.w) * 0.5 * H)), -e.z};
    }
    // Nothing nearer than the near plane is drawn, as for the surfaces.
    std::optional<Projected> project(const glm::dvec3& p) const {
        const glm::dvec4 e = view * glm::dvec4(p, 1.0);
        if (!(-e.z >= near_plane)) return std::nullopt;
        return from_eye(e);
    }

    // A 3D segment p..q, clipped to the near plane; `along` counts pixels
    // along a polyline (dashes continue across its segments).
    void segment(const glm::dvec3& p, const glm::dvec3& q, float width, glm::vec4 col, float hidden, float& along) {
        glm::dvec4 ep = view * glm::dvec4(p, 1.0), eq = view * glm::dvec4(q, 1.0);
        const double dp = -ep.z, dq = -eq.z;
        if (!(dp >= near_plane) && !(dq >= near_plane)) return;
        if (dp < near_plane) ep = glm::mix(ep, eq, (near_plane - dp) / (dq - dp));
        if (dq < near_plane) eq = glm::mix(eq, ep, (near_plane - dq) / (dp - dq));
        const Projected a = from_eye(ep), c = from_eye(eq);
        const glm::vec2 d = c.px - a.px;
        const float l = glm::length(d);
        const glm::vec2 n = l > 0 ? glm::vec2(-d.y, d.x) / l * (width * 0.5f) : glm::vec2(0.0f, width * 0.5f);
        const float ia = float(1.0 / a.depth), ic = float(1.0 / c.depth);
        const OverlayVertex v[4] = {{a.px + n, col, glm::vec2(-1.0f), ia, along, hidden},
                                    {c.px + n, col, glm::vec2(-1.0f), ic, along + l, hidden},
                                    {c.px - n, col, glm::vec2(-1.0f), ic, along + l, hidden},
                                    {a.px - n, col, glm::vec2(-1.0f), ia, along, hidden}};
        b.out.insert(b.out.end(), {v[0], v[1], v[2], v[0], v[2], v[3]});
        along += l;
    }
    // Polylines (each a list of 3D points): a dark outline under all of them, then the colour.
    void polylines(const std::vector<std::vector<glm::dvec3>>& lines, glm::vec3 rgb) {
        for (const bool outline : {true, false}) {
            for (const auto& pl : lines) {
                float along = 0;
                for (std::size_t i = 0; i + 1 < pl.size(); ++i)
                    segment(pl[i], pl[i + 1], outline ? 4.0f * s : 2.0f * s,
                            outline ? glm::vec4(0, 0, 0, 0.6f) : glm::vec4(rgb, 1.0f), outline ? 0.0f : hidden_opacity,
                            along);
            }
        }
    }
    // Glyphs and labels are hidden or not as a whole, by their point's pixel.
    void anchor_at(const Projected& p) {
        b.anchor = p.px;
        b.inv_depth = float(1.0 / p.depth);
        b.hidden_alpha = hidden_opacity;
    }
    void release() {
        b.anchor = glm::vec2(-1.0f);
        b.inv_depth = 0.0f;
        b.hidden_alpha = 1.0f;
    }
    // A cross, 13 px wide at scale 1, in non-overlapping bars (so that a
    // dimmed glyph is one layer of colour), over a dark outline.
    void glyph(const Projected& p, glm::vec3 rgb) {
        anchor_at(p);
        const glm::vec2 c = p.px;
        const float L = 6.0f * s, t = 1.0f * s;
        const auto cross = [&](float grow, glm::vec4 col) {
            const float l = L + grow, w = t + grow;
            b.rect(c + glm::vec2(-l, -w), c + glm::vec2(l, w), col);
            b.rect(c + glm::vec2(-w, -l), c + glm::vec2(w, -w), col);
            b.rect(c + glm::vec2(-w, w), c + glm::vec2(w, l), col);
        };
        b.hidden_alpha = 0.0f;
        cross(1.0f * s, {0, 0, 0, 0.8f});
        b.hidden_alpha = hidden_opacity;
        cross(0.0f, glm::vec4(rgb, 1.0f));
        release();
    }
    static constexpr float kTextSize = 1.6f; // times the scale: 16 px lines at scale 1, as the other labels
    // How far a label's box reaches from its centre along the unit direction `dir`.
    float box_reach(const std::string& text, glm::vec2 dir) const {
        const float size = kTextSize * s;
        return 0.5f * (std::abs(dir.x) * text_width(text, size) + std::abs(dir.y) * 7.0f * size);
    }
    // Text centred on `centre` (pixels), hidden with the point `p`.
    void label(const std::string& text, const Projected& p, glm::vec2 centre, glm::vec3 rgb) {
        if (text.empty()) return;
        anchor_at(p);
        const float size = kTextSize * s;
        b.shadowed_text(text, centre - glm::vec2(text_width(text, size), 7.0f * size) * 0.5f, size,
                        glm::vec4(rgb, 1.0f));
        release();
    }

    void draw(const Markup& m) {
        const auto& pts = m.points;
        const auto defined = [&](std::size_t i) { return i < pts.size() && pts[i].status == PositionStatus::Defined; };
        const glm::vec3 line_rgb = markup_color(m, -1);
        const std::string value = markup_measurement_text(m);
        if (m.type == MarkupType::Line && defined(0) && defined(1)) {
            polylines({{pts[0].position, pts[1].position}}, line_rgb);
            // The length above the segment's 3D midpoint.
            const auto a = project(pts[0].position), c = project(pts[1].position);
            if (const auto mid = project(0.5 * (pts[0].position + pts[1].position))) {
                glm::vec2 dir = a && c ? c->px - a->px : glm::vec2(1, 0);
                if (glm::length(dir) < 1e-3f) dir = {1, 0};
                glm::vec2 n = glm::normalize(glm::vec2(-dir.y, dir.x));
                if (n.y > 0) n = -n;
                label(value, *mid, mid->px + n * (6.0f * s + box_reach(value, n)), line_rgb);
            }
        }
        if (m.type == MarkupType::Angle && defined(0) && defined(1) && defined(2)) {
            const glm::dvec3 v = pts[1].position, u = pts[0].position - v, w = pts[2].position - v;
            std::vector<std::vector<glm::dvec3>> lines{{pts[0].position, v, pts[2].position}};
            // The arc at the vertex, in 3D, at 30 % of the shorter arm.
            const double lu = glm::length(u), lw = glm::length(w);
            const auto angle = angle_degrees(pts[0].position, v, pts[2].position);
            if (angle && *angle > 0.5 && *angle < 179.5) {
                const double th = glm::radians(*angle), r = 0.3 * std::min(lu, lw);
                std::vector<glm::dvec3> arc;
                for (int k = 0; k <= 24; ++k) {
                    const double t = k / 24.0;
                    arc.push_back(v +
                                  r * ((std::sin((1 - t) * th) * u / lu + std::sin(t * th) * w / lw) / std::sin(th)));
                }
                lines.push_back(std::move(arc));
            }
            polylines(lines, line_rgb);
            // The value beside the vertex, away from both arms.
            if (const auto pv = project(v)) {
                const auto pa = project(pts[0].position), pc = project(pts[2].position);
                glm::vec2 bis(0.0f);
                if (pa && glm::length(pa->px - pv->px) > 1e-3f) bis += glm::normalize(pa->px - pv->px);
                if (pc && glm::length(pc->px - pv->px) > 1e-3f) bis += glm::normalize(pc->px - pv->px);
                bis = glm::length(bis) > 1e-3f ? -glm::normalize(bis) : glm::vec2(0.0f, -1.0f);
                label(value, *pv, pv->px + bis * (10.0f * s + box_reach(value, bis)), line_rgb);
            }
        }
        // Control points: a glyph each (visible ones), labelled in point lists and curves.
        const bool labelled =
            m.type == MarkupType::Fiducial || m.type == MarkupType::Curve || m.type == MarkupType::ClosedCurve;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (!defined(i) || !pts[i].visible) continue;
            if (const auto p = project(pts[i].position)) {
                const glm::vec3 rgb = markup_color(m, int(i));
                glyph(*p, rgb);
                if (labelled && !pts[i].label.empty())
                    label(pts[i].label, *p, p->px + glm::vec2(10.0f * s + box_reach(pts[i].label, {1, 0}), 0.0f), rgb);
            }
        }
    }
};

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
    MarkupPainter markups{
        b, cam.view(), cam.projection(aspect), W, H, s, std::clamp(a.hidden_opacity, 0.0f, 1.0f), cam.near_plane};
    for (const auto& m : a.markups) markups.draw(m);
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
