#include "io/volume_io.hpp"
namespace iso {
Volume read_metaimage(const std::string& p) { throw Error(p, "MetaImage reading is being written"); }
}
