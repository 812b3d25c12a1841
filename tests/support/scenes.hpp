// Small scenes for the GL tests and benchmarks: a plate, cameras, bounds,
// and the sRGB decoding written out from its published definition.
#pragma once

#include <cmath>

#include <glm/glm.hpp>

#include "io/mesh.hpp"
#include "renderer/frame/camera.hpp"

namespace iso::test {

// A square in the x-z plane at y (facing the anterior camera), half size h.
inline Mesh plate(double y, double h, double z = 0) {
    Mesh m;
    m.positions = {{-h, y, z - h}, {h, y, z - h}, {h, y, z + h}, {-h, y, z + h}};
    m.normals.assign(4, {0, -1, 0});
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// Looks at b from the front (anterior), fitted.
inline Camera anterior(const Bounds& b) {
    Camera c;
    c.set_view(PatientView::Anterior, b);
    c.fit(b, 1.0);
    return c;
}

// A camera at `eye` looking at `target`, clipping at 1 and 2000 mm unless told.
inline Camera looking(glm::dvec3 eye, glm::dvec3 target, glm::dvec3 up, double near_plane = 1,
                      double far_plane = 2000) {
    Camera c;
    c.eye = eye;
    c.target = target;
    c.up = up;
    c.near_plane = near_plane;
    c.far_plane = far_plane;
    return c;
}

// IEC 61966-2-1 sRGB decoding (8-bit code / 255 -> linear).
inline double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// The cube [-h, h]^3 as bounds (for fitting a camera).
inline Bounds box(double h) {
    Bounds b;
    b.add(glm::dvec3(-h));
    b.add(glm::dvec3(h));
    return b;
}

} // namespace iso::test
