#include "io/volume_io.hpp"
namespace iso {
Volume read_vti(const std::string& p) { throw Error(p, "VTI reading is being written"); }
}
