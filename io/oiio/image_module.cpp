// The OpenImageIO side of io/image_io.cpp, built as a module of its own
// (libisoscope_image.so) and loaded on first use: io/image_module.hpp says
// why. It links OpenImageIO and nothing of isoscope's.
#include <sstream>

#include <OpenImageIO/imageio.h>

#include "io/image_module.hpp"

namespace {
using iso::Image;
using iso::ImageMetadata;

bool save(const Image& img, const std::string& tmp, const std::string& ext, const ImageMetadata& meta,
          std::string& error) {
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) {
        error = "OpenImageIO cannot write this format: " + OIIO::geterror();
        return false;
    }
    OIIO::ImageSpec spec(img.width, img.height, img.channels,
                         img.is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (img.channels == 4) spec.alpha_channel = 3;
    if (img.is_float) {
        if (img.channels == 1) spec.channelnames = {"Z"};
        if (img.channels == 3) spec.channelnames = {"X", "Y", "Z"};
    }
    spec.attribute("Software", "isoscope");
    // TIFF has no free-form tags: everything goes into ImageDescription,
    // one "key: value" line each (load splits it again).
    const bool tiff = ext == ".tif" || ext == ".tiff";
    std::string description;
    for (const auto& [k, v] : meta.text) {
        if (tiff)
            description += k + ": " + v + "\n";
        else
            spec.attribute(k, v);
    }
    for (const auto& [k, v] : meta.float_arrays) {
        if (ext == ".exr") {
            spec.attribute(k, OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, int(v.size())), v.data());
        } else {
            // PNG and TIFF keep text only: the array as space-separated numbers.
            std::ostringstream os;
            os.precision(9);
            for (std::size_t i = 0; i < v.size(); ++i) os << (i ? " " : "") << v[i];
            if (tiff)
                description += k + ": " + os.str() + "\n";
            else
                spec.attribute(k, os.str());
        }
    }
    if (tiff && !description.empty()) spec.attribute("ImageDescription", description);
    if (!out->open(tmp, spec)) {
        error = "cannot open for writing: " + out->geterror();
        return false;
    }
    const bool ok = img.is_float ? out->write_image(OIIO::TypeDesc::FLOAT, img.floats.data())
                                 : out->write_image(OIIO::TypeDesc::UINT8, img.bytes.data());
    if (!ok || !out->close()) {
        error = "writing failed: " + out->geterror();
        return false;
    }
    return true;
}

bool load(const std::string& path, Image& img, ImageMetadata* meta, std::string& error) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        error = "cannot read image: " + OIIO::geterror();
        return false;
    }
    const OIIO::ImageSpec& spec = in->spec();
    img = Image{};
    img.width = spec.width;
    img.height = spec.height;
    img.channels = spec.nchannels;
    img.is_float = spec.format.basetype == OIIO::TypeDesc::FLOAT || spec.format.basetype == OIIO::TypeDesc::HALF;
    bool ok;
    if (img.is_float) {
        img.floats.resize(std::size_t(img.width) * img.height * img.channels);
        ok = in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.floats.data());
    } else {
        img.bytes.resize(std::size_t(img.width) * img.height * img.channels);
        ok = in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::UINT8, img.bytes.data());
    }
    if (!ok) {
        error = "cannot read pixels: " + in->geterror();
        return false;
    }
    if (meta) {
        for (const auto& p : spec.extra_attribs) meta->text[p.name().string()] = p.get_string(1 << 20);
        // Our TIFF metadata: "key: value" lines in ImageDescription.
        std::istringstream lines(spec.get_string_attribute("ImageDescription"));
        std::string line;
        while (std::getline(lines, line))
            if (const auto c = line.find(": "); line.rfind("isoscope:", 0) == 0 && c != std::string::npos)
                meta->text[line.substr(0, c)] = line.substr(c + 2);
    }
    in->close();
    return true;
}

int version() { return OIIO::openimageio_version(); }

const iso::image_module::Functions kFunctions{iso::image_module::kAbi, save, load, version};
} // namespace

extern "C" __attribute__((visibility("default"))) const iso::image_module::Functions* isoscope_image_module() {
    return &kFunctions;
}
