// The Embree AO reference against answers known in closed form.
#include "renderer/ao/reference.hpp"

#include <cmath>

#include "tests/support/ao_metrics.hpp"
#include "tests/support/meshes.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;

TEST(AoReference, OpenPlaneIsUnoccluded) {
    Mesh floor;
    test::append_box(floor, {-1000, -1000, -1}, {1000, 1000, 0});
    AoReference ref({&floor});
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 50, .rays = 512}), 1.0);
}

TEST(AoReference, WallMatchesTheClosedForm) {
    // Floor z <= 0, wall x >= d: far larger than R in every other direction.
    // (At d = 0 the point would lie in the wall's own plane; 0.01 mm gives a = 0.001.)
    for (double d : {0.01, 2.0, 5.0, 9.0}) {
        Mesh scene;
        test::append_box(scene, {-1000, -1000, -1}, {1000, 1000, 0});
        test::append_box(scene, {float(d), -1000, -1}, {float(d) + 10, 1000, 1000});
        AoReference ref({&scene});
        const AoReferenceOptions opt{.radius_mm = 10.0, .rays = 4096};
        const double ao = ref.at({0, 0, 0}, {0, 0, 1}, opt, 7);
        // Standard error <= 0.5/sqrt(4096) = 0.0078; 2.5 of them.
        EXPECT_NEAR(ao, wall_ao(d, 10.0), 0.02) << "wall at " << d << " mm";
    }
}

TEST(AoReference, ClosedBoxIsFullyOccludedAndRadiusLimits) {
    Mesh scene;
    // A room 20 mm high, the point on its floor.
    test::append_box(scene, {-100, -100, -1}, {100, 100, 0});  // floor
    test::append_box(scene, {-100, -100, 20}, {100, 100, 21}); // ceiling
    test::append_box(scene, {-101, -100, -1}, {-100, 100, 21});
    test::append_box(scene, {100, -100, -1}, {101, 100, 21});
    test::append_box(scene, {-100, -101, -1}, {100, -100, 21});
    test::append_box(scene, {-100, 100, -1}, {100, 101, 21});
    AoReference ref({&scene});
    // With R well beyond the ceiling's height, rays escaping sideways hit the
    // walls well within R only when R is large: at R = 1000 all are blocked.
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 1000, .rays = 1024}), 0.0);
    // With R below the ceiling's height nothing is within reach.
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 19, .rays = 1024}), 1.0);
}

TEST(AoReference, ErrorShrinksWithRays) {
    Mesh scene;
    test::append_box(scene, {-1000, -1000, -1}, {1000, 1000, 0});
    test::append_box(scene, {3, -1000, -1}, {13, 1000, 1000});
    AoReference ref({&scene});
    const double truth = wall_ao(3.0, 10.0);
    double err64 = 0, err4096 = 0;
    for (unsigned s = 0; s < 32; ++s) {
        err64 += std::abs(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 10, .rays = 64}, s) - truth);
        err4096 += std::abs(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 10, .rays = 4096}, s) - truth);
    }
    EXPECT_LT(err4096 / 32, 0.5 / std::sqrt(4096.0));
    EXPECT_LT(err4096, err64);
}
