// Sanity check of a VTK XML file's binary headers before vtkXMLDataParser
// reads it (see vtp_check.cpp). Throws iso::Error naming `path`.
#pragma once

#include <string>

namespace iso::detail {
void check_vtk_xml_headers(const std::string& path);
}
