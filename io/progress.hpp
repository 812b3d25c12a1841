// Progress reporting and cancellation for long operations.
#pragma once

#include <functional>
#include <string_view>

#include "io/error.hpp"

namespace iso {

// Called with a fraction in [0, 1] and the current stage's name. Returns false
// to ask the operation to stop; the operation then throws iso::Cancelled.
using ProgressFn = std::function<bool(double fraction, std::string_view stage)>;

class Cancelled : public Error {
public:
    explicit Cancelled(std::string where) : Error(std::move(where), "cancelled by the user") {}
};

// Reports progress; throws Cancelled when the callback asks to stop.
inline void report(const ProgressFn& fn, double fraction, std::string_view stage, const char* where) {
    if (fn && !fn(fraction, stage)) throw Cancelled(where);
}

} // namespace iso
