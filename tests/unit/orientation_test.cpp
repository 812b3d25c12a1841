// The bundled head CT is oriented as a patient is: the test a clinician would
// write. Its skin surface (iso 500) is extracted in LPS millimetres and the
// anterior-most skin point (the nose) is compared with anatomical landmarks
// that a reader placed on the raw voxels (index space, which no header can
// change): it must be anterior of them, inferior of the eyes' level and
// superior of the chin. With the identity directions the headers carried
// before the fix the head was upside down and this test fails (the nose lands
// above the eyes).
#include <algorithm>
#include <map>

#include <glm/glm.hpp>

#include "tests/support/orientation_landmarks.hpp"
#include "renderer/core/api.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

struct Head {
    glm::dmat4 index_to_lps{1.0};
    Mesh skin;
    glm::dvec3 nose{0.0};
};

const Head& head(const std::string& file) {
    static std::map<std::string, Head> cache;
    auto it = cache.find(file);
    if (it != cache.end()) return it->second;
    Head h;
    core::Scene scene;
    scene.open(test::data(file));
    h.skin = scene.mesh(scene.add_isosurfaces({500.0}).at(0));
    h.index_to_lps = scene.volume().index_to_lps;
    // The anterior-most skin point: smallest y in LPS (+y is posterior).
    const auto nose = std::min_element(h.skin.positions.begin(), h.skin.positions.end(),
                                       [](const glm::vec3& a, const glm::vec3& b) { return a.y < b.y; });
    h.nose = glm::dvec3(*nose);
    return cache.emplace(file, std::move(h)).first->second;
}

} // namespace

class BundledHeadOrientation : public ::testing::TestWithParam<const char*> {};

TEST_P(BundledHeadOrientation, NoseIsAnteriorBelowTheEyesAndAboveTheChin) {
    const Head& h = head(GetParam());
    ASSERT_FALSE(h.skin.empty());
    const test::HeadLandmarks lm = test::head_landmarks(h.index_to_lps);
    const glm::dvec3 nose = h.nose;
    const double eye_level = 0.5 * (lm.right_eye.z + lm.left_eye.z);
    SCOPED_TRACE("nose at LPS (" + std::to_string(nose.x) + ", " + std::to_string(nose.y) + ", " +
                 std::to_string(nose.z) + ")");

    // Anterior: nearer the front (smaller y) than the eyes and the chin.
    EXPECT_LT(nose.y, lm.right_eye.y - 5.0);
    EXPECT_LT(nose.y, lm.left_eye.y - 5.0);
    EXPECT_LT(nose.y, lm.chin.y - 5.0);
    // Inferior of the eyes' level and superior of the chin (+z is superior).
    EXPECT_LT(nose.z, eye_level - 3.0);
    EXPECT_GT(nose.z, lm.chin.z + 20.0);
    // On the midline between the eyes, which lie side by side at one level.
    EXPECT_NEAR(nose.x, 0.5 * (lm.right_eye.x + lm.left_eye.x), 10.0);
    EXPECT_NEAR(lm.right_eye.z, lm.left_eye.z, 10.0);
    // The patient's left eye is on the patient's left (+x).
    EXPECT_GT(lm.left_eye.x, lm.right_eye.x + 40.0);
    // The eyes are superior of the chin, the skull's vertex side is the top of
    // the volume: the skin's highest point is above the eyes.
    EXPECT_GT(eye_level, lm.chin.z + 50.0);
    float top = -1e30f;
    for (const auto& p : h.skin.positions) top = std::max(top, p.z);
    EXPECT_GT(double(top), eye_level + 20.0);
}

TEST_P(BundledHeadOrientation, AffineIsTheRotationTheHeaderStates) {
    // i runs towards the patient's right, j towards posterior, k towards
    // inferior: a 180 degree rotation about the anterior-posterior axis of the
    // scaled identity (determinant positive, not a mirror).
    const glm::dmat4& a = head(GetParam()).index_to_lps;
    const glm::dmat4 expected = make_affine({3.2, 3.2, 1.5}, {0, 0, 0}, glm::dmat3(-1, 0, 0, 0, 1, 0, 0, 0, -1));
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], expected[c][r], 1e-12) << "column " << c << " row " << r;
    EXPECT_GT(glm::determinant(glm::dmat3(a)), 0.0);
}

INSTANTIATE_TEST_SUITE_P(BothHeaders, BundledHeadOrientation, ::testing::Values("headsq.nhdr", "headsq.mhd"),
                         [](const auto& info) {
                             return std::string(info.param).substr(7) == "nhdr" ? std::string("Nrrd")
                                                                                : std::string("MetaImage");
                         });
