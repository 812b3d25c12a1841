#include "renderer/frame/annotations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "io/color.hpp"
#include "renderer/text/contrast.hpp"
#include "renderer/text/font.hpp"
#include "renderer/text/placement.hpp"

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
    return round_length_mm(0.2 * width * mm_per_px);
}

double round_length_mm(double want) {
    if (!(want > 0) || !std::isfinite(want)) return 0;
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

std::string markup_label_text(const Markup& m, int point) {
    if (point >= 0) {
        if (std::size_t(point) >= m.points.size()) return {};
        const std::string& own = m.points[std::size_t(point)].label;
        if (m.type == MarkupType::Fiducial) return own.empty() ? m.name : own;
        return m.type == MarkupType::Curve || m.type == MarkupType::ClosedCurve ? own : std::string();
    }
    if (m.type != MarkupType::Line && m.type != MarkupType::Angle) return {};
    const std::string value = markup_measurement_text(m);
    if (m.name.empty() || value.empty()) return m.name.empty() ? value : m.name;
    return m.name + ": " + value;
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

// The colour of the text that is not a markup's: plain labels, the
// orientation letters, the scale bar's length.
const glm::vec3 kTextColor(1.0f, 1.0f, 0.92f);

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
    // A glyph's bitmap at `pixel`, texel for pixel, with the atlas channel
    // `channel` (0: coverage, 1: halo) as its alpha; always on top, never dimmed.
    void glyph_quad(glm::ivec2 pixel, glm::ivec2 texel, glm::ivec2 size, glm::vec4 col, float channel) {
        const glm::vec2 p0(pixel), p1(pixel + size), t0(texel), t1(texel + size);
        const auto v = [&](glm::vec2 p, glm::vec2 t) {
            return OverlayVertex{p, col, glm::vec2(-1.0f), 0.0f, -1.0f, 1.0f, t, channel};
        };
        const OverlayVertex q[4] = {v(p0, t0), v({p1.x, p0.y}, {t1.x, t0.y}), v(p1, t1), v({p0.x, p1.y}, {t0.x, t1.y})};
        out.insert(out.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    }
};

// How far a box of this size reaches from its centre along the unit direction `dir`.
float reach(glm::vec2 size, glm::vec2 dir) { return 0.5f * (std::abs(dir.x) * size.x + std::abs(dir.y) * size.y); }

// A label on its way into the image: laid out when added, placed among the
// others once all are known (text::place_labels), then drawn.
struct PendingLabel {
    std::string text;
    text::TextLayout layout;
    glm::vec3 color;
    glm::vec2 anchor, centre; // the point it labels; its box's centre at its default place
    bool fixed = false;
    bool legend = false;                   // a legend row
    glm::ivec2 swatch_lo{0}, swatch_hi{0}; // a legend row's opaque swatch
    glm::vec2 size() const { return glm::vec2(layout.hi - layout.lo); }
};

struct LabelSet {
    std::vector<PendingLabel> labels;
    std::vector<text::Box> obstacles; // the markups' glyphs, the scale bar: labels keep off them

    // Laid out at `px` pixels per em; the caller sets its default centre from its size.
    PendingLabel& add(const std::string& s, float px, glm::vec3 rgb, glm::vec2 anchor) {
        labels.push_back({s, text::layout_text(s, *text::overlay_font(px)), rgb, anchor, anchor});
        return labels.back();
    }
};

// Draws markups into a Builder: every vertex of their lines and glyphs
// carries the depth of the 3D point it draws, so the overlay pass can dim
// what a surface hides; their labels go to the LabelSet.
struct MarkupPainter {
    Builder& b;
    LabelSet& labels;
    glm::dmat4 view, proj;
    int W, H;
    float s, hidden_opacity, label_px;
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
    // A glyph is hidden or not as a whole, by its point's pixel.
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
        labels.obstacles.push_back({c - (L + s), c + (L + s)});
    }
    // A label of `text` for the point `p`, its box's centre `clear` pixels
    // beyond its edge along the unit direction `dir` from the point.
    void label(const std::string& text, const Projected& p, glm::vec2 dir, float clear, glm::vec3 rgb) {
        if (text.empty()) return;
        PendingLabel& l = labels.add(text, label_px, rgb, p.px);
        l.centre = p.px + dir * (clear + reach(l.size(), dir));
    }

    void draw(const Markup& m) {
        const auto& pts = m.points;
        const auto defined = [&](std::size_t i) { return i < pts.size() && pts[i].status == PositionStatus::Defined; };
        const glm::vec3 line_rgb = markup_color(m, -1);
        const std::string text = markup_label_text(m); // a Line's or an Angle's name and value
        if (m.type == MarkupType::Line && defined(0) && defined(1)) {
            polylines({{pts[0].position, pts[1].position}}, line_rgb);
            // The name and length above the segment's 3D midpoint.
            const auto a = project(pts[0].position), c = project(pts[1].position);
            if (const auto mid = project(0.5 * (pts[0].position + pts[1].position))) {
                glm::vec2 dir = a && c ? c->px - a->px : glm::vec2(1, 0);
                if (glm::length(dir) < 1e-3f) dir = {1, 0};
                glm::vec2 n = glm::normalize(glm::vec2(-dir.y, dir.x));
                if (n.y > 0) n = -n;
                label(text, *mid, n, 6.0f * s, line_rgb);
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
            // The name and value beside the vertex, away from both arms.
            if (const auto pv = project(v)) {
                const auto pa = project(pts[0].position), pc = project(pts[2].position);
                glm::vec2 bis(0.0f);
                if (pa && glm::length(pa->px - pv->px) > 1e-3f) bis += glm::normalize(pa->px - pv->px);
                if (pc && glm::length(pc->px - pv->px) > 1e-3f) bis += glm::normalize(pc->px - pv->px);
                bis = glm::length(bis) > 1e-3f ? -glm::normalize(bis) : glm::vec2(0.0f, -1.0f);
                label(text, *pv, bis, 10.0f * s, line_rgb);
            }
        }
        // Control points: a glyph each (visible ones), labelled in point lists
        // (the point's label, else the markup's name) and curves (the point's label).
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (!defined(i) || !pts[i].visible) continue;
            if (const auto p = project(pts[i].position)) {
                const glm::vec3 rgb = markup_color(m, int(i));
                glyph(*p, rgb);
                label(markup_label_text(m, int(i)), *p, {1, 0}, 10.0f * s, rgb);
            }
        }
    }
};

// A thin line in the label's colour over an outline in its halo's, from
// near the anchor to the edge of the label's box.
void leader_line(Builder& b, const LabelBox& l, float s) {
    const glm::vec2 lo(l.lo), hi(l.hi), c = 0.5f * (lo + hi), half = 0.5f * (hi - lo), d = l.anchor - c;
    // Where the segment from the box's centre to the anchor leaves the box.
    const float t =
        std::min(std::abs(d.x) > 0 ? half.x / std::abs(d.x) : 1e9f, std::abs(d.y) > 0 ? half.y / std::abs(d.y) : 1e9f);
    if (t >= 1.0f) return; // the anchor is inside the box
    const glm::vec2 edge = c + d * t, u = glm::normalize(l.anchor - edge);
    const float len = glm::length(l.anchor - edge), skip = std::min(3.0f * s, 0.5f * len);
    const glm::vec2 end = l.anchor - u * skip; // stops short of the anchor, clear of its glyph's centre
    b.line(edge, end, 3.25f * s, glm::vec4(l.halo, 1.0f));
    b.line(edge, end, 1.25f * s, glm::vec4(l.color, 1.0f));
}

// A placed label's glyphs: the halo of all of them first, then their text,
// so that no glyph's halo covers its neighbour's text; and what was drawn,
// in the label's box.
void draw_label(Builder& b, const PendingLabel& p, const text::GlyphAtlas& atlas, LabelBox& l) {
    const glm::ivec2 origin = l.lo - p.layout.lo, size = l.hi - l.lo;
    l.coverage.assign(std::size_t(size.x) * size.y, 0);
    l.halo_alpha.assign(l.coverage.size(), 0);
    for (const float channel : {1.0f, 0.0f})
        for (const auto& g : p.layout.glyphs) {
            const text::GlyphBitmap& bm = *g.bitmap;
            const glm::ivec2 at = origin + g.pen + bm.offset;
            b.glyph_quad(at, atlas.texel(&bm), {bm.width, bm.height}, glm::vec4(channel > 0 ? l.halo : l.color, 1.0f),
                         channel);
            const auto& src = channel > 0 ? bm.halo : bm.coverage;
            auto& dst = channel > 0 ? l.halo_alpha : l.coverage;
            for (int y = 0; y < bm.height; ++y)
                for (int x = 0; x < bm.width; ++x) {
                    auto& d = dst[std::size_t(at.y - l.lo.y + y) * size.x + std::size_t(at.x - l.lo.x + x)];
                    d = std::max(d, src[std::size_t(y) * bm.width + x]);
                }
        }
}

// Places the labels (text::place_labels), draws leader lines to those moved
// away from their default place, then the labels over everything else.
std::vector<LabelBox> draw_labels(Builder& b, const LabelSet& set, int W, int H, float s, text::AtlasImage& image) {
    std::vector<text::LabelRequest> req;
    for (const auto& l : set.labels) req.push_back({l.size(), l.anchor, l.centre, l.fixed});
    const auto placed = text::place_labels(req, set.obstacles, glm::vec2(W, H), 2.0f * s);
    std::vector<LabelBox> out(set.labels.size());
    text::GlyphAtlas atlas;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const PendingLabel& p = set.labels[i];
        LabelBox& l = out[i];
        l.text = p.text;
        l.lo = glm::ivec2(glm::round(placed[i].box.lo)); // whole pixels: glyphs land texel for pixel
        l.hi = l.lo + (p.layout.hi - p.layout.lo);
        l.anchor = p.fixed ? glm::vec2(l.lo + l.hi) * 0.5f : p.anchor;
        l.moved = placed[i].moved;
        l.fixed = p.fixed;
        l.legend = p.legend;
        l.swatch_lo = p.swatch_lo;
        l.swatch_hi = p.swatch_hi;
        l.color = p.color;
        l.halo = text::halo_color(p.color);
        if (l.moved) leader_line(b, l, s);
        for (const auto& g : p.layout.glyphs) atlas.add(g.bitmap);
    }
    image = atlas.pack();
    for (std::size_t i = 0; i < out.size(); ++i) draw_label(b, set.labels[i], atlas, out[i]);
    return out;
}

