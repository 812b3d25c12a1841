// MetaImage (.mha, .mhd): VTK's vtkMetaImageReader reads the samples (raw,
// zlib-compressed, detached or attached data), but VTK 9.1 drops the
// direction matrix, so the header's geometry is parsed here, and checked
// against the data before VTK allocates anything.
//
// Conventions (ITK's MetaImageIO, which defines the format in practice):
// world space is LPS; TransformMatrix (alias Rotation, Orientation) lists
// the direction of index axis k as values 3k..3k+2; Offset (alias Position,
// Origin) is the centre of voxel (0,0,0). AnatomicalOrientation is a label
// that ITK does not apply to the geometry, and neither do we.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <zlib.h>

#include <vtkImageData.h>
#include <vtkMetaImageReader.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkDataArray.h>

#include "io/vtk_util.hpp"
#include "io/volume_io.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

struct Header {
    std::map<std::string, std::string> keys; // in file order up to ElementDataFile
    std::uintmax_t header_bytes = 0;         // attached data starts here
};

Header parse_header(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open");
    Header h;
    std::string line;
    std::size_t lines = 0;
    while (std::getline(f, line)) {
        if (++lines > 200) throw Error(path, "no ElementDataFile line in the first 200 lines: not a MetaImage header");
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto eq = line.find('=');
        if (eq == std::string::npos) {
            if (line.find_first_not_of(" \t") == std::string::npos) continue;
            throw Error(path, "malformed MetaImage header line: '" + line.substr(0, 60) + "'");
        }
        auto trim = [](std::string s) {
            const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
            return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
        };
        const std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
        h.keys[key] = value;
        if (key == "ElementDataFile") {
            h.header_bytes = std::uintmax_t(f.tellg());
            return h;
        }
    }
    throw Error(path, "no ElementDataFile line: not a MetaImage header");
}

std::vector<double> numbers(const std::string& path, const std::string& key, const std::string& value, std::size_t n) {
    std::istringstream in(value);
    std::vector<double> v;
    double x;
    while (in >> x) v.push_back(x);
    if (v.size() != n)
        throw Error(path, key + " has " + std::to_string(v.size()) + " values, " + std::to_string(n) + " expected");
    return v;
}

VoxelType element_type(const std::string& path, const std::string& t) {
    static const std::map<std::string, VoxelType> types = {
        {"MET_CHAR", VoxelType::I8},    {"MET_UCHAR", VoxelType::U8},  {"MET_SHORT", VoxelType::I16},
        {"MET_USHORT", VoxelType::U16}, {"MET_INT", VoxelType::I32},   {"MET_UINT", VoxelType::U32},
        {"MET_FLOAT", VoxelType::F32},  {"MET_DOUBLE", VoxelType::F64}};
    auto it = types.find(t);
    if (it == types.end())
        throw Error(path, "unsupported ElementType '" + t +
                              "' (supported: MET_CHAR, MET_UCHAR, MET_SHORT, MET_USHORT, "
                              "MET_INT, MET_UINT, MET_FLOAT, MET_DOUBLE)");
    return it->second;
}

} // namespace

