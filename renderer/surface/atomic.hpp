// Atomic updates that parallel loops share (measure.cpp, core/slices.cpp).
#pragma once

#include <atomic>

namespace iso {

// Lowers `target` to `value` when `value` is smaller. A parallel check keeps
// the smallest bad index this way, so the error names the first bad input
// whatever the order the threads found them in.
template <class T> void atomic_min(std::atomic<T>& target, T value) {
    T current = target.load();
    while (value < current && !target.compare_exchange_weak(current, value)) {}
}

} // namespace iso
