// Helpers shared by the tests (CPU, GL, MPI): data paths, temporary
// folders, reading and writing whole files, running the CLI as a process.
#pragma once

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/error.hpp"

namespace iso::test {

inline std::string data(const std::string& rel) { return std::string(ISOSCOPE_DATA_DIR) + "/" + rel; }

// A fresh temporary folder per test, removed at the end.
class TempDir {
public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name =
            std::string("isoscope-") + (info ? std::string(info->test_suite_name()) + "-" + info->name() : "t");
        for (auto& c : name)
            if (c == '/') c = '_';
        path_ = std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string operator/(const std::string& rel) const { return (path_ / rel).string(); }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// A file's bytes ("" when it cannot be read).
inline std::string read_file(const std::filesystem::path& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

// Writes `bytes` as the whole file, replacing what was there.
inline void write_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Every file and folder under `dir`, as paths relative to it, sorted.
inline std::vector<std::string> files_in(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
        names.push_back(std::filesystem::relative(e.path(), dir).string());
    std::sort(names.begin(), names.end());
    return names;
}

struct CommandResult {
    int exit_code = -1;
    std::string out; // stdout
};

// Runs a shell command, capturing stdout (stderr goes to stdout when
// `merge_stderr`). Used for the real CLI binary.
inline CommandResult run_command(const std::string& cmd, bool merge_stderr = false) {
    CommandResult r;
    std::string full = cmd + (merge_stderr ? " 2>&1" : "");
    FILE* p = ::popen(full.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf{};
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
    int status = ::pclose(p);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

inline std::string cli() { return ISOSCOPE_CLI; }

// The message of the iso::Error that `f` throws, or "(no error)".
inline std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const iso::Error& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace iso::test
