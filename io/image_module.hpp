// The boundary between io/image_io.cpp and the OpenImageIO module
// (io/oiio/image_module.cpp, libisoscope_image.so), which the program loads
// on its first image read or write rather than at start.
//
// Why a module: OpenImageIO links about 260 shared libraries (FFmpeg,
// OpenCV, DCMTK, LibRaw, ...), so every isoscope process, and every test
// program, spent about half a second in the dynamic loader binding them
// (`isoscope --version`: 317 libraries; 119 without OpenImageIO), most of
// them before it could print a line and most of them never used: only PNG,
// TIFF and EXR images are read or written, and only by some commands.
#pragma once

#include <string>

#include "io/image.hpp"

namespace iso::image_module {

// What the module gives. Both sides are built from this header by the same
// build: `abi` only catches a stale module from another build.
struct Functions {
    int abi;
    // Writes `img` to `tmp` in the format of `ext` (".png", ".tif", ".tiff",
    // ".exr") with its metadata; false with the reason in `error`.
    bool (*save)(const Image& img, const std::string& tmp, const std::string& ext, const ImageMetadata& meta,
                 std::string& error);
    // Reads `path` into `img` (and its metadata); false with the reason.
    bool (*load)(const std::string& path, Image& img, ImageMetadata* meta, std::string& error);
    // OpenImageIO's version, 10000 * major + 100 * minor + patch.
    int (*version)();
};
inline constexpr int kAbi = 1;
inline constexpr const char* kEntry = "isoscope_image_module";
inline constexpr const char* kFileName = "libisoscope_image.so";

} // namespace iso::image_module
