// Writing output without ever leaving a half-written file where the user's
// file was: write next to it under a temporary name with the same extension
// (libraries pick the encoding from the extension), then rename into place.
#pragma once

#include <filesystem>
#include <string>

#include "io/error.hpp"

namespace iso {

// A temporary path in the same folder as `path`, ending with the same file
// name (so ".nii.gz", ".nrrd" etc. still select the right encoding).
std::string temp_path_for(const std::string& path);

// Calls write(tmp) and renames tmp onto `path`. On any exception the temporary
// file is removed and the exception propagates; `path` is untouched.
template <class F> void write_atomically(const std::string& path, F&& write) {
    const std::string tmp = temp_path_for(path);
    try {
        write(tmp);
        std::error_code ec;
        std::filesystem::rename(tmp, path, ec);
        if (ec) throw Error(path, "cannot move the written file into place: " + ec.message());
    } catch (...) {
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        throw;
    }
}

// Throws iso::Error naming `path` when its folder does not exist or is not writable.
void check_writable_destination(const std::string& path);

} // namespace iso