VolumeHeader read_metaimage_header(const std::string& path) {
    quiet_vtk();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path, "no such file");
    const auto size = fs::file_size(path, ec);
    if (size == 0) throw Error(path, "file is empty");
    const Header h = parse_header(path);
    auto get = [&](std::initializer_list<const char*> names) -> const std::string* {
        for (auto n : names)
            if (auto it = h.keys.find(n); it != h.keys.end()) return &it->second;
        return nullptr;
    };
    const std::string* ndims_s = get({"NDims"});
    if (!ndims_s) throw Error(path, "no NDims in the header");
    const int ndims = std::atoi(ndims_s->c_str());
    if (ndims < 2 || ndims > 3) throw Error(path, "NDims = " + *ndims_s + ": only 2D and 3D images are supported");
    const std::string* dim_s = get({"DimSize"});
    if (!dim_s) throw Error(path, "no DimSize in the header");
    const auto d = numbers(path, "DimSize", *dim_s, std::size_t(ndims));
    std::array<std::int64_t, 3> dims{1, 1, 1};
    for (int a = 0; a < ndims; ++a) {
        if (!(d[std::size_t(a)] >= 1 && d[std::size_t(a)] < 9.2e18) ||
            d[std::size_t(a)] != std::floor(d[std::size_t(a)]))
            throw Error(path, "DimSize value " + std::to_string(d[std::size_t(a)]) + " is not a positive integer");
        dims[std::size_t(a)] = std::int64_t(d[std::size_t(a)]);
    }
    const std::string* type_s = get({"ElementType"});
    if (!type_s) throw Error(path, "no ElementType in the header");
    const VoxelType type = element_type(path, *type_s);
    if (const auto* ch = get({"ElementNumberOfChannels"}); ch && std::atoi(ch->c_str()) != 1)
        throw Error(path, "ElementNumberOfChannels = " + *ch + ": only scalar images are supported");
    const std::size_t bytes = checked_byte_size(path, dims, type);

    glm::dvec3 spacing(1.0), origin(0.0);
    glm::dmat3 dir(1.0);
    if (const auto* s = get({"ElementSpacing", "ElementSize"})) {
        const auto v = numbers(path, "ElementSpacing", *s, std::size_t(ndims));
        for (int a = 0; a < ndims; ++a) spacing[a] = v[std::size_t(a)];
    }
    if (const auto* s = get({"Offset", "Position", "Origin"})) {
        const auto v = numbers(path, "Offset", *s, std::size_t(ndims));
        for (int a = 0; a < ndims; ++a) origin[a] = v[std::size_t(a)];
    }
    if (const auto* s = get({"TransformMatrix", "Rotation", "Orientation"})) {
        const auto v = numbers(path, "TransformMatrix", *s, std::size_t(ndims * ndims));
        for (int a = 0; a < ndims; ++a)
            for (int k = 0; k < ndims; ++k) dir[a][k] = v[std::size_t(a * ndims + k)];
    }
    for (int a = 0; a < 3; ++a)
        if (!(spacing[a] > 0.0) || !std::isfinite(spacing[a]))
            throw Error(path, std::string("spacing along ") + "ijk"[a] +
                                  " (ElementSpacing) is zero, negative or not a number");
    if (ndims == 2) dir[2] = glm::cross(dir[0], dir[1]);
    const glm::dmat4 affine = make_affine(spacing, origin, dir);
    check_affine(path, affine);

    // The data's size, before VTK allocates.
    VolumeHeader out;
    out.path = path;
    out.format = VolumeFormat::MetaImage;
    out.dims = dims;
    out.stored = out.type = type;
    out.index_to_lps = affine;
    out.meta.source = path;
    out.meta.format = "MetaImage";
    if (const auto* m = get({"Modality"})) {
        std::string mod = *m;
        if (mod.rfind("MET_MOD_", 0) == 0) mod = mod.substr(8);
        out.meta.modality = mod;
    }
    if (const auto* msb = get({"ElementByteOrderMSB", "BinaryDataByteOrderMSB"}))
        out.swap_bytes = voxel_size(type) > 1 && (*msb == "True" || *msb == "true" || *msb == "TRUE") !=
                                                     (std::endian::native == std::endian::big);
    // Samples as text: MetaIO reads as many numbers as the file holds and
    // leaves the rest of the image unset, without an error (found by the fuzz
    // smoke): refused rather than half-loaded.
    if (const auto* b = get({"BinaryData"}); b && !b->empty() && (b->front() == 'F' || b->front() == 'f' || *b == "0"))
        throw Error(path, "BinaryData = " + *b +
                              ": samples stored as text are not supported (save the image with "
                              "binary data, e.g. BinaryData = True)");
    const std::string* data_file = get({"ElementDataFile"});
    const bool compressed = [&] {
        const auto* c = get({"CompressedData"});
        return c && (*c == "True" || *c == "true" || *c == "TRUE");
    }();
    if (*data_file == "LOCAL") {
        const auto available = size - h.header_bytes;
        if (const auto* hs = get({"HeaderSize"}); hs && std::atoll(hs->c_str()) > 0)
            throw Error(path, "HeaderSize with attached data is not supported");
        if (!compressed && available < bytes)
            throw Error(path, "truncated: the header announces " + std::to_string(bytes) +
                                  " bytes of data, the file holds " + std::to_string(available));
        out.data_file = path;
        out.data_offset = h.header_bytes;
    } else if (*data_file != "LIST" && data_file->find('%') == std::string::npos) {
        const fs::path data = fs::path(path).parent_path() / *data_file;
        if (!fs::is_regular_file(data, ec)) throw Error(path, "its data file '" + data.string() + "' does not exist");
        std::intmax_t skip = 0;
        if (const auto* hs = get({"HeaderSize"})) skip = std::max<std::intmax_t>(0, std::atoll(hs->c_str()));
        const auto dsize = fs::file_size(data, ec);
        if (!compressed && dsize < std::uintmax_t(skip) + bytes)
            throw Error(path, "data file '" + data.string() + "' is truncated: " + std::to_string(bytes) +
                                  " bytes expected, it has " + std::to_string(dsize));
        if (compressed && dsize == 0) throw Error(path, "compressed data file '" + data.string() + "' is empty");
        out.data_file = data.string();
        out.data_offset = std::uint64_t(skip);
    } else {
        throw Error(path, "ElementDataFile = " + *data_file + ": file lists and patterns are not supported");
    }
    // zlib-compressed MetaImage data is one deflate stream: inflated by read_metaimage.
    out.encoding = compressed ? DataEncoding::Other : DataEncoding::Raw;
    return out;
}

