// Annotations drawn over the rendered image: text labels at 3D points, lines
// and points, 3D Slicer markups (point lists, lines with their name and
// length, angles with their name and value: markup_label_text), a scale bar
// in millimetres, and the patient orientation letters (L/R/A/P/S/I) at the
// viewport edges. Built on the CPU as triangles in pixel coordinates; all
// text goes through the text engine (renderer/text: DejaVu Sans through
// fontconfig and FreeType, sizes in points) as glyph quads into a per-frame
// atlas, each label over a halo of contrasting colour and placed so that
// labels do not cover one another (docs/text.md). Everything scales with `scale` so that a 4x export has 4x
// thicker lines and larger text. Markup lines and glyphs carry the depth of
// the 3D point each vertex draws: the overlay pass compares it with the
// frame's depth and dims (and dashes) what lies behind a surface; labels
// are always drawn on top at full contrast (docs/markups.md, "Drawing
// markups").
#pragma once

#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "io/markups.hpp"
#include "renderer/frame/camera.hpp"
#include "renderer/frame/frame.hpp"
#include "renderer/text/atlas.hpp"

namespace iso {

struct Annotations {
    struct Label {
        glm::dvec3 at; // LPS mm
        std::string text;
    };
    struct Line {
        glm::dvec3 a, b;
        glm::vec4 color{1.0f, 0.85f, 0.2f, 1.0f}; // sRGB, straight alpha
    };
    std::vector<Label> labels;
    std::vector<Line> lines;
    std::vector<glm::dvec3> points;
    bool scale_bar = true, orientation = true;
    // 3D Slicer markups (io/markups.hpp), LPS mm. Points that are not
    // Defined or not visible are skipped. Parts behind the nearest opaque
    // surface of the frame (its G-buffer depth) by more than
    // `occlusion_tolerance_mm` are drawn at `hidden_opacity` without their
    // dark outline, hidden line parts also dashed; a glyph is hidden as a
    // whole only when the surface is in front at every pixel of the 3x3
    // block around its point. Labels are never dimmed.
    std::vector<Markup> markups;
    // The legend: one row per visible surface, a colour swatch (its left
    // half the surface's colour, its right half that colour at the
    // surface's opacity over a checker) and its text ("iso 500 \u00b7 500 HU
    // \u00b7 35 %": legend_text), in a box in the first corner clear of the
    // orientation letters, the scale bar and the markups' glyphs; fixed, so
    // labels placed after it keep off it. Empty: no legend. Where all rows
    // have no such place, it is drawn smaller (80 %, 65 % of the labels'
    // size), then as its first rows and a last row "+ K more" (no swatch)
    // for the K left out: the most rows, then the largest text. Left out
    // only of an image with no place for even one row and that last row at
    // 65 % (narrower than a row); the image's metadata says so.
    struct LegendEntry {
        std::string name;      // "iso 500", a mesh file's name
        glm::vec3 color{1.0f}; // linear RGB
        float opacity = 1.0f;  // 0..1
        std::string value;     // the iso value with its unit, "500 HU"; empty: none (a mesh)
    };
    std::vector<LegendEntry> legend;
    float hidden_opacity = 0.35f;
    float occlusion_tolerance_mm = 1.0f;
    // Text sizes in points at `dpi` pixels per inch, times the frame's scale
    // (the view's device pixel ratio, an export's --scale): 11 pt on a 96
    // dpi screen is 14.7 px per em, 58.7 px in a 4x export.
    float label_pt = 11.0f;       // markup labels and values, Annotations::labels, the scale bar's length
    float orientation_pt = 16.0f; // the orientation letters
    float dpi = 96.0f;
};

struct OverlayVertex {
    glm::vec2 pixel; // from the image's top-left corner
    glm::vec4 color; // sRGB, straight alpha
    // Markups only. The pixel (top-left origin) whose 3x3 block decides
    // whether this vertex's glyph or label is hidden; negative: each
    // fragment's own pixel decides (lines).
    glm::vec2 anchor{-1.0f};
    // 1 / (the drawn 3D point's depth along the view axis, mm); 0: a 2D
    // annotation, never compared or dimmed. Interpolated linearly in the
    // image, which is exact for a projected segment.
    float inv_depth = 0.0f;
    // Pixels along a line from its start, for dashing hidden parts; negative: solid.
    float along = -1.0f;
    // The alpha factor when hidden: Annotations::hidden_opacity for the
    // colour, 0 for outlines.
    float hidden_alpha = 1.0f;
    // Text: the atlas texel (from its top-left corner) at this vertex, one
    // texel per pixel, and the atlas channel that is the fragment's alpha
    // (0: the glyph's coverage, 1: its halo); negative: not text.
    glm::vec2 texel{0.0f};
    float atlas_channel = -1.0f;
};

// What the overlay pass draws over a W x H colour image: triangles (3
// vertices each), the glyph atlas their text samples, and the labels as
// placed.
struct Overlay {
    std::vector<OverlayVertex> vertices;
    text::AtlasImage atlas;
    std::vector<LabelBox> labels;
};
// Throws iso::Error when there is text to draw and the font cannot be
// found or read (text::overlay_font).
Overlay build_overlay(const Annotations& a, const Camera& cam, int width, int height, float scale);

// The text drawn with a Line or an Angle: its length as "42.3 mm" or its
// angle as "87.5\u00b0" (UTF-8: the font's own degree sign), one decimal.
// The file's own "length"/"angle" measurement is used when it has a value
// in mm (length) or degrees (angle), else computed_measurement()'s. Empty for
// other types and when there is no value (a point not Defined, a
// zero-length arm).
std::string markup_measurement_text(const Markup& m);

// The text of a markup's label as the overlay draws it (as 3D Slicer shows
// it). `point` -1: a Line's or an Angle's label, its name and its value
// ("Vessel gap: 36.6 mm"), the value alone when it has no name, the name
// alone when it has no value (markup_measurement_text). `point` >= 0: that
// control point's label in a point list (Fiducial), else the markup's name;
// in a curve the point's own label only. Empty: no label (other types, an
// unnamed point of an unnamed point list, a point out of range).
std::string markup_label_text(const Markup& m, int point = -1);

// The colour of a markup's control point `point`, or of its lines (point
// -1: as if selected when any Defined point is): Slicer's selectedColor
// for selected points (the default), its color for the others, else a
// default per type (points pink-red, lines cyan, angles green, curves
// orange); sRGB components in [0, 1] as Slicer stores them.
glm::vec3 markup_color(const Markup& m, int point = -1);

// A legend row's text: the name, the value when there is one, the opacity
// in percent when below 100 %, separated by middle dots (UTF-8).
std::string legend_text(const Annotations::LegendEntry& e);

// The letters of the patient directions pointing to the right and top of the
// view ("L", "P", ...), and the scale bar's length in mm for a view of that width.
std::string orientation_letter(const glm::dvec3& world_direction);
double scale_bar_mm(const Camera& cam, int width, int height);
// The longest round length (1, 2 or 5 x 10^k) not above `want` (0 for a
// `want` that is not a positive finite number): the scale bars' lengths.
double round_length_mm(double want);

} // namespace iso