// The patient directions at the middle of each edge, fixed in place.
void orientation_letters(LabelSet& set, const Camera& cam, int W, int H, float px, float s) {
    const glm::dvec3 f = cam.forward(), right = glm::normalize(glm::cross(f, cam.up)), up = glm::cross(right, f);
    const float margin = 5.0f * s;
    const auto letter = [&](const glm::dvec3& dir, glm::vec2 edge, glm::vec2 inward) {
        PendingLabel& l = set.add(orientation_letter(dir), px, kTextColor, edge);
        l.centre = edge + inward * (margin + reach(l.size(), inward));
        l.fixed = true;
    };
    letter(right, {float(W), H * 0.5f}, {-1, 0});
    letter(-right, {0.0f, H * 0.5f}, {1, 0});
    letter(up, {W * 0.5f, 0.0f}, {0, 1});
    letter(-up, {W * 0.5f, float(H)}, {0, -1});
}

// A bar of a round length in the bottom-left corner, its length above it.
void scale_bar(Builder& b, LabelSet& set, const Camera& cam, int W, int H, float px, float s) {
    const double mm = scale_bar_mm(cam, W, H);
    const double dist = glm::length(cam.target - cam.eye);
    const double px_per_mm = double(H) / (2.0 * dist * std::tan(glm::radians(cam.fov_y_degrees) * 0.5));
    const float len = float(mm * px_per_mm), x0 = 16 * s, y0 = H - 20 * s;
    const glm::vec2 lo{x0 - s, y0 - 4 * s - s}, hi{x0 + len + s, y0 + s};
    b.rect(lo, hi, {0, 0, 0, 0.75f});
    b.rect({x0, y0 - 4 * s}, {x0 + len, y0}, glm::vec4(kTextColor, 1.0f));
    set.obstacles.push_back({lo, hi});
    char txt[32];
    std::snprintf(txt, sizeof txt, "%g mm", mm);
    PendingLabel& l = set.add(txt, px, kTextColor, {x0, lo.y});
    // The text's left edge over the bar's, its box just above the bar.
    l.centre = glm::vec2(x0 + float(l.layout.lo.x), lo.y - s) + glm::vec2(0.5f, -0.5f) * l.size();
    l.fixed = true;
}

