// Error policy (docs/architecture.md, "Errors"):
//  - programmer errors (broken preconditions) assert;
//  - bad input and environment failures throw iso::Error, whose message names
//    the file (or function) and the reason;
//  - expected outcomes (empty surface, nothing picked, NaN voxels) are values
//    or warnings carried with the result.
#pragma once

#include <stdexcept>
#include <string>

namespace iso {

class Error : public std::runtime_error {
public:
    // `where` is a file path or, for non-file errors, the operation's name.
    Error(std::string where, std::string reason)
        : std::runtime_error(where.empty() ? reason : where + ": " + reason), where_(std::move(where)),
          reason_(std::move(reason)) {}

    const std::string& where() const noexcept { return where_; }
    const std::string& reason() const noexcept { return reason_; }

private:
    std::string where_;
    std::string reason_;
};

} // namespace iso
