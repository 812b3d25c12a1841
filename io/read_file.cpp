#include "io/read_file.hpp"

#include <filesystem>
#include <fstream>
#include <iterator>

#include "io/error.hpp"

namespace iso {

std::string read_file(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, fs::exists(path, ec) ? "not a regular file" : "no such file");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open");
    std::string s((std::istreambuf_iterator<char>(f)), {});
    if (f.bad()) throw Error(path, "read failed");
    return s;
}

} // namespace iso