// Where the legend's box of `size` goes: the first place, corners first
// (top left, top right, then down the left and right edges, bottom last),
// whose box grown by `gap` meets no fixed label (the orientation letters,
// the scale bar's length) and no obstacle (the scale bar, the markups'
// glyphs); none when no place is free (an image too small for it).
std::optional<glm::ivec2> legend_corner(const LabelSet& set, glm::ivec2 size, int W, int H, float margin, float gap) {
    std::vector<text::Box> avoid = set.obstacles;
    for (const auto& l : set.labels)
        if (l.fixed) avoid.push_back({l.centre - 0.5f * l.size(), l.centre + 0.5f * l.size()});
    const auto free = [&](glm::vec2 lo) {
        const text::Box b{lo - gap, lo + glm::vec2(size) + gap};
        for (const auto& a : avoid)
            if (text::overlaps(a, b)) return false;
        return true;
    };
    const float left = margin, right = float(W) - margin - float(size.x), bottom = float(H) - margin - float(size.y);
    for (float y = margin; y <= bottom; y += std::max(1.0f, 0.5f * gap))
        for (const float x : {left, right})
            if (x >= 0 && free({x, y})) return glm::ivec2(glm::round(glm::vec2(x, y)));
    return std::nullopt;
}

// A legend row's swatch at `lo`, `side` pixels high and two sides wide, over
// a dark outline: the left half the colour itself, the right half the colour
// at its opacity over a grey checker (so that the opacity shows).
void legend_swatch(Builder& b, glm::ivec2 lo, int side, glm::vec3 srgb, float opacity, float s) {
    const glm::vec2 p(lo), q = p + glm::vec2(2 * side, side), mid = p + glm::vec2(side, 0);
    const float edge = std::max(1.0f, std::round(s));
    b.rect(p - edge, q + edge, {0, 0, 0, 1});
    b.rect(p, mid + glm::vec2(0, side), glm::vec4(srgb, 1));
    const int cells = 3;
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const glm::vec2 c0 = mid + glm::vec2(i, j) * float(side) / float(cells);
            const float grey = (i + j) % 2 ? 0.35f : 0.85f;
            b.rect(glm::round(c0), glm::round(c0 + float(side) / float(cells)), {grey, grey, grey, 1});
        }
    b.rect(mid, q, glm::vec4(srgb, std::clamp(opacity, 0.0f, 1.0f)));
}

