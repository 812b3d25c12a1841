// DICOM series reader: scan, group, split, sort, check geometry, read pixels.
//
// Each file's element structure is walked first (io/dicom_structure.hpp:
// vtk-dicom and GDCM abort on some malformed files), headers are parsed with
// vtkDICOMParser (one file at a time, errors caught), grouping/sorting/
// geometry are done here, and pixels are decoded by vtkDICOMReader (GDCM
// behind it for compressed transfer syntaxes, then in a child process:
// io/dicom_pixels.hpp) given the files in our order, with its own sorting,
// row flipping and rescaling off. A file found in a folder that cannot be
// read is skipped with a warning naming it; a file named alone is an error.
//
// Behaviours chosen (see also the comments at each place):
//  - Series are grouped by SeriesInstanceUID and split by orientation
//    (ImageOrientationPatient within 1e-4), Rows/Columns and PixelSpacing.
//    A split series is listed as "<uid>.1", "<uid>.2", ...
//  - Localizers are dropped: ImageType containing LOCALIZER (unless the folder
//    holds nothing else), and, inside one SeriesInstanceUID, small groups (<= 3
//    images) whose orientation differs from the main group's.
//  - Missing slices (a gap close to an integer multiple >= 2 of the typical
//    step) are filled by linear interpolation of the neighbouring slices, with
//    a warning naming where; other non-uniform spacing gives a warning and the
//    mean step.
//  - Duplicate positions: copies of the same instance (same SOPInstanceUID) are
//    read once, with a warning; different instances at one position (several
//    phases/echoes in one series) are an error, since any choice would be a
//    guess.
//  - Gantry tilt: a warning with the angle; the affine is sheared so every
//    voxel stays where the scanner put it (no resampling).
//  - Colour (RGB, YBR, PALETTE) images are refused with an error; multi-frame
//    (enhanced) files are listed but refused with an error when loaded.
#include "io/volume_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMValue.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>
#include <vtkType.h>

#include "io/dicom_pixels.hpp"
#include "io/dicom_structure.hpp"
#include "io/vtk_util.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

constexpr const char* kWhere = "read_dicom";
constexpr const char* kStage = "reading DICOM";

// Everything we need from one file's header.
struct Slice {
    std::string file;
    std::string sop_uid, series_uid, study_uid, description, modality, patient_name, patient_id;
    std::string image_type, photometric, transfer_syntax;
    int series_number = 0, instance_number = 0;
    int rows = 0, cols = 0, frames = 1, samples = 1, bits_allocated = 0, pixel_rep = 0;
    bool has_ipp = false, has_iop = false, has_spacing = false, imager_spacing = false;
    glm::dvec3 ipp{0.0}, row{1, 0, 0}, col{0, 1, 0};
    double spacing_between_rows = 1, spacing_between_cols = 1; // PixelSpacing[0], [1]
    double slope = 1, intercept = 0;
    bool has_rescale = false;
    bool localizer = false;
    double thickness = 0;
};

