#include "io/atomic_file.hpp"

#include <atomic>
#include <unistd.h>

namespace iso {

std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path p(path);
    const std::string name =
        ".isoscope-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" + p.filename().string();
    return (p.parent_path() / name).string();
}

void check_writable_destination(const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path p(path);
    if (p.filename().empty()) throw Error(path, "no file name given");
    fs::path dir = p.parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw Error(path, "folder '" + dir.string() + "' does not exist");
    if (::access(dir.c_str(), W_OK) != 0) throw Error(path, "folder '" + dir.string() + "' is not writable");
    if (fs::is_directory(p, ec)) throw Error(path, "is a folder, not a file");
}

} // namespace iso