// The legend's text at one size: each entry's row laid out.
struct LegendText {
    float px = 0;
    std::shared_ptr<const text::Font> font;
    std::vector<text::TextLayout> rows;
};

LegendText legend_text_at(const std::vector<Annotations::LegendEntry>& entries, float px) {
    LegendText t{px, text::overlay_font(px), {}};
    for (const auto& e : entries) t.rows.push_back(text::layout_text(legend_text(e), *t.font));
    return t;
}

// One way to draw the legend: the first `shown` entries' rows (and a "+ K
// more" row, `more`, when that is not all of them) at `text`'s size, in a
// box of `size` whose top-left corner is `lo`.
struct LegendLayout {
    const LegendText* text = nullptr;
    std::size_t shown = 0;
    text::TextLayout more;
    int pad = 0, side = 0, swatch_w = 0, row_h = 0;
    glm::ivec2 size{0}, lo{0};
};

std::string legend_more_text(std::size_t k) { return "+ " + std::to_string(k) + " more"; }

LegendLayout legend_layout(const LegendText& t, std::size_t shown, float s) {
    LegendLayout l{&t, shown};
    l.pad = int(std::lround(5.0f * s));
    l.side = std::max(4, int(std::lround(0.8f * t.px)));
    l.swatch_w = 2 * l.side + int(std::lround(2.0f * s)); // the swatch and a gap before the text's halo
    glm::ivec2 text_size(0);
    for (std::size_t i = 0; i < shown; ++i) text_size = glm::max(text_size, t.rows[i].hi - t.rows[i].lo);
    const std::size_t rows = shown < t.rows.size() ? shown + 1 : shown;
    if (shown < t.rows.size()) {
        l.more = text::layout_text(legend_more_text(t.rows.size() - shown), *t.font);
        text_size = glm::max(text_size, l.more.hi - l.more.lo);
    }
    l.row_h = text_size.y;
    l.size = glm::ivec2(2 * l.pad + l.swatch_w + text_size.x, 2 * l.pad + int(rows) * text_size.y);
    return l;
}

