// The Embree AO reference against answers known in closed form.
#include "renderer/ao/reference.hpp"

#include <cmath>

#include "tests/support/test_util.hpp"

using namespace iso;

namespace {

// An axis-aligned box of triangles, outward faces, from lo to hi.
void add_box(Mesh& m, glm::vec3 lo, glm::vec3 hi) {
    const auto base = std::uint32_t(m.positions.size());
    for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 2; ++x) m.positions.emplace_back(x ? hi.x : lo.x, y ? hi.y : lo.y, z ? hi.z : lo.z);
    auto q = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
        m.triangles.push_back({base + a, base + b, base + c});
        m.triangles.push_back({base + a, base + c, base + d});
    };
    q(0, 2, 3, 1);
    q(4, 5, 7, 6);
    q(0, 1, 5, 4);
    q(2, 6, 7, 3);
    q(0, 4, 6, 2);
    q(1, 3, 7, 5);
}

// Cosine-weighted visibility at the foot of an infinite wall at distance d,
// rays limited to R: directions project uniformly onto the unit disk, and
// the wall blocks the segment x >= d/R of it.
double wall_ao(double d, double R) {
    const double a = std::min(d / R, 1.0);
    return 1.0 - (std::acos(a) - a * std::sqrt(1.0 - a * a)) / M_PI;
}

} // namespace

TEST(AoReference, OpenPlaneIsUnoccluded) {
    Mesh floor;
    add_box(floor, {-1000, -1000, -1}, {1000, 1000, 0});
    AoReference ref({&floor});
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 50, .rays = 512}), 1.0);
}

TEST(AoReference, WallMatchesTheClosedForm) {
    // Floor z <= 0, wall x >= d: far larger than R in every other direction.
    // (At d = 0 the point would lie in the wall's own plane; 0.01 mm gives a = 0.001.)
    for (double d : {0.01, 2.0, 5.0, 9.0}) {
        Mesh scene;
        add_box(scene, {-1000, -1000, -1}, {1000, 1000, 0});
        add_box(scene, {float(d), -1000, -1}, {float(d) + 10, 1000, 1000});
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
    add_box(scene, {-100, -100, -1}, {100, 100, 0});  // floor
    add_box(scene, {-100, -100, 20}, {100, 100, 21}); // ceiling
    add_box(scene, {-101, -100, -1}, {-100, 100, 21});
    add_box(scene, {100, -100, -1}, {101, 100, 21});
    add_box(scene, {-100, -101, -1}, {100, -100, 21});
    add_box(scene, {-100, 100, -1}, {100, 101, 21});
    AoReference ref({&scene});
    // With R well beyond the ceiling's height, rays escaping sideways hit the
    // walls well within R only when R is large: at R = 1000 all are blocked.
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 1000, .rays = 1024}), 0.0);
    // With R below the ceiling's height nothing is within reach.
    EXPECT_EQ(ref.at({0, 0, 0}, {0, 0, 1}, {.radius_mm = 19, .rays = 1024}), 1.0);
}

TEST(AoReference, ErrorShrinksWithRays) {
    Mesh scene;
    add_box(scene, {-1000, -1000, -1}, {1000, 1000, 0});
    add_box(scene, {3, -1000, -1}, {13, 1000, 1000});
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
