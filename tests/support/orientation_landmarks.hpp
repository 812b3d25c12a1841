// Anatomical landmarks of the bundled head CT (datasets/headsq.raw), placed by
// a reader on the raw voxels, in index space (i, j, k) of the 64 x 64 x 93
// grid: they belong to the data, not to a header, so they hold whatever the
// header says and the tests map them through the loaded affine.
//
// How they were placed: the anterior skin height map (for each column (i, k),
// the first voxel along j at or above 500, linearly interpolated) shows the
// nasal ridge at i = 29..31, the closed eyes as the two recesses either side
// of it between the brow and the cheek (deepest at i = 21, k = 21 and
// i = 39, k = 24; the head is rolled slightly), and the chin as the mental
// protuberance at i = 28, k = 73..81, the last anterior bulge of the midline
// profile above the neck. The raw data stores the patient's left at low i
// (datasets/README.md), so the eye at i = 21 is the left one.
#pragma once

#include <glm/glm.hpp>

namespace iso::test {

struct HeadLandmarks {
    glm::dvec3 left_eye, right_eye, chin; // LPS mm
};

inline HeadLandmarks head_landmarks(const glm::dmat4& index_to_lps) {
    const auto lps = [&](double i, double j, double k) { return glm::dvec3(index_to_lps * glm::dvec4(i, j, k, 1.0)); };
    return {lps(21, 10, 21), lps(39, 10, 24), lps(28, 11.2, 77)};
}

} // namespace iso::test