// Where the legend goes, and how much of it. The rule: the most rows, then
// the largest text. All rows at the labels' size when a place is free for
// them (legend_corner); else all rows at 80 %, then at 65 % of that size
// (7 pt at 11 pt labels, the smallest drawn); else the first N entries and
// a last row "+ K more" for the other K, the largest N (at least 1) that has
// a place at any of those sizes, larger text first. None only when not even
// one row and the "+ K more" row (or the one entry) fit at 65 % anywhere
// clear of the letters and the scale bar (an image narrower than a row):
// then the image's metadata says it was not drawn (isoscope:legend_note).
std::optional<LegendLayout> fit_legend(const LabelSet& set, const std::vector<LegendText>& sizes, int W, int H,
                                       float s) {
    const std::size_t n = sizes.front().rows.size();
    for (std::size_t shown = n; shown >= 1; --shown)
        for (const LegendText& t : sizes) {
            LegendLayout l = legend_layout(t, shown, s);
            if (l.size.y > H || l.size.x > W) continue;
            if (const auto corner = legend_corner(set, l.size, W, H, 8.0f * s, 2.0f * s)) {
                l.lo = *corner;
                return l;
            }
        }
    return std::nullopt;
}

// The legend (Annotations::legend): a dark box with a row per surface shown
// (fit_legend), its swatch and its text as a fixed label, the "+ K more" row
// without a swatch; the box an obstacle for the labels placed later.
void legend(Builder& b, LabelSet& set, const std::vector<Annotations::LegendEntry>& entries, int W, int H, float px,
            float s) {
    if (entries.empty()) return;
    std::vector<LegendText> sizes;
    for (const float f : {1.0f, 0.8f, 0.65f}) sizes.push_back(legend_text_at(entries, px * f));
    const auto fit = fit_legend(set, sizes, W, H, s);
    if (!fit) return;
    const LegendLayout& l = *fit;
    const std::size_t n = entries.size(), rows = l.shown < n ? l.shown + 1 : l.shown;
    b.rect(glm::vec2(l.lo), glm::vec2(l.lo + l.size), {0, 0, 0, 0.55f});
    set.obstacles.push_back({glm::vec2(l.lo), glm::vec2(l.lo + l.size)});
    for (std::size_t i = 0; i < rows; ++i) {
        const bool more = i == l.shown;
        std::string txt = more ? legend_more_text(n - l.shown) : legend_text(entries[i]);
        set.labels.push_back({std::move(txt), more ? l.more : l.text->rows[i], kTextColor, {}, {}});
        PendingLabel& p = set.labels.back();
        const glm::ivec2 text_lo = l.lo + glm::ivec2(l.pad + l.swatch_w, l.pad + int(i) * l.row_h);
        p.centre = p.anchor = glm::vec2(text_lo) + 0.5f * p.size();
        p.fixed = p.legend = true;
        if (more) continue;
        // The swatch centred on the text's capitals (about 0.73 em above the baseline).
        const float baseline = float(text_lo.y - p.layout.lo.y);
        const glm::ivec2 swatch(l.lo.x + l.pad,
                                int(std::lround(baseline - 0.365f * l.text->px - 0.5f * float(l.side))));
        const glm::vec3 c = entries[i].color;
        legend_swatch(b, swatch, l.side, glm::vec3(srgb_from_linear(c.r), srgb_from_linear(c.g), srgb_from_linear(c.b)),
                      entries[i].opacity, s);
        p.swatch_lo = swatch;
        p.swatch_hi = swatch + glm::ivec2(l.side);
    }
}

} // namespace

