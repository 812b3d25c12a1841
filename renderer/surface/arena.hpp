// TBB arenas with a caller's thread count, shared by extraction and measurement.
#pragma once

#include <algorithm>
#include <utility>

#include <tbb/task_arena.h>

namespace iso {

// `requested` threads (0 or less: as many as TBB allows), capped at what TBB allows.
inline int effective_threads(int requested) {
    const int hw = tbb::this_task_arena::max_concurrency();
    return requested > 0 ? std::min(requested, hw) : hw;
}

// Runs f inside an arena of `threads` threads.
template <class F> void in_arena(int threads, F&& f) {
    tbb::task_arena arena(effective_threads(threads));
    arena.execute(std::forward<F>(f));
}

} // namespace iso
