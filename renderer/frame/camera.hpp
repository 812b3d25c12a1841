// A perspective camera in LPS millimetres, with the standard patient views.
// Depth is reversed-Z (near plane at 1, far at 0, float depth buffer): a
// 0.1 mm structure seen from 2 m keeps its depth resolution.
#pragma once

#include <string>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace iso {

struct Bounds {
    glm::dvec3 min{1e300}, max{-1e300};
    bool empty() const { return min.x > max.x; }
    void add(const glm::dvec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    glm::dvec3 center() const { return 0.5 * (min + max); }
    // Corner c = 0..7: bit 0 picks max.x, bit 1 max.y, bit 2 max.z.
    glm::dvec3 corner(int c) const {
        return {(c & 1) ? max.x : min.x, (c & 2) ? max.y : min.y, (c & 4) ? max.z : min.z};
    }
    double radius() const; // half the diagonal
};

enum class PatientView { Anterior, Posterior, Left, Right, Superior, Inferior };
// "anterior", "posterior", "left", "right", "superior", "inferior"; throws iso::Error otherwise.
PatientView patient_view_from_name(const std::string& name);
const char* patient_view_name(PatientView v);

// A ray: origin and unit direction.
struct Ray {
    glm::dvec3 origin{0.0}, dir{0.0, 0.0, -1.0};
};

class Camera {
public:
    glm::dvec3 eye{0, -500, 0}, target{0, 0, 0}, up{0, 0, 1};
    double fov_y_degrees = 30.0;
    double near_plane = 1.0, far_plane = 1000.0;

    // Looks at `b` from the given side of the patient (e.g. Anterior: from the
    // front, patient's superior up, patient's left on the image's right).
    void set_view(PatientView v, const Bounds& b);
    // Keeps the direction, moves so that `b` fills the view, and sets near/far
    // planes around it.
    void fit(const Bounds& b, double aspect);
    // Keeps position and direction; sets near/far planes around `b`.
    void fit_planes(const Bounds& b);
    void orbit(double yaw_degrees, double pitch_degrees); // about `target`
    void pan(double dx, double dy);                       // in units of the view height at the target
    void zoom(double factor);                             // > 1 moves closer

    glm::dmat4 view() const;                    // LPS world -> eye (OpenGL: camera looks down -z)
    glm::dmat4 projection(double aspect) const; // eye -> clip, reversed Z in [0, 1]
    glm::dvec3 forward() const { return glm::normalize(target - eye); }
    // Linear eye depth (distance along the view axis) from a reversed-Z depth value.
    double linear_depth(double d) const;
    // The ray from the eye through image point (x, y) of a width x height
    // image, in pixels from its top-left corner (pixel i's centre is i + 0.5),
    // as the rasterizer samples it: picking and the ray-traced references.
    Ray pixel_ray(double x, double y, int width, int height) const;
    bool operator==(const Camera&) const = default;
};

} // namespace iso
