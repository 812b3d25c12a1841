// Reading a whole (small) file into memory with errors that name it: the
// JSON readers (Slicer markups, sessions) parse from a string.
#pragma once

#include <string>

namespace iso {

// The file's bytes. Throws iso::Error naming `path`: no such file, not a
// regular file, cannot open, read failed.
std::string read_file(const std::string& path);

} // namespace iso
