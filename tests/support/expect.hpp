// Checks shared by the tests that compare matrices element by element.
#pragma once

#include <glm/mat4x4.hpp>
#include <gtest/gtest.h>

namespace iso::test {

// Every element of a within tol of b's (index -> LPS affines, in mm).
inline void expect_affine_near(const glm::dmat4& a, const glm::dmat4& b, double tol) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tol) << "column " << c << " row " << r;
}

} // namespace iso::test
