#include "renderer/frame/camera.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "io/error.hpp"

namespace iso {

double Bounds::radius() const { return empty() ? 0.0 : 0.5 * glm::length(max - min); }

PatientView patient_view_from_name(const std::string& n) {
    if (n == "anterior") return PatientView::Anterior;
    if (n == "posterior") return PatientView::Posterior;
    if (n == "left") return PatientView::Left;
    if (n == "right") return PatientView::Right;
    if (n == "superior") return PatientView::Superior;
    if (n == "inferior") return PatientView::Inferior;
    throw Error("patient view", "unknown view '" + n + "' (anterior, posterior, left, right, superior, inferior)");
}

const char* patient_view_name(PatientView v) {
    switch (v) {
    case PatientView::Anterior: return "anterior";
    case PatientView::Posterior: return "posterior";
    case PatientView::Left: return "left";
    case PatientView::Right: return "right";
    case PatientView::Superior: return "superior";
    case PatientView::Inferior: return "inferior";
    }
    return "?";
}

void Camera::set_view(PatientView v, const Bounds& b) {
    // LPS: +x patient's left, +y posterior, +z superior. `dir` points from the
    // target to the eye.
    glm::dvec3 dir, u(0, 0, 1);
    switch (v) {
    case PatientView::Anterior: dir = {0, -1, 0}; break;
    case PatientView::Posterior: dir = {0, 1, 0}; break;
    case PatientView::Left: dir = {1, 0, 0}; break;
    case PatientView::Right: dir = {-1, 0, 0}; break;
    case PatientView::Superior:
        dir = {0, 0, 1};
        u = {0, -1, 0};
        break; // anterior up
    case PatientView::Inferior:
        dir = {0, 0, -1};
        u = {0, -1, 0};
        break;
    }
    target = b.empty() ? glm::dvec3(0) : b.center();
    eye = target + dir;
    up = u;
    fit(b, 1.0);
}

void Camera::fit(const Bounds& b, double aspect) {
    const double r = std::max(b.empty() ? 1.0 : b.radius(), 1e-6);
    const glm::dvec3 dir = -forward();
    target = b.empty() ? target : b.center();
    const double half = glm::radians(fov_y_degrees) * 0.5;
    const double half_h = std::min(half, std::atan(std::tan(half) * std::max(aspect, 1e-6)));
    const double dist = r / std::sin(half_h) * 1.05;
    eye = target + dir * dist;
    near_plane = std::max(dist - 2.0 * r, dist * 1e-4);
    far_plane = dist + 2.0 * r;
}

void Camera::fit_planes(const Bounds& b) {
    if (b.empty()) return;
    const double r = std::max(b.radius(), 1e-6);
    const double d = glm::dot(b.center() - eye, forward()); // depth of the centre
    far_plane = std::max(d + 2.0 * r, 1e-3);
    near_plane = std::max(d - 2.0 * r, far_plane * 1e-5);
}

void Camera::orbit(double yaw, double pitch) {
    glm::dvec3 offset = eye - target;
    const glm::dmat4 ry = glm::rotate(glm::dmat4(1.0), glm::radians(yaw), up);
    offset = glm::dvec3(ry * glm::dvec4(offset, 0));
    const glm::dvec3 right = glm::normalize(glm::cross(-offset, up));
    const glm::dmat4 rp = glm::rotate(glm::dmat4(1.0), glm::radians(pitch), right);
    offset = glm::dvec3(rp * glm::dvec4(offset, 0));
    up = glm::normalize(glm::dvec3(rp * glm::dvec4(up, 0)));
    eye = target + offset;
}

void Camera::pan(double dx, double dy) {
    const double dist = glm::length(eye - target);
    const double h = 2.0 * dist * std::tan(glm::radians(fov_y_degrees) * 0.5);
    const glm::dvec3 right = glm::normalize(glm::cross(forward(), up));
    const glm::dvec3 u = glm::normalize(glm::cross(right, forward()));
    const glm::dvec3 shift = (-dx * right + dy * u) * h;
    eye += shift;
    target += shift;
}

void Camera::zoom(double factor) {
    if (!(factor > 0)) return;
    eye = target + (eye - target) / factor;
}

glm::dmat4 Camera::view() const { return glm::lookAtRH(eye, target, up); }

glm::dmat4 Camera::projection(double aspect) const {
    // Reversed Z: pass far as "near" and near as "far" to the [0,1] projection.
    return glm::perspectiveRH_ZO(glm::radians(fov_y_degrees), aspect, far_plane, near_plane);
}

double Camera::linear_depth(double d) const {
    const double n = near_plane, f = far_plane;
    return n * f / (d * (f - n) + n);
}

Ray Camera::pixel_ray(double x, double y, int width, int height) const {
    const double aspect = double(width) / double(height);
    const glm::dmat4 inv = glm::inverse(projection(aspect) * view());
    const double nx = x / width * 2.0 - 1.0, ny = 1.0 - y / height * 2.0;
    const auto unproject = [&](double z) {
        const glm::dvec4 p = inv * glm::dvec4(nx, ny, z, 1.0);
        return glm::dvec3(p) / p.w;
    };
    // Reversed Z: depth 1 at the near plane, 0.5 on the way to the far one.
    return {eye, glm::normalize(unproject(0.5) - unproject(1.0))};
}

} // namespace iso
