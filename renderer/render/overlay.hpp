// Annotations drawn over the rendered image: text labels at 3D points, lines
// and points, a scale bar in millimetres, and the patient orientation letters
// (L/R/A/P/S/I) at the viewport edges. Built on the CPU as coloured
// triangles in pixel coordinates; text comes from stb_easy_font (Debian's
// libstb-dev), so no font file is needed. Everything scales with `scale`
// so that a 4x export has 4x thicker lines and larger text.
#pragma once

#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "renderer/scene/camera.hpp"

namespace iso {

struct Annotations {
    struct Label {
        glm::dvec3 at;  // LPS mm
        std::string text;
    };
    struct Line {
        glm::dvec3 a, b;
    };
    std::vector<Label> labels;
    std::vector<Line> lines;
    std::vector<glm::dvec3> points;
    bool scale_bar = true, orientation = true;
};

struct OverlayVertex {
    glm::vec2 pixel;
    glm::vec4 color;
};

// Triangles (3 vertices each) for the annotations of a W x H view.
std::vector<OverlayVertex> build_overlay(const Annotations& a, const Camera& cam, int width, int height, float scale);

// The letters of the patient directions pointing to the right and top of the
// view ("L", "P", ...), and the scale bar's length in mm for a view of that width.
std::string orientation_letter(const glm::dvec3& world_direction);
double scale_bar_mm(const Camera& cam, int width, int height);

} // namespace iso
