#include "io/image.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenImageIO/imageio.h>
#include <openssl/evp.h>

#include "io/atomic_file.hpp"
#include "io/error.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {
std::string lower_ext(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}
} // namespace

void save_image(const Image& img, const std::string& path, const ImageMetadata& meta) {
    const std::string ext = lower_ext(path);
    if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".exr")
        throw Error(path, "unsupported image format (write .png, .tif or .exr)");
    if (img.is_float && ext == ".png") throw Error(path, "float images (AOVs) need .exr or .tif");
    if (img.width <= 0 || img.height <= 0) throw Error(path, "empty image");
    check_writable_destination(path);
    write_atomically(path, [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create(tmp);
        if (!out) throw Error(path, "OpenImageIO cannot write this format: " + OIIO::geterror());
        OIIO::ImageSpec spec(img.width, img.height, img.channels,
                             img.is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
        if (img.channels == 4) spec.alpha_channel = 3;
        if (img.is_float) {
            if (img.channels == 1) spec.channelnames = {"Z"};
            if (img.channels == 3) spec.channelnames = {"X", "Y", "Z"};
        }
        spec.attribute("Software", "isoscope");
        // TIFF has no free-form tags: everything goes into ImageDescription,
        // one "key: value" line each (load_image splits it again).
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
        if (!out->open(tmp, spec)) throw Error(path, "cannot open for writing: " + out->geterror());
        const bool ok = img.is_float ? out->write_image(OIIO::TypeDesc::FLOAT, img.floats.data())
                                     : out->write_image(OIIO::TypeDesc::UINT8, img.bytes.data());
        if (!ok || !out->close()) throw Error(path, "writing failed: " + out->geterror());
    });
}

Image load_image(const std::string& path, ImageMetadata* meta) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw Error(path, "cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    Image img;
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
    if (!ok) throw Error(path, "cannot read pixels: " + in->geterror());
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
    return img;
}

namespace {
std::string hex_digest(EVP_MD_CTX* ctx) {
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned int n = 0;
    EVP_DigestFinal_ex(ctx, md, &n);
    EVP_MD_CTX_free(ctx);
    static const char* hex = "0123456789abcdef";
    std::string s;
    for (unsigned i = 0; i < n; ++i) {
        s += hex[md[i] >> 4];
        s += hex[md[i] & 15];
    }
    return s;
}
} // namespace

std::string sha256_of_string(const std::string& bytes) {
    EVP_MD_CTX* ctx = EVP_MD_CTX_new();
    EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr);
    EVP_DigestUpdate(ctx, bytes.data(), bytes.size());
    return hex_digest(ctx);
}

std::string sha256_of_path(const std::string& path) {
    std::vector<std::string> files;
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        for (auto& e : fs::recursive_directory_iterator(path, ec))
            if (e.is_regular_file(ec)) files.push_back(e.path().string());
        std::sort(files.begin(), files.end());
    } else {
        files.push_back(path);
    }
    EVP_MD_CTX* ctx = EVP_MD_CTX_new();
    EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr);
    std::vector<char> buf(1 << 16);
    for (const auto& f : files) {
        std::ifstream in(f, std::ios::binary);
        if (!in) {
            EVP_MD_CTX_free(ctx);
            throw Error(f, "cannot read to hash it");
        }
        while (in.read(buf.data(), std::streamsize(buf.size())) || in.gcount() > 0)
            EVP_DigestUpdate(ctx, buf.data(), std::size_t(in.gcount()));
    }
    return hex_digest(ctx);
}

} // namespace iso
