// NRRD through teem, the format's reference library: raw and gzip encodings,
// attached (.nrrd) and detached (.nhdr) headers. VTK's reader handles raw
// only (no gzip; docs/architecture.md, formats), so it is not used.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include <teem/nrrd.h>

#include "io/atomic_file.hpp"
#include "io/volume_io.hpp"

namespace iso {

namespace {

struct NrrdDeleter {
    void operator()(Nrrd* n) const { nrrdNuke(n); }
};
// For a nrrd that wraps memory it does not own: frees the struct, not the data.
struct NrrdWrapDeleter {
    void operator()(Nrrd* n) const { nrrdNix(n); }
};
struct NioDeleter {
    void operator()(NrrdIoState* n) const { nrrdIoStateNix(n); }
};
using NrrdPtr = std::unique_ptr<Nrrd, NrrdDeleter>;
using NioPtr = std::unique_ptr<NrrdIoState, NioDeleter>;

// teem's error text (from its biff stack), trimmed to the first lines.
std::string teem_error() {
    char* e = biffGetDone(NRRD);
    std::string s = e ? e : "unknown teem error";
    std::free(e);
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    // biff prefixes every line with "[nrrd] "; keep the innermost reason.
    const auto last = s.rfind("[nrrd] ");
    if (last != std::string::npos && last + 7 < s.size()) s = s.substr(last + 7);
    return s;
}

VoxelType nrrd_voxel_type(const std::string& path, int t) {
    switch (t) {
    case nrrdTypeChar: return VoxelType::I8;
    case nrrdTypeUChar: return VoxelType::U8;
    case nrrdTypeShort: return VoxelType::I16;
    case nrrdTypeUShort: return VoxelType::U16;
    case nrrdTypeInt: return VoxelType::I32;
    case nrrdTypeUInt: return VoxelType::U32;
    case nrrdTypeFloat: return VoxelType::F32;
    case nrrdTypeDouble: return VoxelType::F64;
    default: break;
    }
    throw Error(path, std::string("unsupported voxel type '") + airEnumStr(nrrdType, t) +
                          "' (supported: int8, uint8, int16, uint16, int32, uint32, float, double)");
}

int nrrd_type(VoxelType t) {
    switch (t) {
    case VoxelType::I8: return nrrdTypeChar;
    case VoxelType::U8: return nrrdTypeUChar;
    case VoxelType::I16: return nrrdTypeShort;
    case VoxelType::U16: return nrrdTypeUShort;
    case VoxelType::I32: return nrrdTypeInt;
    case VoxelType::U32: return nrrdTypeUInt;
    case VoxelType::F32: return nrrdTypeFloat;
    case VoxelType::F64: return nrrdTypeDouble;
    }
    return nrrdTypeUnknown;
}

// Geometry from the header: index -> LPS, with warnings for what had to be assumed.
glm::dmat4 geometry(const std::string& path, const Nrrd* n, unsigned dim, std::vector<std::string>& warnings) {
    glm::dmat4 m(1.0);
    if (n->spaceDim > 0) {
        if (n->spaceDim != 3)
            throw Error(path, "world space has " + std::to_string(n->spaceDim) + " dimensions (3 expected)");
        // Flip from the file's space to LPS.
        glm::dvec3 flip(1.0);
        switch (n->space) {
        case nrrdSpaceLeftPosteriorSuperior:
        case nrrdSpaceLeftPosteriorSuperiorTime: break;
        case nrrdSpaceRightAnteriorSuperior:
        case nrrdSpaceRightAnteriorSuperiorTime: flip = {-1, -1, 1}; break;
        case nrrdSpaceLeftAnteriorSuperior:
        case nrrdSpaceLeftAnteriorSuperiorTime: flip = {1, -1, 1}; break;
        case nrrdSpaceScannerXYZ:
        case nrrdSpaceScannerXYZTime:
            // teem: identical to LPS for a patient lying normally in the scanner.
            warnings.push_back("space 'scanner-xyz' taken as LPS");
            break;
        default:
            warnings.push_back(std::string("space '") + airEnumStr(nrrdSpace, n->space) +
                               "' has no patient orientation; taken as LPS");
        }
        for (unsigned a = 0; a < 3; ++a) {
            if (a >= dim) {
                m[int(a)] = glm::dvec4(0, 0, 0, 0); // filled below for 2D images
                continue;
            }
            const double* d = n->axis[a].spaceDirection;
            for (int k = 0; k < 3; ++k) {
                if (!std::isfinite(d[k])) throw Error(path, "axis " + std::to_string(a) + " has no space direction");
                m[int(a)][k] = d[k] * flip[k];
            }
        }
        for (int k = 0; k < 3; ++k) m[3][k] = std::isfinite(n->spaceOrigin[k]) ? n->spaceOrigin[k] * flip[k] : 0.0;
        if (!std::isfinite(n->spaceOrigin[0])) warnings.push_back("no space origin; taken as (0, 0, 0)");
        if (dim == 2) {
            // A single slice: its normal, one unit of the in-plane spacing long.
            const glm::dvec3 a(m[0]), b(m[1]);
            const glm::dvec3 nrm = glm::normalize(glm::cross(a, b)) * std::sqrt(glm::length(a) * glm::length(b));
            m[2] = glm::dvec4(nrm, 0.0);
        }
    } else {
        bool assumed = false;
        for (unsigned a = 0; a < dim; ++a) {
            double s = n->axis[a].spacing;
            if (!std::isfinite(s)) {
                s = 1.0;
                assumed = true;
            }
            m[int(a)][int(a)] = s;
        }
        warnings.push_back(assumed ? "no space information and no spacing: unit spacing, origin 0, axes taken as LPS"
                                   : "no space information: axes taken as LPS, origin 0");
    }
    return m;
}

} // namespace

VolumeHeader read_nrrd_header(const std::string& path) {
    if (!std::filesystem::is_regular_file(path)) throw Error(path, "no such file");
    if (std::filesystem::file_size(path) == 0) throw Error(path, "file is empty");

    // Header only (teem opens, but does not read, a detached data file; it is
    // kept open so that the position of attached data can be asked).
    NrrdPtr header(nrrdNew());
    NioPtr nio(nrrdIoStateNew());
    nrrdIoStateSet(nio.get(), nrrdIoStateSkipData, AIR_TRUE);
    nrrdIoStateSet(nio.get(), nrrdIoStateKeepNrrdDataFileOpen, AIR_TRUE);
    const int failed = nrrdLoad(header.get(), path.c_str(), nio.get());
    long data_pos = -1;
    if (nio->dataFile) {
        data_pos = std::ftell(nio->dataFile);
        if (nio->dataFile != stdin) std::fclose(nio->dataFile);
        nio->dataFile = nullptr;
    }
    if (failed) throw Error(path, "not a readable NRRD file: " + teem_error());
    const unsigned dim = header->dim;
    if (dim < 2 || dim > 3) {
        std::string sizes;
        for (unsigned a = 0; a < dim; ++a) sizes += (a ? " x " : "") + std::to_string(header->axis[a].size);
        throw Error(path, std::to_string(dim) + "-dimensional data (" + sizes +
                              "): only scalar 3D volumes (or single 2D slices) are supported");
    }
    for (unsigned a = 0; a < dim; ++a)
        if (header->axis[a].kind != nrrdKindUnknown && header->axis[a].kind != nrrdKindDomain &&
            header->axis[a].kind != nrrdKindSpace)
            throw Error(path, std::string("axis ") + std::to_string(a) + " is of kind '" +
                                  airEnumStr(nrrdKind, header->axis[a].kind) + "': only scalar volumes are supported");
    VolumeHeader h;
    h.path = path;
    h.format = VolumeFormat::Nrrd;
    h.stored = h.type = nrrd_voxel_type(path, header->type);
    h.dims = {1, 1, 1};
    for (unsigned a = 0; a < dim; ++a) h.dims[a] = std::int64_t(header->axis[a].size);
    checked_byte_size(path, h.dims, h.stored);
    h.index_to_lps = geometry(path, header.get(), dim, h.meta.warnings);
    check_affine(path, h.index_to_lps);
    h.meta.source = path;
    h.meta.format = "NRRD";
    if (header->content) h.meta.series_description = header->content;

    // Where the samples are, for streaming: one data file (or the header's
    // own), raw or gzip, no line skips.
    h.encoding = nio->encoding == nrrdEncodingRaw    ? DataEncoding::Raw
                 : nio->encoding == nrrdEncodingGzip ? DataEncoding::Gzip
                                                     : DataEncoding::Other;
    h.swap_bytes = voxel_size(h.stored) > 1 && nio->endian != airEndianUnknown && nio->endian != airMyEndian();
    const unsigned files = nio->dataFNArr ? nio->dataFNArr->len : 0;
    if (files > 1 || nio->lineSkip > 0 || (nio->dataFSkip != nullptr)) {
        h.encoding = DataEncoding::Other; // several data files or skipped lines: read by teem only
    } else if (files == 1) {
        std::filesystem::path f(nio->dataFN[0]);
        if (f.is_relative() && nio->path) f = std::filesystem::path(nio->path) / f;
        h.data_file = f.string();
        h.data_offset = std::uint64_t(std::max<long>(nio->byteSkip, 0));
    } else {
        h.data_file = path;
        h.data_offset = std::uint64_t(std::max<long>(data_pos, 0)) + std::uint64_t(std::max<long>(nio->byteSkip, 0));
    }
    if (h.encoding == DataEncoding::Raw) {
        std::error_code ec;
        const auto size = std::filesystem::file_size(h.data_file, ec);
        if (ec) throw Error(path, "data file '" + h.data_file + "' cannot be read: " + ec.message());
        if (nio->byteSkip == -1)
            h.data_offset = size >= h.stored_bytes() ? size - h.stored_bytes() : 0; // "byte skip: -1": data at the end
        if (size < h.data_offset + h.stored_bytes())
            throw Error(path, "truncated: the header announces " + std::to_string(h.stored_bytes()) + " bytes of data" +
                                  (h.data_file != path ? " in '" + h.data_file + "'" : "") + " after offset " +
                                  std::to_string(h.data_offset) + ", the file has " + std::to_string(size) + " bytes");
    }
    return h;
}

Volume read_nrrd(const std::string& path) {
    VolumeHeader h = read_nrrd_header(path);
    NrrdPtr full(nrrdNew());
    if (nrrdLoad(full.get(), path.c_str(), nullptr)) throw Error(path, "cannot read the data: " + teem_error());
    Volume v = Volume::dense(h.dims, h.type, h.index_to_lps);
    if (nrrdElementNumber(full.get()) * nrrdElementSize(full.get()) != v.bytes().size())
        throw Error(path, "data size does not match the header");
    std::memcpy(v.bytes().data(), full->data, v.bytes().size());
    v.meta = std::move(h.meta);
    if (full->content) v.meta.series_description = full->content;
    warn_non_finite(v);
    return v;
}

void write_nrrd(const Volume& v, const std::string& path, bool compress) {
    if (v.is_sparse()) throw Error(path, "sparse volumes are written as .vdb, not NRRD");
    namespace fs = std::filesystem;
    const bool detached = fs::path(path).extension() == ".nhdr";
    // nrrdWrap does not copy; the wrapper's deleter frees only teem's struct.
    std::unique_ptr<Nrrd, NrrdWrapDeleter> n(nrrdNew());
    if (nrrdWrap_va(n.get(), const_cast<std::byte*>(v.bytes().data()), nrrd_type(v.type), 3, std::size_t(v.dims[0]),
                    std::size_t(v.dims[1]), std::size_t(v.dims[2])))
        throw Error(path, "cannot describe the volume to teem: " + teem_error());
    nrrdSpaceSet(n.get(), nrrdSpaceLeftPosteriorSuperior);
    double dirs[3][NRRD_SPACE_DIM_MAX] = {};
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) dirs[a][k] = v.index_to_lps[a][k];
    nrrdAxisInfoSet_va(n.get(), nrrdAxisInfoSpaceDirection, dirs[0], dirs[1], dirs[2]);
    const int kinds[3] = {nrrdKindDomain, nrrdKindDomain, nrrdKindDomain};
    nrrdAxisInfoSet_nva(n.get(), nrrdAxisInfoKind, kinds);
    const double origin[3] = {v.index_to_lps[3][0], v.index_to_lps[3][1], v.index_to_lps[3][2]};
    nrrdSpaceOriginSet(n.get(), origin);
    NioPtr nio(nrrdIoStateNew());
    nrrdIoStateEncodingSet(nio.get(), compress && nrrdEncodingGzip->available() ? nrrdEncodingGzip : nrrdEncodingRaw);

    auto save = [&](const std::string& target) {
        if (nrrdSave(target.c_str(), n.get(), nio.get())) {
            const std::string e = teem_error();
            throw Error(path, "cannot write: " + e);
        }
    };
    if (!detached) {
        save(path);
    } else {
        // A detached header names its data file after itself, so both are
        // written under their final names in a private folder beside the
        // target, then moved into place: data first, header last.
        check_writable_destination(path);
        const fs::path dest(path);
        const fs::path dir = fs::path(temp_path_for(path)).replace_extension("");
        fs::create_directory(dir);
        try {
            save((dir / dest.filename()).string());
            for (const auto& e : fs::directory_iterator(dir))
                if (e.path().filename() != dest.filename())
                    fs::rename(e.path(), dest.parent_path() / e.path().filename());
            fs::rename(dir / dest.filename(), dest);
        } catch (...) {
            std::error_code ec;
            fs::remove_all(dir, ec);
            throw;
        }
        fs::remove_all(dir);
    }
}

} // namespace iso