std::string legend_text(const Annotations::LegendEntry& e) {
    const std::string dot = " \xC2\xB7 ";
    std::string t = e.name;
    if (!e.value.empty()) t += (t.empty() ? "" : dot) + e.value;
    const long percent = std::lround(std::clamp(double(e.opacity), 0.0, 1.0) * 100.0);
    if (percent < 100) t += (t.empty() ? "" : dot) + std::to_string(percent) + " %";
    return t;
}

Overlay build_overlay(const Annotations& a, const Camera& cam, int W, int H, float scale) {
    Overlay out;
    Builder b{out.vertices};
    LabelSet labels;
    const float s = std::max(scale, 0.1f);
    const float label_px = a.label_pt * a.dpi / 72.0f * s, orientation_px = a.orientation_pt * a.dpi / 72.0f * s;
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
        if (project(l.a, p) && project(l.b, q)) b.line(p, q, 2.0f * s, l.color);
    }
    for (const auto& p : a.points) {
        glm::vec2 px;
        if (project(p, px)) {
            b.rect(px - 4.0f * s, px + 4.0f * s, {0, 0, 0, 0.8f});
            b.rect(px - 3.0f * s, px + 3.0f * s, line_color);
            labels.obstacles.push_back({px - 4.0f * s, px + 4.0f * s});
        }
    }
    // Fixed labels first: the others are placed around them.
    if (a.orientation) orientation_letters(labels, cam, W, H, orientation_px, s);
    if (a.scale_bar) scale_bar(b, labels, cam, W, H, label_px, s);
    for (const auto& l : a.labels) {
        glm::vec2 px;
        if (!project(l.at, px) || l.text.empty()) continue;
        PendingLabel& p = labels.add(l.text, label_px, kTextColor, px);
        p.centre = px + glm::vec2(6.0f, -6.0f) * s + glm::vec2(0.5f, -0.5f) * p.size(); // above right
    }
    MarkupPainter markups{
        b,        labels,        cam.view(), cam.projection(aspect), W, H, s, std::clamp(a.hidden_opacity, 0.0f, 1.0f),
        label_px, cam.near_plane};
    for (const auto& m : a.markups) markups.draw(m);
    legend(b, labels, a.legend, W, H, label_px, s); // after the markups: over their lines, clear of their glyphs
    out.labels = draw_labels(b, labels, W, H, s, out.atlas);
    return out;
}

} // namespace iso
