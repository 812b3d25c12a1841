#include "io/volume_io.hpp"

#include <algorithm>
#include <filesystem>

#include "io/atomic_file.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {
std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}
bool ends_with(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
} // namespace

VolumeFormat volume_format_of(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) return VolumeFormat::Dicom;
    const std::string p = lower(path);
    if (ends_with(p, ".nii") || ends_with(p, ".nii.gz")) return VolumeFormat::Nifti;
    if (ends_with(p, ".nrrd") || ends_with(p, ".nhdr")) return VolumeFormat::Nrrd;
    if (ends_with(p, ".mha") || ends_with(p, ".mhd")) return VolumeFormat::MetaImage;
    if (ends_with(p, ".vti")) return VolumeFormat::Vti;
    if (ends_with(p, ".vdb")) return VolumeFormat::Vdb;
    if (ends_with(p, ".dcm") || ends_with(p, ".ima") || ends_with(p, ".dicom")) return VolumeFormat::Dicom;
    return VolumeFormat::Unknown;
}

const char* volume_format_name(VolumeFormat f) {
    switch (f) {
    case VolumeFormat::Dicom: return "DICOM";
    case VolumeFormat::Nifti: return "NIfTI";
    case VolumeFormat::Nrrd: return "NRRD";
    case VolumeFormat::MetaImage: return "MetaImage";
    case VolumeFormat::Vti: return "VTI";
    case VolumeFormat::Vdb: return "OpenVDB";
    case VolumeFormat::Unknown: break;
    }
    return "unknown";
}

Volume load_volume(const std::string& path, const LoadOptions& opt) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path, "no such file or folder");
    VolumeFormat f = volume_format_of(path);
    Volume v;
    try {
        switch (f) {
        case VolumeFormat::Dicom: v = read_dicom({path}, opt); break;
        case VolumeFormat::Nifti: v = read_nifti(path); break;
        case VolumeFormat::Nrrd: v = read_nrrd(path); break;
        case VolumeFormat::MetaImage: v = read_metaimage(path); break;
        case VolumeFormat::Vti: v = read_vti(path); break;
        case VolumeFormat::Vdb: v = read_vdb(path); break;
        case VolumeFormat::Unknown:
            // Extension-less files are common for DICOM; let the DICOM reader decide.
            if (fs::is_regular_file(path, ec) && fs::path(path).extension().empty()) {
                v = read_dicom({path}, opt);
                break;
            }
            throw Error(path, "unsupported volume format (expected .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd, "
                              ".vti, .vdb, or a DICOM file or folder)");
        }
    } catch (const std::bad_alloc&) {
        // Libraries (VTK's XML reader, OpenVDB) allocate what a header claims.
        throw Error(path, "not enough memory to read this file (a corrupt header announcing a huge size?)");
    }
    if (v.meta.source.empty()) v.meta.source = path;
    if (v.meta.format.empty()) v.meta.format = volume_format_name(f);
    return v;
}

VolumeHeader read_volume_header(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path, "no such file or folder");
    const VolumeFormat f = volume_format_of(path);
    switch (f) {
    case VolumeFormat::Nifti: return read_nifti_header(path);
    case VolumeFormat::Nrrd: return read_nrrd_header(path);
    case VolumeFormat::MetaImage: return read_metaimage_header(path);
    case VolumeFormat::Vdb: return read_vdb_header(path).header;
    default: break;
    }
    throw Error(
        path, std::string("the header of a ") + volume_format_name(f) +
                  " volume cannot be read without its samples (header-only reading: NIfTI, NRRD, MetaImage, OpenVDB)");
}

Volume load_dicom_files(const std::vector<std::string>& files, const LoadOptions& opt) {
    if (files.empty()) throw Error("load_dicom_files", "no files given");
    return read_dicom(files, opt);
}

void save_volume(const Volume& v, const std::string& path, bool compress) {
    check_writable_destination(path);
    switch (volume_format_of(path)) {
    case VolumeFormat::Nifti: write_atomically(path, [&](const std::string& tmp) { write_nifti(v, tmp); }); return;
    case VolumeFormat::Nrrd:
        // A detached header (.nhdr) names its data file, so it cannot be written under a
        // temporary name; the writer handles .nhdr atomicity itself.
        if (lower(fs::path(path).extension().string()) == ".nhdr") {
            write_nrrd(v, path, compress);
            return;
        }
        write_atomically(path, [&](const std::string& tmp) { write_nrrd(v, tmp, compress); });
        return;
    case VolumeFormat::Vdb: write_atomically(path, [&](const std::string& tmp) { write_vdb(v, tmp); }); return;
    default: break;
    }
    throw Error(path, "cannot write this format (write .nrrd, .nhdr, .nii, .nii.gz or .vdb)");
}

} // namespace iso
