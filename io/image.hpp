// CPU images and their export (PNG, TIFF, EXR through OpenImageIO, loaded
// on the first read or write: io/image_module.hpp) with metadata embedded in
// the file.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace iso {

// `channels` floats or bytes per pixel, rows top to bottom.
struct Image {
    int width = 0, height = 0, channels = 4;
    bool is_float = false;
    std::vector<std::uint8_t> bytes; // !is_float
    std::vector<float> floats;       // is_float
};

struct ImageMetadata {
    std::map<std::string, std::string> text;                // e.g. "isoscope:input"
    std::map<std::string, std::vector<float>> float_arrays; // e.g. "isoscope:view" (16 floats, column-major)
};

// Writes .png, .tif/.tiff or .exr (by extension). 8-bit images go to any of
// them; float images need .exr or .tif. Written to a temporary file and
// renamed, so an existing file is never left half-written.
void save_image(const Image& img, const std::string& path, const ImageMetadata& meta = {});

// Reads any image OpenImageIO reads, with its metadata as text (tests,
// golden images). Throws iso::Error.
Image load_image(const std::string& path, ImageMetadata* meta = nullptr);

// OpenImageIO's version (10000 * major + 100 * minor + patch), loading the
// image module if it is not yet; -1 when it cannot be loaded.
int image_library_version();

// SHA-256 of a file or of every file under a folder (sorted by path), hex.
std::string sha256_of_path(const std::string& path);
// Hex SHA-256 of a byte string (cache keys).
std::string sha256_of_string(const std::string& bytes);

} // namespace iso
