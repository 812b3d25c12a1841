// Checks the binary headers of a VTK XML file before VTK's reader trusts
// them. VTK 9.1's vtkXMLDataParser allocates and reads whatever a block or
// compression header claims, and writes through a null pointer when that
// allocation fails (found by tests/fuzz). Each binary DataArray (appended
// raw, appended base64, or inline base64) starts with a header of
// header_type integers: uncompressed [bytes], or compressed [blocks,
// block size, last block size, compressed size of each block]. They must
// describe data that fits in the file.
#include "io/vtp_check.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <regex>

#include "io/error.hpp"

namespace iso::detail {

namespace {

std::string attr(const std::string& tag, const char* name) {
    const std::string key = std::string(" ") + name + "=\"";
    const auto p = tag.find(key);
    if (p == std::string::npos) return "";
    const auto e = tag.find('"', p + key.size());
    return e == std::string::npos ? "" : tag.substr(p + key.size(), e - p - key.size());
}

// Decodes base64 from `s` at `pos`, at most `want` bytes (skipping whitespace).
std::string base64(const std::string& s, std::size_t pos, std::size_t want) {
    auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+') return 62;
        if (c == '/') return 63;
        return -1;
    };
    std::string out;
    std::uint32_t acc = 0;
    int bits = 0;
    for (std::size_t i = pos; i < s.size() && out.size() < want; ++i) {
        const char c = s[i];
        if (c == '=' || c == '<') break;
        const int v = value(c);
        if (v < 0) continue;
        acc = (acc << 6) | std::uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(char((acc >> bits) & 0xFF));
        }
    }
    return out;
}

std::uint64_t get_int(const std::string& b, std::size_t i, std::size_t size, bool big_endian) {
    unsigned char x[8] = {};
    std::memcpy(x, b.data() + i * size, size);
    std::uint64_t v = 0;
    for (std::size_t k = 0; k < size; ++k) v |= std::uint64_t(x[big_endian ? size - 1 - k : k]) << (8 * k);
    return v;
}

} // namespace

void check_vtk_xml_headers(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    const std::string s((std::istreambuf_iterator<char>(f)), {});
    const auto file_tag_at = s.find("<VTKFile");
    if (file_tag_at == std::string::npos) throw Error(path, "not a VTK XML file (no <VTKFile> element)");
    const std::string file_tag = s.substr(file_tag_at, s.find('>', file_tag_at) - file_tag_at);
    const std::size_t hs = attr(file_tag, "header_type") == "UInt64" ? 8 : 4;
    const bool big = attr(file_tag, "byte_order") == "BigEndian";
    const bool compressed = !attr(file_tag, "compressor").empty();
    // Start of appended data: after the '_' that follows <AppendedData ...>.
    std::size_t appended = std::string::npos;
    bool appended_b64 = false;
    if (const auto a = s.find("<AppendedData"); a != std::string::npos) {
        const auto close = s.find('>', a);
        appended_b64 = attr(s.substr(a, close - a), "encoding") == "base64";
        const auto u = s.find('_', close);
        if (u != std::string::npos) appended = u + 1;
    }
    const std::uint64_t file_size = s.size();
    static const std::regex array_re("<(DataArray|Array)\\b[^>]*>");
    for (auto it = std::sregex_iterator(
             s.begin(), s.begin() + std::ptrdiff_t(appended == std::string::npos ? s.size() : appended), array_re);
         it != std::sregex_iterator(); ++it) {
        const std::string tag = it->str();
        const std::string format = attr(tag, "format");
        // VTK reads any format that is not "ascii" or "binary" as appended
        // data at `offset` (and then trusts its headers): refuse the others.
        if (format == "ascii") continue;
        if (format != "appended" && format != "binary")
            throw Error(path, "an array's format '" + format + "' is not ascii, binary or appended");
        std::string head; // the header bytes
        std::size_t data_start = 0;
        const std::size_t want = compressed ? 3 * hs : hs;
        if (format == "appended") {
            if (appended == std::string::npos)
                throw Error(path, "an array refers to appended data, but the file has none");
            const std::string off = attr(tag, "offset");
            char* end = nullptr;
            const unsigned long long o = std::strtoull(off.c_str(), &end, 10);
            if (off.empty() || *end || appended + o > s.size())
                throw Error(path, "an array's appended-data offset is outside the file");
            data_start = appended + std::size_t(o);
            head = appended_b64 ? base64(s, data_start, want) : s.substr(data_start, want);
        } else {
            data_start = std::size_t(it->position()) + tag.size();
            head = base64(s, data_start, want);
        }
        if (head.size() < want) throw Error(path, "an array's binary header is truncated");
        if (!compressed) {
            if (get_int(head, 0, hs, big) > file_size * 4)
                throw Error(path, "an array claims more data than the file holds");
            continue;
        }
        const std::uint64_t blocks = get_int(head, 0, hs, big), block = get_int(head, 1, hs, big),
                            last = get_int(head, 2, hs, big);
        if (blocks > file_size)
            throw Error(path, "an array's compression header claims " + std::to_string(blocks) + " blocks");
        // VTK divides by the block size even for an empty array.
        if (block == 0 || block > (std::uint64_t(1) << 30) || last > block)
            throw Error(path, "an array's compression header has an invalid block size");
        if (blocks == 0) continue;
        const std::string sizes = format == "appended" && !appended_b64
                                      ? s.substr(data_start + want, std::size_t(blocks) * hs)
                                      : base64(s, data_start, want + std::size_t(blocks) * hs).substr(want);
        if (sizes.size() < blocks * hs) throw Error(path, "an array's compression header is truncated");
        std::uint64_t total = 0;
        for (std::uint64_t b = 0; b < blocks; ++b) {
            const std::uint64_t c = get_int(sizes, std::size_t(b), hs, big);
            if (c == 0 || c > file_size) throw Error(path, "an array's compressed block size is invalid");
            total += c;
        }
        if (total > file_size) throw Error(path, "an array claims more compressed data than the file holds");
    }
}

} // namespace iso::detail