namespace {

// Compressed samples are inflated here, not by VTK: MetaIO inflates what it
// can, says "Uncompress failed" on stderr at best, and leaves the rest of the
// image as it was allocated (found when the deterministic fuzz smoke, run
// twice, saw one corrupt file give different voxels). The stream (zlib or
// gzip framing, as MetaIO accepts) must inflate to exactly `expected` bytes.
void inflate_into(const std::string& path, const std::string& data_file, std::uint64_t offset, std::byte* dst,
                  std::uint64_t expected) {
    std::ifstream f(data_file, std::ios::binary);
    f.seekg(std::streamoff(offset));
    z_stream z{};
    if (!f || inflateInit2(&z, 15 + 32) != Z_OK) throw Error(path, "cannot read the compressed data");
    std::vector<unsigned char> in(1 << 16);
    unsigned char spill[256]; // where output past `expected` goes, to be counted
    std::uint64_t total = 0;
    int rc = Z_OK;
    while (rc != Z_STREAM_END && total <= expected) {
        if (z.avail_in == 0) {
            f.read(reinterpret_cast<char*>(in.data()), std::streamsize(in.size()));
            z.avail_in = unsigned(f.gcount());
            z.next_in = in.data();
            if (z.avail_in == 0) break; // the data end before the stream does
        }
        const std::uint64_t room = expected - total;
        z.next_out = room ? reinterpret_cast<unsigned char*>(dst + total) : spill;
        z.avail_out = room ? unsigned(std::min<std::uint64_t>(room, 1u << 30)) : unsigned(sizeof spill);
        const unsigned before = z.avail_out;
        rc = inflate(&z, Z_NO_FLUSH);
        total += before - z.avail_out;
        if (rc != Z_OK && rc != Z_STREAM_END) break;
    }
    inflateEnd(&z);
    if (rc != Z_STREAM_END || total != expected)
        throw Error(path, "the compressed data are truncated or corrupt: they inflate to " +
                              std::string(total > expected ? "more than " : "") + std::to_string(total) +
                              " bytes, the header announces " + std::to_string(expected));
}

} // namespace

Volume read_metaimage(const std::string& path) {
    quiet_vtk();
    const VolumeHeader hd = read_metaimage_header(path);
    const auto dims = hd.dims;
    const VoxelType type = hd.type;
    const std::size_t bytes = std::size_t(hd.stored_bytes());
    const glm::dmat4 affine = hd.index_to_lps;
    if (hd.encoding == DataEncoding::Other) {
        Volume v = Volume::dense(dims, type, affine);
        inflate_into(path, hd.data_file, hd.data_offset, v.bytes().data(), bytes);
        const std::size_t ss = voxel_size(type);
        if (hd.swap_bytes)
            for (std::size_t i = 0; i < bytes; i += ss) std::reverse(v.bytes().data() + i, v.bytes().data() + i + ss);
        v.meta = hd.meta;
        warn_non_finite(v);
        return v;
    }

    vtkNew<vtkMetaImageReader> r;
    vtkNew<VtkMessages> msgs;
    msgs->watch(r);
    r->SetFileName(path.c_str());
    r->Update();
    if (msgs->has_error()) throw Error(path, msgs->first_error());
    vtkImageData* img = r->GetOutput();
    vtkDataArray* arr = img ? img->GetPointData()->GetScalars() : nullptr;
    if (!arr) throw Error(path, "no samples could be read (truncated or corrupt data)");
    int vd[3];
    img->GetDimensions(vd);
    if (vd[0] != dims[0] || vd[1] != dims[1] || vd[2] != dims[2] ||
        std::size_t(arr->GetNumberOfValues()) * voxel_size(type) != bytes ||
        arr->GetDataTypeSize() != int(voxel_size(type)))
        throw Error(path, "the data read does not match the header (truncated or corrupt compressed data?)");
    Volume v = Volume::dense(dims, type, affine);
    std::memcpy(v.bytes().data(), arr->GetVoidPointer(0), bytes);
    v.meta = hd.meta;
    warn_non_finite(v);
    return v;
}

} // namespace iso
