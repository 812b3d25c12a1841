#include "renderer/core/drag_pacing.hpp"

#include <algorithm>
#include <cmath>

namespace iso::core {

void DragPacing::frame(std::uint64_t request, double ms, bool reduced, std::uint64_t newest) {
    if (request <= changed_at_) return;
    if (ms > kAimMs) {
        slow(ms, reduced, newest);
    } else if (reduced && ms < 15.0) {
        if (coarsen_ > 1.0)
            coarsen_ /= 2.0;
        else
            scale_ = 1.0;
        changed_at_ = newest;
    }
}

void DragPacing::start(double still_ms, std::uint64_t newest) {
    if (scale_ == 1.0 && coarsen_ == 1.0 && still_ms > kSlowStillMs) slow(still_ms, false, newest);
}

void DragPacing::slow(double ms, bool reduced, std::uint64_t newest) {
    double slower = ms / kAimMs;
    if (!reduced) {
        scale_ = 0.5;
        slower /= 3.0;
    }
    if (slower > 1.5 && coarsen_ < kMaxCoarsen)
        coarsen_ = std::min(kMaxCoarsen, coarsen_ * std::exp2(std::max(1.0, std::round(0.5 * std::log2(slower)))));
    changed_at_ = newest;
}

} // namespace iso::core
