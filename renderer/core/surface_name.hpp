// The names of the surfaces extracted from a volume, in one place for the
// scene, the streamed and the MPI paths, the image metadata and the file
// names: what a user reads ("iso 500", "label 3") and the suffix that tells
// apart the files of several surfaces written from one output name
// ("-iso500", "-label3").
#pragma once

#include <string>

namespace iso::core {

// An iso value or label as every name writes it: printf's %g (500, -0.5, 1e+06).
std::string value_text(double value);

// "iso 500" or "label 3".
std::string surface_name(bool label, double value);

// "-iso500" or "-label3", put between a file's stem and its extension.
std::string surface_file_suffix(bool label, double value);

} // namespace iso::core
