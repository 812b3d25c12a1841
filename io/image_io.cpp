#include "io/image.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <vector>

#include <dlfcn.h>

#include <openssl/evp.h>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/image_module.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {
std::string lower_ext(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

// Where the module may be, in this order: beside the object this code is in
// (libisoscope_io.so in the shared sanitizer build) or the program, and in
// the install layout relative to either (/usr/bin/isoscope ->
// /usr/lib/isoscope/); then the build tree's output (ISOSCOPE_IMAGE_MODULE:
// test programs and benchmarks run from folders of their own).
std::vector<fs::path> module_candidates() {
    std::vector<fs::path> dirs;
    std::error_code ec;
    Dl_info info{};
    // For the program itself dladdr names argv[0], which may be relative to
    // a folder the process has left: only a library's absolute path is used.
    if (dladdr(reinterpret_cast<void*>(&save_image), &info) && info.dli_fname && info.dli_fname[0] == '/')
        if (const fs::path self = fs::canonical(info.dli_fname, ec); !ec) dirs.push_back(self.parent_path());
    if (const fs::path exe = fs::canonical("/proc/self/exe", ec); !ec) dirs.push_back(exe.parent_path());
    std::vector<fs::path> paths;
    for (const fs::path& dir : dirs) {
        paths.push_back(dir / image_module::kFileName);
        paths.push_back(dir.parent_path() / "lib" / "isoscope" / image_module::kFileName);
    }
#ifdef ISOSCOPE_IMAGE_MODULE
    paths.emplace_back(ISOSCOPE_IMAGE_MODULE);
#endif
    return paths;
}

// Loads the module once (a failed load is tried again on the next call);
// throws iso::Error naming `path`, the image being read or written.
const image_module::Functions& module_for(const std::string& path) {
    static std::mutex mutex;
    static const image_module::Functions* loaded = nullptr;
    std::lock_guard lock(mutex);
    if (loaded) return *loaded;
    std::string tried;
    for (const fs::path& candidate : module_candidates()) {
        std::error_code ec;
        if (!fs::exists(candidate, ec)) {
            tried += (tried.empty() ? "" : ", ") + candidate.string();
            continue;
        }
        // Never closed: the module stays for the process's life.
        void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) throw Error(path, std::string("cannot load the image module: ") + dlerror());
        using Entry = const image_module::Functions* (*)();
        auto entry = reinterpret_cast<Entry>(dlsym(handle, image_module::kEntry));
        const image_module::Functions* f = entry ? entry() : nullptr;
        if (!f || f->abi != image_module::kAbi)
            throw Error(path, "the image module " + candidate.string() + " is from another build of isoscope");
        loaded = f;
        return *loaded;
    }
    throw Error(path, std::string("cannot read or write images: the image module (") + image_module::kFileName +
                          ", OpenImageIO) is not installed (looked in " + tried + ")");
}
} // namespace

void save_image(const Image& img, const std::string& path, const ImageMetadata& meta) {
    const std::string ext = lower_ext(path);
    if (ext != ".png" && ext != ".tif" && ext != ".tiff" && ext != ".exr")
        throw Error(path, "unsupported image format (write .png, .tif or .exr)");
    if (img.is_float && ext == ".png") throw Error(path, "float images (AOVs) need .exr or .tif");
    if (img.width <= 0 || img.height <= 0) throw Error(path, "empty image");
    const image_module::Functions& oiio = module_for(path);
    check_writable_destination(path);
    write_atomically(path, [&](const std::string& tmp) {
        std::string error;
        if (!oiio.save(img, tmp, ext, meta, error)) throw Error(path, error);
    });
}

Image load_image(const std::string& path, ImageMetadata* meta) {
    const image_module::Functions& oiio = module_for(path);
    Image img;
    std::string error;
    if (!oiio.load(path, img, meta, error)) throw Error(path, error);
    return img;
}

int image_library_version() {
    try {
        return module_for("OpenImageIO").version();
    } catch (const Error&) {
        return -1;
    }
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
