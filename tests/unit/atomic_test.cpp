// atomic_min (renderer/surface/atomic.hpp): many threads lowering one value in
// any order leave the smallest, as the parallel input checks need to name
// the first bad triangle or vertex.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "renderer/surface/atomic.hpp"

using namespace iso;

TEST(AtomicMin, KeepsTheSmallestWhateverTheOrder) {
    std::vector<std::size_t> values(200000);
    std::iota(values.begin(), values.end(), std::size_t(1000));
    std::shuffle(values.begin(), values.end(), std::mt19937(3));
    std::atomic<std::size_t> smallest{values.size() + 1000};
    tbb::parallel_for(std::size_t(0), values.size(), [&](std::size_t i) { atomic_min(smallest, values[i]); });
    EXPECT_EQ(smallest.load(), 1000u);
    atomic_min(smallest, std::size_t(5000)); // larger: no change
    EXPECT_EQ(smallest.load(), 1000u);
    atomic_min(smallest, std::size_t(7));
    EXPECT_EQ(smallest.load(), 7u);
}