std::string upper(std::string s) {
    for (auto& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
    return s;
}

std::string trim(std::string s) {
    while (!s.empty() && (std::isspace(static_cast<unsigned char>(s.back())) || s.back() == '\0')) s.pop_back();
    size_t b = 0;
    while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
    return s.substr(b);
}

std::string fmt(double v, int prec = 4) {
    std::ostringstream os;
    os.precision(prec);
    os << std::fixed << v;
    std::string s = os.str();
    if (s.find('.') != std::string::npos) {
        while (!s.empty() && s.back() == '0') s.pop_back();
        if (!s.empty() && s.back() == '.') s.pop_back();
    }
    return s == "-0" ? "0" : s;
}

std::string fmt_vec(const glm::dvec3& v) { return "(" + fmt(v.x, 3) + ", " + fmt(v.y, 3) + ", " + fmt(v.z, 3) + ")"; }

// A DICOM file has "DICM" after a 128-byte preamble; old ACR-NEMA style files
// without preamble start with a group 0x0008 (or 0x0002) element.
bool looks_like_dicom(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    unsigned char b[132] = {};
    in.read(reinterpret_cast<char*>(b), sizeof b);
    const auto n = in.gcount();
    if (n >= 132 && std::memcmp(b + 128, "DICM", 4) == 0) return true;
    if (n >= 8) {
        const unsigned group = b[0] | (b[1] << 8);
        const unsigned elem = b[2] | (b[3] << 8);
        return (group == 0x0008 || group == 0x0002) && elem < 0x0100;
    }
    return false;
}

// Decimal strings are parsed here rather than by vtk-dicom, which reads text
// such as "nan" as 0: a value that is not a number becomes NaN and is refused
// by the geometry checks.
bool get_doubles(const vtkDICOMValue& v, double* out, size_t n) {
    if (!v.IsValid() || v.GetNumberOfValues() < n) return false;
    if (v.GetVR() != vtkDICOMVR::DS) {
        v.GetValues(out, n);
        return true;
    }
    const std::string text = v.AsString();
    size_t start = 0;
    for (size_t i = 0; i < n; ++i) {
        size_t end = text.find('\\', start);
        std::string item = trim(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
        char* stop = nullptr;
        out[i] = std::strtod(item.c_str(), &stop);
        if (item.empty() || stop != item.c_str() + item.size()) out[i] = std::numeric_limits<double>::quiet_NaN();
        if (end == std::string::npos && i + 1 < n) return false;
        start = end + 1;
    }
    return true;
}

std::string get_string(vtkDICOMMetaData* md, vtkDICOMTag tag, bool utf8 = false) {
    const auto& v = md->Get(tag);
    if (!v.IsValid()) return {};
    return trim(utf8 ? v.AsUTF8String() : v.AsString());
}

bool is_uncompressed(const std::string& ts) {
    return ts.empty() || ts == "1.2.840.10008.1.2" || ts == "1.2.840.10008.1.2.1" || ts == "1.2.840.10008.1.2.2";
}

// Parses one file's header. Returns nullopt for DICOM files without pixel data
// (DICOMDIR, reports, ...). Throws iso::Error for a DICOM file that is broken.
std::optional<Slice> parse_header(const std::string& path) {
    vtkNew<vtkDICOMParser> parser;
    vtkNew<vtkDICOMMetaData> md;
    vtkNew<VtkMessages> msgs;
    msgs->watch(parser);
    parser->SetMetaData(md);
    parser->SetFileName(path.c_str());
    parser->Update();
    if (parser->GetErrorCode() != 0 || msgs->has_error()) {
        const std::string m = msgs->joined_errors();
        const bool short_file = m.find("end of file") != std::string::npos || m.find("remaining") != std::string::npos;
        throw Error(path, std::string(short_file ? "file is truncated or corrupt" : "cannot read the DICOM header") +
                              (m.empty() ? "" : " (" + m + ")"));
    }
    if (!parser->GetPixelDataFound()) return std::nullopt;

    Slice s;
    s.file = path;
    s.sop_uid = get_string(md, DC::SOPInstanceUID);
    s.series_uid = get_string(md, DC::SeriesInstanceUID);
    s.study_uid = get_string(md, DC::StudyInstanceUID);
    s.description = get_string(md, DC::SeriesDescription, true);
    s.modality = get_string(md, DC::Modality);
    s.patient_name = get_string(md, DC::PatientName, true);
    s.patient_id = get_string(md, DC::PatientID, true);
    s.image_type = upper(get_string(md, DC::ImageType));
    s.photometric = upper(get_string(md, DC::PhotometricInterpretation));
    s.transfer_syntax = get_string(md, DC::TransferSyntaxUID);
    s.series_number = md->Get(DC::SeriesNumber).AsInt();
    s.instance_number = md->Get(DC::InstanceNumber).AsInt();
    s.rows = md->Get(DC::Rows).AsInt();
    s.cols = md->Get(DC::Columns).AsInt();
    s.frames = std::max(1, md->Get(DC::NumberOfFrames).AsInt());
    s.samples = md->Has(DC::SamplesPerPixel) ? md->Get(DC::SamplesPerPixel).AsInt() : 1;
    s.bits_allocated = md->Get(DC::BitsAllocated).AsInt();
    s.pixel_rep = md->Get(DC::PixelRepresentation).AsInt();
    s.thickness = md->Get(DC::SliceThickness).AsDouble();
    s.localizer = s.image_type.find("LOCALIZER") != std::string::npos;

    double v[6];
    if (get_doubles(md->Get(DC::ImagePositionPatient), v, 3)) {
        s.has_ipp = true;
        s.ipp = {v[0], v[1], v[2]};
    }
    if (get_doubles(md->Get(DC::ImageOrientationPatient), v, 6)) {
        s.has_iop = true;
        s.row = {v[0], v[1], v[2]};
        s.col = {v[3], v[4], v[5]};
    }
    if (get_doubles(md->Get(DC::PixelSpacing), v, 2)) {
        s.has_spacing = true;
    } else if (get_doubles(md->Get(DC::ImagerPixelSpacing), v, 2)) {
        s.has_spacing = true;
        s.imager_spacing = true;
    }
    if (s.has_spacing) {
        s.spacing_between_rows = v[0];
        s.spacing_between_cols = v[1];
    }
    const auto& vs = md->Get(DC::RescaleSlope);
    const auto& vi = md->Get(DC::RescaleIntercept);
    if (vs.IsValid() || vi.IsValid()) {
        s.has_rescale = true;
        if (vs.IsValid()) s.slope = vs.AsDouble();
        if (vi.IsValid()) s.intercept = vi.AsDouble();
    }

    if (s.rows <= 0 || s.cols <= 0) throw Error(path, "image has no Rows/Columns");
    // Truncated pixel data, for the transfer syntaxes where the size is known.
    if (is_uncompressed(s.transfer_syntax) && s.bits_allocated > 0) {
        const long long expected =
            (static_cast<long long>(s.rows) * s.cols * s.frames * s.samples * s.bits_allocated + 7) / 8;
        const long long available = parser->GetFileSize() - parser->GetFileOffset();
        const unsigned vl = parser->GetPixelDataVL();
        if (available < expected || (vl != 0xffffffffu && vl < expected))
            throw Error(path, "pixel data is truncated (" + std::to_string(std::max<long long>(0, available)) +
                                  " bytes present, " + std::to_string(expected) + " expected)");
    }
    return s;
}

bool valid_orientation(const Slice& s) {
    return s.has_iop && std::isfinite(glm::dot(s.row, s.col)) && std::abs(glm::length(s.row) - 1) <= 1e-3 &&
           std::abs(glm::length(s.col) - 1) <= 1e-3 && std::abs(glm::dot(s.row, s.col)) <= 1e-3;
}

// A group of slices that can form one volume.
struct Group {
    std::vector<Slice> slices;
    std::string uid; // listing uid (with ".n" when split)
};

bool same_geometry_class(const Slice& a, const Slice& b) {
    if (a.series_uid != b.series_uid || a.rows != b.rows || a.cols != b.cols) return false;
    if (a.frames > 1 || b.frames > 1) return a.file == b.file; // a multi-frame file is its own volume
    if (a.localizer != b.localizer) return false;
    if (a.has_iop != b.has_iop) return false;
    if (glm::length(a.row - b.row) > 1e-4 || glm::length(a.col - b.col) > 1e-4) return false;
    if (std::abs(a.spacing_between_rows - b.spacing_between_rows) > 1e-4 ||
        std::abs(a.spacing_between_cols - b.spacing_between_cols) > 1e-4)
        return false;
    return true;
}

struct Scan {
    std::vector<Group> groups;      // listed series, in listing order
    std::vector<std::string> notes; // dropped localizers, skipped files
    std::string where;              // folder or file to name in messages
};

// The files to scan, each with whether the caller named it (a file named
// must be readable; a file found in a folder that is not gets skipped).
struct Candidate {
    std::string path;
    bool named = false;
};

std::vector<Candidate> collect_files(const std::vector<std::string>& inputs, std::string& where) {
    if (inputs.empty()) throw Error(kWhere, "no files or folder given");
    where = inputs.size() == 1 ? inputs[0] : fs::path(inputs[0]).parent_path().string();
    if (where.empty()) where = inputs[0];
    std::vector<Candidate> files;
    for (const auto& in : inputs) {
        std::error_code ec;
        if (!fs::exists(in, ec)) throw Error(in, "no such file or folder");
        if (!fs::is_directory(in, ec)) {
            files.push_back({in, true});
            continue;
        }
        std::vector<std::string> found;
        for (auto it = fs::recursive_directory_iterator(in, fs::directory_options::skip_permission_denied, ec);
             !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
            std::error_code ec2;
            if (it->is_regular_file(ec2)) found.push_back(it->path().string());
        }
        if (ec) throw Error(in, "cannot list the folder: " + ec.message());
        if (found.empty()) throw Error(in, "folder is empty (no files found)");
        std::sort(found.begin(), found.end());
        for (auto& f : found) files.push_back({std::move(f), false});
    }
    return files;
}

// What a folder's unreadable files become: one note naming the first few.
std::string skipped_note(const std::vector<std::string>& bad) {
    std::string note = "skipped " + std::to_string(bad.size()) + " unreadable DICOM file(s): ";
    const std::size_t shown = std::min<std::size_t>(bad.size(), 3);
    for (std::size_t i = 0; i < shown; ++i) note += (i ? "; " : "") + bad[i];
    if (bad.size() > shown) note += "; and " + std::to_string(bad.size() - shown) + " more";
    return note;
}

Scan scan(const std::vector<std::string>& inputs, const ProgressFn& progress) {
    Scan sc;
    const std::vector<Candidate> files = collect_files(inputs, sc.where);

    std::vector<Slice> slices;
    std::vector<std::string> bad; // what was wrong with each unreadable file
    size_t non_dicom = 0, non_image = 0;
    for (size_t i = 0; i < files.size(); ++i) {
        report(progress, 0.4 * double(i) / double(files.size()), kStage, kWhere);
        const std::string& file = files[i].path;
        if (!looks_like_dicom(file)) {
            ++non_dicom;
            continue;
        }
        std::optional<Slice> s;
        try {
            // vtk-dicom and GDCM abort on some malformed files: they see only
            // files whose structure was walked (io/dicom_structure.hpp).
            check_dicom_structure(file);
            s = parse_header(file);
        } catch (const Error& e) {
            if (files[i].named) throw;
            bad.push_back(e.what());
            continue;
        }
        if (!s) {
            ++non_image;
            continue;
        }
        slices.push_back(std::move(*s));
    }
    if (slices.empty()) {
        std::string why = "no DICOM images found (" + std::to_string(files.size()) + " file(s) looked at, " +
                          std::to_string(non_dicom) + " not DICOM";
        if (non_image) why += ", " + std::to_string(non_image) + " DICOM file(s) without pixel data";
        if (!bad.empty()) why += "; " + skipped_note(bad);
        throw Error(sc.where, why + ")");
    }
    if (!bad.empty()) sc.notes.push_back(skipped_note(bad));

    // Group by SeriesInstanceUID, split by orientation / size / spacing.
    std::vector<Group> groups;
    for (auto& s : slices) {
        auto it = std::find_if(groups.begin(), groups.end(),
                               [&](const Group& g) { return same_geometry_class(g.slices.front(), s); });
        if (it == groups.end()) {
            groups.push_back({});
            it = groups.end() - 1;
        }
        it->slices.push_back(std::move(s));
    }

    // Drop localizers.
    const bool any_regular =
        std::any_of(groups.begin(), groups.end(), [](const Group& g) { return !g.slices.front().localizer; });
    size_t dropped = 0;
    std::vector<bool> drop(groups.size(), false);
    for (size_t g = 0; g < groups.size(); ++g) {
        const Slice& a = groups[g].slices.front();
        if (a.localizer && any_regular) drop[g] = true;
        // Small groups of another (valid) orientation inside one series are
        // scouts. Broken orientations stay listed so that loading them says why.
        if (a.frames == 1 && groups[g].slices.size() <= 3 && valid_orientation(a)) {
            for (size_t h = 0; h < groups.size(); ++h) {
                const Slice& b = groups[h].slices.front();
                if (h != g && b.series_uid == a.series_uid && !b.localizer && b.frames == 1 &&
                    groups[h].slices.size() >= 2 * groups[g].slices.size() && groups[h].slices.size() > 3 &&
                    (glm::length(a.row - b.row) > 1e-4 || glm::length(a.col - b.col) > 1e-4))
                    drop[g] = true;
            }
        }
        if (drop[g]) dropped += groups[g].slices.size();
    }
    for (size_t g = 0; g < groups.size(); ++g)
        if (!drop[g]) sc.groups.push_back(std::move(groups[g]));
    if (dropped) sc.notes.push_back("ignored " + std::to_string(dropped) + " localizer/scout image(s)");

    // Listing order: series number, UID, then bigger groups first.
    std::stable_sort(sc.groups.begin(), sc.groups.end(), [](const Group& x, const Group& y) {
        const Slice &a = x.slices.front(), &b = y.slices.front();
        if (a.series_number != b.series_number) return a.series_number < b.series_number;
        if (a.series_uid != b.series_uid) return a.series_uid < b.series_uid;
        return x.slices.size() > y.slices.size();
    });
    for (size_t g = 0; g < sc.groups.size(); ++g) {
        const auto& uid = sc.groups[g].slices.front().series_uid;
        size_t count = 0, rank = 0;
        for (size_t h = 0; h < sc.groups.size(); ++h)
            if (sc.groups[h].slices.front().series_uid == uid) {
                if (h < g) ++rank;
                ++count;
            }
        sc.groups[g].uid = count > 1 ? uid + "." + std::to_string(rank + 1) : uid;
    }
    return sc;
}

// What the headers alone say about a group's grid (the series chooser lists
// it before any pixel is read; loading uses it): the slices sorted along the
// normal with copies of one instance dropped, each slice's index on the
// regular grid (missing slices leave holes), the index -> LPS affine and the
// warnings. Throws iso::Error for what cannot be loaded.
struct Layout {
    std::vector<int> grid;
    glm::dmat4 affine{1.0};
    std::vector<std::string> warnings;
    bool scout = false; // looks like a scout/localizer
};

Layout lay_out(Group& g, const std::string& where);

SeriesInfo info_of(const Group& g, const std::string& where) {
    const Slice& s = g.slices.front();
    SeriesInfo si;
    si.uid = g.uid;
    si.description = s.description;
    si.modality = s.modality;
    si.number = s.series_number;
    int depth = 0;
    for (const auto& x : g.slices) depth += x.frames;
    si.dims = {s.cols, s.rows, depth};
    si.files = g.slices.size();
    // The warnings loading would give, from the headers (on a copy: lay_out sorts).
    try {
        Group copy = g;
        const Layout l = lay_out(copy, where);
        si.dims[2] = l.grid.back() + 1; // missing slices are filled in
        si.warnings = l.warnings;
        si.for_3d = !l.scout;
    } catch (const Error& e) {
        si.for_3d = false;
        si.warnings.push_back(std::string("cannot be loaded: ") + e.what());
    }
    return si;
}

std::string listing_text(const std::vector<SeriesInfo>& list) {
    std::string out;
    for (size_t i = 0; i < list.size(); ++i) {
        const auto& s = list[i];
        out += "\n  [" + std::to_string(i) + "] " + (s.modality.empty() ? "?" : s.modality) + " #" +
               std::to_string(s.number) + " " + std::to_string(s.dims[0]) + "x" + std::to_string(s.dims[1]) + "x" +
               std::to_string(s.dims[2]) + " \"" + s.description + "\" " + s.uid;
    }
    return out;
}

int select_series(const Scan& sc, const std::vector<SeriesInfo>& list, const std::string& want) {
    if (want.empty()) {
        if (list.size() == 1) return 0;
        throw Error("DICOM series", sc.where + " holds " + std::to_string(list.size()) +
                                        " series; choose a series by its index in this list or its "
                                        "SeriesInstanceUID:" +
                                        listing_text(list));
    }
    if (std::all_of(want.begin(), want.end(), [](unsigned char c) { return std::isdigit(c); }) && want.size() < 9) {
        const int idx = std::stoi(want);
        if (idx < 0 || size_t(idx) >= list.size())
            throw Error(sc.where,
                        "no series " + want + " (there are " + std::to_string(list.size()) + "):" + listing_text(list));
        // A purely numeric UID is not a valid DICOM UID, so an index is meant.
        return idx;
    }
    for (size_t i = 0; i < list.size(); ++i)
        if (list[i].uid == want) return int(i);
    std::vector<int> by_base;
    for (size_t i = 0; i < sc.groups.size(); ++i)
        if (sc.groups[i].slices.front().series_uid == want) by_base.push_back(int(i));
    if (by_base.size() == 1) return by_base[0];
    if (by_base.size() > 1)
        throw Error(sc.where, "series " + want + " was split into " + std::to_string(by_base.size()) +
                                  " parts (different orientation, size or spacing); choose one:" + listing_text(list));
    throw Error(sc.where, "no series with UID " + want + "; available:" + listing_text(list));
}

VoxelType voxel_type_of_vtk(int t, const std::string& where) {
    switch (t) {
    case VTK_UNSIGNED_CHAR: return VoxelType::U8;
    case VTK_SIGNED_CHAR:
    case VTK_CHAR: return VoxelType::I8;
    case VTK_UNSIGNED_SHORT: return VoxelType::U16;
    case VTK_SHORT: return VoxelType::I16;
    case VTK_UNSIGNED_INT: return VoxelType::U32;
    case VTK_INT: return VoxelType::I32;
    case VTK_FLOAT: return VoxelType::F32;
    case VTK_DOUBLE: return VoxelType::F64;
    default: break;
    }
    throw Error(where, std::string("unsupported pixel type ") + vtkImageScalarTypeNameMacro(t));
}

bool integral(double v) { return std::isfinite(v) && v == std::round(v); }

// Checks orientation, position and spacing of every slice in a group.
void check_geometry(const Group& g, bool need_position) {
    for (const auto& s : g.slices) {
        if (need_position && !s.has_ipp) throw Error(s.file, "ImagePositionPatient is missing");
        if (need_position && !s.has_iop) throw Error(s.file, "ImageOrientationPatient is missing");
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(s.ipp[a])) throw Error(s.file, "ImagePositionPatient is not finite");
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(s.row[a]) || !std::isfinite(s.col[a]))
                throw Error(s.file, "ImageOrientationPatient is not finite");
        const double lr = glm::length(s.row), lc = glm::length(s.col), d = glm::dot(s.row, s.col);
        if (std::abs(lr - 1) > 1e-3 || std::abs(lc - 1) > 1e-3 || std::abs(d) > 1e-3)
            throw Error(s.file, "ImageOrientationPatient is not orthonormal (|row| = " + fmt(lr, 5) +
                                    ", |column| = " + fmt(lc, 5) + ", row.column = " + fmt(d, 5) + ")");
        if (!std::isfinite(s.spacing_between_rows) || !std::isfinite(s.spacing_between_cols) ||
            !(s.spacing_between_rows > 0) || !(s.spacing_between_cols > 0))
            throw Error(s.file, "PixelSpacing is zero, negative or not finite (" + fmt(s.spacing_between_rows) + "\\" +
                                    fmt(s.spacing_between_cols) + ")");
        if (s.has_rescale && (!std::isfinite(s.slope) || !std::isfinite(s.intercept) || s.slope == 0))
            throw Error(s.file, "RescaleSlope/RescaleIntercept are invalid");
    }
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// What lay_out refuses before looking at positions: multi-frame files,
// colour images, and slices whose pixel format or size differs from the first.
void check_pixel_format(const Group& g) {
    const Slice& first = g.slices.front();
    if (first.frames > 1)
        throw Error(first.file, "multi-frame (enhanced) DICOM files are not supported yet (" +
                                    std::to_string(first.frames) + " frames in one file)");
    for (const auto& s : g.slices) {
        if (s.samples != 1 ||
            (s.photometric != "MONOCHROME1" && s.photometric != "MONOCHROME2" && !s.photometric.empty()))
            throw Error(s.file, "colour images (" + s.photometric + ", " + std::to_string(s.samples) +
                                    " samples per pixel) are not supported: isoscope reads greyscale CT/MR");
        if (s.bits_allocated != first.bits_allocated || s.pixel_rep != first.pixel_rep)
            throw Error(s.file, "pixel format (BitsAllocated/PixelRepresentation) differs from " + first.file);
        if (s.rows != first.rows || s.cols != first.cols) throw Error(s.file, "image size differs from " + first.file);
    }
}

double position_along(const Slice& s, const glm::dvec3& normal) { return glm::dot(s.ipp, normal); }

// Sorts the slices along the normal (equal positions by InstanceNumber).
// Duplicate positions: a copy of the same instance is read once; two
// different instances at one position mean the series holds several
// volumes (phases, echoes), which we refuse rather than guess.
void sort_slices(Group& g, const glm::dvec3& normal, const std::string& where, std::vector<std::string>& warnings) {
    const auto pos = [&](const Slice& s) { return position_along(s, normal); };
    std::stable_sort(g.slices.begin(), g.slices.end(), [&](const Slice& a, const Slice& b) {
        const double pa = pos(a), pb = pos(b);
        if (pa != pb) return pa < pb;
        return a.instance_number < b.instance_number;
    });
    std::vector<Slice> kept;
    size_t copies = 0;
    for (auto& s : g.slices) {
        if (!kept.empty() && std::abs(pos(s) - pos(kept.back())) < 1e-3) {
            if (!s.sop_uid.empty() && s.sop_uid == kept.back().sop_uid) {
                ++copies;
                continue;
            }
            throw Error(where, "two different images at the same position " + fmt_vec(s.ipp) + ": " + kept.back().file +
                                   " and " + s.file +
                                   " (several volumes, e.g. phases or echoes, in one series are not supported)");
        }
        kept.push_back(std::move(s));
    }
    g.slices = std::move(kept);
    if (copies) warnings.push_back("ignored " + std::to_string(copies) + " duplicate file(s) of the same image");
}

// Each sorted slice's index on the regular grid (two or more slices): a gap
// close to a whole number (>= 2) of the typical step leaves slices missing
// there; any other uneven step makes the spacing irregular (indices 0..n-1,
// the mean step). Returns whether it is irregular.
bool place_on_grid(const std::vector<Slice>& slices, const glm::dvec3& normal, std::vector<int>& grid,
                   std::vector<std::string>& warnings) {
    const size_t n = slices.size();
    std::vector<double> p(n), d(n - 1);
    for (size_t k = 0; k < n; ++k) p[k] = position_along(slices[k], normal);
    for (size_t k = 0; k + 1 < n; ++k) d[k] = p[k + 1] - p[k];
    const double m = median(d);
    const double tol = 0.01; // mm, uniform spacing
    bool irregular = false;
    std::vector<std::string> gaps;
    for (size_t k = 0; k + 1 < n; ++k) {
        int r = 1;
        if (std::abs(d[k] - m) > tol) {
            const double q = d[k] / m;
            r = int(std::lround(q));
            if (r < 2 || std::abs(d[k] - r * m) > std::max(tol, 0.1 * m)) {
                irregular = true;
                r = 1;
            } else {
                gaps.push_back(std::to_string(r - 1) + " slice(s) missing between slice " + std::to_string(k) + " at " +
                               fmt(p[k], 3) + " mm and slice " + std::to_string(k + 1) + " at " + fmt(p[k + 1], 3) +
                               " mm (files " + fs::path(slices[k].file).filename().string() + ", " +
                               fs::path(slices[k + 1].file).filename().string() + ")");
            }
        }
        grid[k + 1] = grid[k] + r;
    }
    if (irregular) {
        for (size_t k = 0; k < n; ++k) grid[k] = int(k);
        const auto [mn, mx] = std::minmax_element(d.begin(), d.end());
        warnings.push_back("slice spacing is not uniform (steps from " + fmt(*mn) + " to " + fmt(*mx) +
                           " mm along the normal); the mean step " + fmt((p[n - 1] - p[0]) / double(n - 1)) +
                           " mm is used, so positions are approximate");
    } else {
        for (const auto& gtxt : gaps)
            warnings.push_back("missing slice: " + gtxt + "; filled by linear interpolation of the neighbours");
    }
    return irregular;
}

// The step from one grid slice to the next (two or more slices): along the
// normal, or, under gantry tilt, sheared along the scanner axis so voxels
// keep their true positions.
glm::dvec3 slice_step(const std::vector<Slice>& slices, const glm::dvec3& normal, const std::vector<int>& grid,
                      bool irregular, std::vector<std::string>& warnings) {
    const size_t n = slices.size();
    glm::dvec3 step_vec;
    const glm::dvec3 total = slices[n - 1].ipp - slices[0].ipp;
    const double along = glm::dot(total, normal);
    const glm::dvec3 inplane = total - along * normal;
    const double steps = double(grid[n - 1]);
    const double angle = std::atan2(glm::length(inplane), along) * 180.0 / M_PI;
    if (glm::length(inplane) > 0.01 && angle > 0.01) {
        step_vec = total / steps;
        warnings.push_back("gantry tilt of " + fmt(angle, 2) +
                           " degrees: slices are sheared along the scanner axis; the index->LPS affine is "
                           "sheared to keep voxels at their true positions (not resampled)");
    } else {
        step_vec = normal * (along / steps);
    }
    // Each slice should sit on the (possibly sheared) line.
    double worst = 0;
    for (size_t k = 0; k < n; ++k)
        worst = std::max(worst, glm::length(slices[0].ipp + double(grid[k]) * step_vec - slices[k].ipp));
    if (!irregular && worst > 0.05)
        warnings.push_back("slice positions deviate up to " + fmt(worst) + " mm from a straight line");
    return step_vec;
}

Layout lay_out(Group& g, const std::string& where) {
    check_pixel_format(g);
    const Slice first = g.slices.front(); // a copy: sort_slices rebuilds g.slices
    std::vector<std::string> warnings;
    const bool multi = g.slices.size() > 1;
    check_geometry(g, multi);
    if (!first.has_spacing)
        warnings.push_back("PixelSpacing is missing; 1 mm assumed");
    else if (first.imager_spacing)
        warnings.push_back("PixelSpacing is missing; ImagerPixelSpacing (at the detector) used instead, "
                           "measurements may be off by the magnification factor");

    const glm::dvec3 row = glm::normalize(first.row), col = glm::normalize(first.col);
    const glm::dvec3 normal = glm::normalize(glm::cross(row, col));
    sort_slices(g, normal, where, warnings);

    const size_t n = g.slices.size();
    Layout out;
    out.grid.assign(n, 0); // slice index on the regular grid
    glm::dvec3 step_vec = normal * (first.thickness > 0 ? first.thickness : 1.0);
    if (n == 1 && first.thickness <= 0) warnings.push_back("single slice without SliceThickness: 1 mm assumed");
    if (n == 1 && (!first.has_ipp || !first.has_iop))
        warnings.push_back("ImagePositionPatient/ImageOrientationPatient missing: placed at the origin, axis-aligned");
    if (n > 1) {
        const bool irregular = place_on_grid(g.slices, normal, out.grid, warnings);
        step_vec = slice_step(g.slices, normal, out.grid, irregular, warnings);
    }

    glm::dmat4 affine(1.0);
    affine[0] = glm::dvec4(row * first.spacing_between_cols, 0.0);
    affine[1] = glm::dvec4(col * first.spacing_between_rows, 0.0);
    affine[2] = glm::dvec4(step_vec, 0.0);
    affine[3] = glm::dvec4(g.slices[0].ipp, 1.0);
    check_affine(where, affine, /*allow_shear=*/true);
    const std::string desc = upper(first.description);
    out.scout = desc.find("SCOUT") != std::string::npos || desc.find("LOCALI") != std::string::npos || first.localizer;
    if (out.scout)
        warnings.push_back("series \"" + first.description + "\" looks like a scout/localizer (" + std::to_string(n) +
                           " slice(s), " + fmt(glm::length(step_vec)) + " mm apart): not meant for 3D reconstruction");
    out.affine = affine;
    out.warnings = std::move(warnings);
    return out;
}

// A group's pixels as vtk-dicom decodes them (stored values, no rescale),
// one output slice per file, checked against the size the headers give.
// Compressed files are decoded in a child process (io/dicom_pixels.hpp).
struct Pixels {
    vtkSmartPointer<vtkDataArray> array;
    std::vector<int> file_of_slice; // output slice k holds g.slices[file_of_slice[k]]
    VoxelType stored = VoxelType::U8;
    std::vector<std::string> notes; // what the decoder said
};

Pixels read_pixels(const Group& g, const std::string& where, const ProgressFn& progress) {
    const size_t n = g.slices.size();
    const Slice& first = g.slices.front();
    std::vector<std::string> files;
    bool isolate = false;
    for (const auto& s : g.slices) {
        files.push_back(s.file);
        isolate = isolate || !dicom_is_native(s.transfer_syntax);
    }
    DecodedPixels d = decode_dicom_pixels(files, isolate, where, progress, 0.4, 0.9, kStage);
    if (d.dims[0] != first.cols || d.dims[1] != first.rows || d.dims[2] != int(n) || d.components != 1)
        throw Error(where, "pixel data does not have the size given by the headers (" + std::to_string(d.dims[0]) +
                               "x" + std::to_string(d.dims[1]) + "x" + std::to_string(d.dims[2]) + ")");
    // Map output slices to our files (the reader was told not to sort, but check).
    Pixels px;
    px.file_of_slice.resize(n);
    for (size_t k = 0; k < n; ++k) {
        const int f = d.file_index.size() == n ? d.file_index[k] : int(k);
        if (f < 0 || size_t(f) >= n) throw Error(where, "reader returned an unexpected slice order");
        px.file_of_slice[k] = f;
    }
    px.stored = voxel_type_of_vtk(d.array->GetDataType(), where);
    px.array = std::move(d.array);
    px.notes = std::move(d.notes);
    return px;
}

// The type the volume is stored in: the files' own, or after a rescale
// int16 when every rescaled value is an integer that fits, else float32
// (float64 for 32/64-bit data).
struct OutputType {
    VoxelType type;
    bool rescale; // some slice's slope/intercept is not 1/0
};

OutputType output_type(const Group& g, const Pixels& px) {
    bool any_rescale = false, all_integral = true;
    for (const auto& s : g.slices) {
        if (s.has_rescale && (s.slope != 1.0 || s.intercept != 0.0)) any_rescale = true;
        all_integral = all_integral && integral(s.slope) && integral(s.intercept);
    }
    const VoxelType stored = px.stored;
    if (!any_rescale) return {stored, false};
    const std::size_t plane = std::size_t(g.slices.front().cols) * std::size_t(g.slices.front().rows);
    const std::byte* raw = static_cast<const std::byte*>(px.array->GetVoidPointer(0));
    const std::size_t ssize = voxel_size(stored);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    dispatch_voxel_type(stored, [&](auto t) {
        using S = decltype(t);
        for (size_t k = 0; k < g.slices.size(); ++k) {
            const Slice& s = g.slices[px.file_of_slice[k]];
            const S* src = reinterpret_cast<const S*>(raw + k * plane * ssize);
            for (size_t i = 0; i < plane; ++i) {
                const double v = double(src[i]) * s.slope + s.intercept;
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
        }
    });
    VoxelType out_type = (all_integral && lo >= -32768.0 && hi <= 32767.0) ? VoxelType::I16 : VoxelType::F32;
    if (stored == VoxelType::F64 || stored == VoxelType::I32 || stored == VoxelType::U32)
        out_type = all_integral && lo >= -32768.0 && hi <= 32767.0 ? VoxelType::I16 : VoxelType::F64;
    return {out_type, true};
}

// Copies each file's slice to its place on the grid (rescaled when asked),
// then fills missing slices linearly between their neighbours on the grid.
void fill_volume(Volume& vol, const Group& g, const Pixels& px, const std::vector<int>& grid, const OutputType& out) {
    const size_t n = g.slices.size();
    const std::size_t plane = std::size_t(vol.dims[0]) * std::size_t(vol.dims[1]);
    const std::byte* raw = static_cast<const std::byte*>(px.array->GetVoidPointer(0));
    const std::size_t ssize = voxel_size(px.stored);
    dispatch_voxel_type(px.stored, [&](auto st) {
        using S = decltype(st);
        dispatch_voxel_type(out.type, [&](auto ot) {
            using O = decltype(ot);
            auto dst = vol.as<O>();
            auto put = [&](std::size_t idx, double v) {
                if constexpr (std::is_integral_v<O>)
                    dst[idx] = static_cast<O>(std::llround(v));
                else
                    dst[idx] = static_cast<O>(v);
            };
            for (size_t k = 0; k < n; ++k) {
                const size_t fi = px.file_of_slice[k];
                const Slice& s = g.slices[fi];
                const S* src = reinterpret_cast<const S*>(raw + k * plane * ssize);
                O* o = dst.data() + std::size_t(grid[fi]) * plane;
                if (out.rescale) {
                    for (size_t i = 0; i < plane; ++i) put(&o[i] - dst.data(), double(src[i]) * s.slope + s.intercept);
                } else {
                    for (size_t i = 0; i < plane; ++i) o[i] = static_cast<O>(src[i]);
                }
            }
            for (size_t k = 0; k + 1 < n; ++k) {
                const int a = grid[k], b = grid[k + 1];
                for (int z = a + 1; z < b; ++z) {
                    const double t = double(z - a) / double(b - a);
                    const O* pa = dst.data() + std::size_t(a) * plane;
                    const O* pb = dst.data() + std::size_t(b) * plane;
                    for (size_t i = 0; i < plane; ++i)
                        put(std::size_t(z) * plane + i, (1 - t) * double(pa[i]) + t * double(pb[i]));
                }
            }
        });
    });
}

Volume load_group(Group& g, const Scan& sc, const ProgressFn& progress) {
    const std::string where = sc.where;
    Layout layout = lay_out(g, where);
    const Slice first = g.slices.front();
    const std::int64_t nx = first.cols, ny = first.rows, nz = std::int64_t(layout.grid.back()) + 1;
    // Fail early on a size that cannot be allocated (float32 is the largest output type we pick
    // unless the files hold 32/64-bit data).
    checked_byte_size(where, {nx, ny, nz}, first.bits_allocated > 16 ? VoxelType::F64 : VoxelType::F32);

    const Pixels px = read_pixels(g, where, progress);
    const OutputType out = output_type(g, px);
    report(progress, 0.92, kStage, kWhere);
    Volume vol = Volume::dense({nx, ny, nz}, out.type, layout.affine);
    fill_volume(vol, g, px, layout.grid, out);

    vol.meta.format = "DICOM";
    vol.meta.modality = first.modality;
    vol.meta.patient_name = first.patient_name;
    vol.meta.patient_id = first.patient_id;
    vol.meta.study_uid = first.study_uid;
    vol.meta.series_uid = first.series_uid;
    vol.meta.series_description = first.description;
    vol.meta.reference_file = first.file;
    vol.meta.warnings = std::move(layout.warnings);
    vol.meta.warnings.insert(vol.meta.warnings.end(), px.notes.begin(), px.notes.end());
    return vol;
}

} // namespace

std::vector<SeriesInfo> list_dicom_series(const std::vector<std::string>& files_or_folder) {
    const Scan sc = scan(files_or_folder, {});
    std::vector<SeriesInfo> out;
    for (const auto& g : sc.groups) out.push_back(info_of(g, sc.where));
    return out;
}

Volume read_dicom(const std::vector<std::string>& files_or_folder, const LoadOptions& opt) {
    report(opt.progress, 0.0, kStage, kWhere);
    Scan sc = scan(files_or_folder, opt.progress);
    std::vector<SeriesInfo> list;
    for (const auto& g : sc.groups) list.push_back(info_of(g, sc.where));
    const int idx = select_series(sc, list, opt.series);
    Volume v = load_group(sc.groups[size_t(idx)], sc, opt.progress);
    v.meta.source = sc.where;
    v.meta.series = std::move(list);
    v.meta.selected_series = idx;
    v.meta.warnings.insert(v.meta.warnings.begin(), sc.notes.begin(), sc.notes.end());
    report(opt.progress, 1.0, kStage, kWhere);
    return v;
}

} // namespace iso
