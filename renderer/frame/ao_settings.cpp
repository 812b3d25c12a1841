#include "renderer/render/disk_ao.hpp"

#include <cmath>
#include <sstream>

#include "io/error.hpp"

namespace iso {

namespace {

void check_range(const char* what, double v, double lo, double hi) {
    if (!(std::isfinite(v) && v >= lo && v <= hi)) {
        std::ostringstream m;
        m << "must be in " << lo << " .. " << hi << ", got " << v;
        throw Error(std::string("disk AO ") + what, m.str());
    }
}

} // namespace

void validate(const DiskAoSettings& s) {
    // clip epsilon: the chapter's 1e-6 mm up to a tenth of a mm (a larger
    // snap would flatten real geometry).
    check_range("clip epsilon", s.clip_epsilon, 0.0, 0.1);
    // traversal epsilon: 0 would gather only root disks; beyond ~1e4 every
    // node is opened down to the triangles (exact but O(triangles) per pixel).
    check_range("traversal epsilon", s.traversal_epsilon, 0.0, 1e4);
    check_range("distance attenuation", s.distance_attenuation, 0.0, 100.0);
    check_range("triangle attenuation", s.triangle_attenuation, 0.0, 16.0);
    check_range("blend minimum weight", s.min_scale, 0.0, 1.0);
    check_range("blend maximum weight", s.max_scale, 0.0, 1.0);
    check_range("passes", s.passes, 0, 16); // 0: none, the default
    // Receiver raised by offset x R: 0 lets a receiver see its own disk;
    // beyond a tenth of R it floats visibly off the surface.
    check_range("receiver offset", s.receiver_offset, 0.0, 0.1);
}

bool same_settings(const DiskAoSettings& a, const DiskAoSettings& b) {
    return a.clip_epsilon == b.clip_epsilon && a.traversal_epsilon == b.traversal_epsilon &&
           a.distance_attenuation == b.distance_attenuation && a.triangle_attenuation == b.triangle_attenuation &&
           a.min_scale == b.min_scale && a.max_scale == b.max_scale && a.passes == b.passes &&
           a.receiver_offset == b.receiver_offset;
}

} // namespace iso
