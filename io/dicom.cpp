// DICOM series through vtk-dicom (vtkDICOMParser for headers, vtkDICOMReader
// for pixels; GDCM decodes compressed transfer syntaxes). The series logic is
// ours, because no installed library does all of it the way clinical tools
// expect (see docs/clinical.md):
//  - group by SeriesInstanceUID, then split by orientation, size and pixel
//    spacing; drop localizers; list several series, never merge them;
//  - sort along the normal of ImageOrientationPatient by ImagePositionPatient;
//    spacing from positions, not SliceThickness;
//  - missing slices (a step that is a whole multiple of the usual one) are
//    reported and filled by linear interpolation so the geometry stays right;
//    other non-uniform spacing is reported;
//  - gantry tilt (steps not along the normal) is reported and kept as a
//    sheared index->LPS affine, which places every voxel where it was
//    acquired (resampling to an orthogonal grid comes later);
//  - RescaleSlope/Intercept applied (vtkDICOMReader's AutoRescale, per slice).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMReader.h>
#include <vtkDICOMValue.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>

#include "io/vtk_util.hpp"
#include "io/volume_io.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

struct Slice {
    std::string file;
    std::string series_uid, study_uid, description, modality, patient_name, patient_id, image_type;
    int series_number = 0, instance_number = 0;
    int rows = 0, cols = 0, frames = 1, samples = 1;
    bool has_ipp = false, has_iop = false, has_spacing = false;
    glm::dvec3 ipp{0.0}, row{1, 0, 0}, col{0, 1, 0};
    double row_spacing = 1, col_spacing = 1; // PixelSpacing[0] (between rows), [1] (between columns)
    std::string problem; // why this file cannot be loaded (reported if its series is chosen)
};

struct Group {
    std::vector<Slice> slices;
    SeriesInfo info;
};

std::string str(vtkDICOMMetaData* m, vtkDICOMTag t) {
    const vtkDICOMValue& v = m->Get(t);
    if (!v.IsValid()) return "";
    std::string s = v.AsString();
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
    return s;
}

// Part 10 files carry "DICM" after a 128-byte preamble.
bool looks_like_dicom(const std::string& file) {
    std::ifstream f(file, std::ios::binary);
    char magic[4] = {};
    f.seekg(128);
    f.read(magic, 4);
    return f && std::memcmp(magic, "DICM", 4) == 0;
}

// Reads one file's header; false when it is not DICOM.
bool parse(const std::string& file, Slice& s) {
    vtkNew<vtkDICOMMetaData> meta;
    vtkNew<vtkDICOMParser> parser;
    vtkNew<VtkMessages> msgs;
    msgs->watch(parser);
    parser->SetMetaData(meta);
    parser->SetFileName(file.c_str());
    parser->Update();
    if (parser->GetErrorCode() || msgs->has_error()) {
        // A file with the DICOM magic that does not parse is damaged, not foreign.
        if (looks_like_dicom(file)) throw Error(file, "truncated or corrupt DICOM file: " + msgs->first_error());
        return false;
    }
    if (!meta->Has(DC::Rows) || !meta->Has(DC::Columns)) return false; // not an image (DICOMDIR, report, ...)
    s.file = file;
    // vtkDICOMReader reads a short file without complaint: check the length
    // of uncompressed pixel data against the file here.
    if (!parser->GetPixelDataFound()) {
        s.problem = "has no pixel data (truncated?)";
    } else if (parser->GetPixelDataVL() != 0xFFFFFFFFu &&
               parser->GetFileOffset() + vtkTypeInt64(parser->GetPixelDataVL()) > parser->GetFileSize()) {
        s.problem = "truncated: its pixel data needs " + std::to_string(parser->GetPixelDataVL()) + " bytes, " +
                    std::to_string(parser->GetFileSize() - parser->GetFileOffset()) + " are left in the file";
    }
    s.series_uid = str(meta, DC::SeriesInstanceUID);
    s.study_uid = str(meta, DC::StudyInstanceUID);
    s.description = str(meta, DC::SeriesDescription);
    s.modality = str(meta, DC::Modality);
    s.patient_name = str(meta, DC::PatientName);
    s.patient_id = str(meta, DC::PatientID);
    s.image_type = str(meta, DC::ImageType);
    s.series_number = meta->Get(DC::SeriesNumber).AsInt();
    s.instance_number = meta->Get(DC::InstanceNumber).AsInt();
    s.rows = meta->Get(DC::Rows).AsInt();
    s.cols = meta->Get(DC::Columns).AsInt();
    if (meta->Has(DC::NumberOfFrames)) s.frames = std::max(1, meta->Get(DC::NumberOfFrames).AsInt());
    if (meta->Has(DC::SamplesPerPixel)) s.samples = meta->Get(DC::SamplesPerPixel).AsInt();
    const vtkDICOMValue& ipp = meta->Get(DC::ImagePositionPatient);
    if (ipp.IsValid() && ipp.GetNumberOfValues() == 3) {
        double v[3];
        ipp.GetValues(v, 3);
        s.ipp = {v[0], v[1], v[2]};
        s.has_ipp = true;
    }
    const vtkDICOMValue& iop = meta->Get(DC::ImageOrientationPatient);
    if (iop.IsValid() && iop.GetNumberOfValues() == 6) {
        double v[6];
        iop.GetValues(v, 6);
        s.row = {v[0], v[1], v[2]};
        s.col = {v[3], v[4], v[5]};
        s.has_iop = true;
    }
    const vtkDICOMValue& ps = meta->Get(DC::PixelSpacing);
    if (ps.IsValid() && ps.GetNumberOfValues() == 2) {
        double v[2];
        ps.GetValues(v, 2);
        s.row_spacing = v[0];
        s.col_spacing = v[1];
        s.has_spacing = true;
    }
    return true;
}

std::vector<std::string> expand(const std::vector<std::string>& paths, std::string& where) {
    std::vector<std::string> files;
    for (const auto& p : paths) {
        std::error_code ec;
        if (fs::is_directory(p, ec)) {
            if (where.empty()) where = p;
            for (auto it = fs::recursive_directory_iterator(p, fs::directory_options::skip_permission_denied, ec);
                 it != fs::recursive_directory_iterator(); it.increment(ec)) {
                if (ec) break;
                if (it->is_regular_file(ec)) files.push_back(it->path().string());
            }
        } else if (fs::is_regular_file(p, ec)) {
            if (where.empty()) where = p;
            files.push_back(p);
        } else {
            throw Error(p, "no such file or folder");
        }
    }
    std::sort(files.begin(), files.end());
    return files;
}

std::string round_key(double x, double step) {
    std::ostringstream os;
    os << std::llround(x / step);
    return os.str();
}

// Scans, parses, groups. Localizers are dropped (counted in `dropped`).
std::vector<Group> scan(const std::vector<std::string>& paths, std::string& where, std::size_t& dropped,
                        const ProgressFn& progress) {
    const auto files = expand(paths, where);
    if (files.empty()) throw Error(where.empty() ? "DICOM" : where, "folder is empty");
    std::map<std::string, Group> groups;
    std::size_t dicom = 0;
    for (std::size_t i = 0; i < files.size(); ++i) {
        Slice s;
        if (parse(files[i], s)) {
            ++dicom;
            if (s.image_type.find("LOCALIZER") != std::string::npos) {
                ++dropped;
            } else {
                std::string key = s.series_uid + "|" + std::to_string(s.rows) + "x" + std::to_string(s.cols);
                if (s.has_iop)
                    for (int k = 0; k < 3; ++k) key += "|" + round_key(s.row[k], 1e-4) + "," + round_key(s.col[k], 1e-4);
                if (s.has_spacing) key += "|" + round_key(s.row_spacing, 1e-4) + "," + round_key(s.col_spacing, 1e-4);
                groups[key].slices.push_back(std::move(s));
            }
        }
        if (i % 16 == 0) report(progress, 0.5 * double(i) / double(files.size()), "scanning DICOM files", "read_dicom");
    }
    if (dicom == 0)
        throw Error(where, "no DICOM files found (" + std::to_string(files.size()) + " file" + (files.size() == 1 ? "" : "s") +
                               " looked at)");
    if (groups.empty()) throw Error(where, "only localizer images found (" + std::to_string(dropped) + ")");
    std::vector<Group> out;
    for (auto& [key, g] : groups) out.push_back(std::move(g));
    std::sort(out.begin(), out.end(), [](const Group& a, const Group& b) {
        const Slice &x = a.slices[0], &y = b.slices[0];
        if (x.series_number != y.series_number) return x.series_number < y.series_number;
        if (x.series_uid != y.series_uid) return x.series_uid < y.series_uid;
        return a.slices.size() > b.slices.size();
    });
    // Series split by orientation or size get a "#k" suffix on their UID.
    std::map<std::string, int> seen;
    for (auto& g : out) {
        const Slice& s = g.slices[0];
        const int k = ++seen[s.series_uid];
        g.info.uid = s.series_uid;
        if (k > 1) g.info.uid += "#" + std::to_string(k);
        g.info.description = s.description;
        g.info.modality = s.modality;
        g.info.number = s.series_number;
        g.info.dims = {s.cols, s.rows, int(g.slices.size()) * s.frames};
        g.info.files = g.slices.size();
    }
    return out;
}

std::string listing(const std::vector<Group>& groups) {
    std::string s;
    for (std::size_t i = 0; i < groups.size(); ++i) {
        const auto& g = groups[i].info;
        s += "\n  [" + std::to_string(i) + "] " + g.modality + " #" + std::to_string(g.number) + " " + std::to_string(g.dims[0]) + "x" +
             std::to_string(g.dims[1]) + "x" + std::to_string(g.dims[2]) + " '" + g.description + "' " + g.uid;
    }
    return s;
}

std::size_t select(const std::vector<Group>& groups, const std::string& want, const std::string& where) {
    if (want.empty()) {
        if (groups.size() == 1) return 0;
        throw Error(where, "holds " + std::to_string(groups.size()) +
                               " series; choose one with --series N (index) or --series UID:" + listing(groups));
    }
    if (std::all_of(want.begin(), want.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
        const auto i = std::stoull(want);
        if (i < groups.size()) return std::size_t(i);
        throw Error(where, "series index " + want + " is out of range (" + std::to_string(groups.size()) + " series):" + listing(groups));
    }
    for (std::size_t i = 0; i < groups.size(); ++i)
        if (groups[i].info.uid == want) return i;
    throw Error(where, "no series with UID " + want + ":" + listing(groups));
}

VoxelType type_of(vtkDataArray* a, const std::string& where) {
    switch (a->GetDataType()) {
    case VTK_SIGNED_CHAR:
    case VTK_CHAR: return VoxelType::I8;
    case VTK_UNSIGNED_CHAR: return VoxelType::U8;
    case VTK_SHORT: return VoxelType::I16;
    case VTK_UNSIGNED_SHORT: return VoxelType::U16;
    case VTK_INT: return VoxelType::I32;
    case VTK_UNSIGNED_INT: return VoxelType::U32;
    case VTK_FLOAT: return VoxelType::F32;
    case VTK_DOUBLE: return VoxelType::F64;
    default: break;
    }
    throw Error(where, std::string("unsupported pixel data type ") + a->GetDataTypeAsString());
}

} // namespace

std::vector<SeriesInfo> list_dicom_series(const std::vector<std::string>& paths) {
    quiet_vtk();
    std::string where;
    std::size_t dropped = 0;
    std::vector<SeriesInfo> out;
    for (auto& g : scan(paths, where, dropped, {})) out.push_back(g.info);
    return out;
}

Volume read_dicom(const std::vector<std::string>& paths, const LoadOptions& opt) {
    quiet_vtk();
    std::string where;
    std::size_t dropped = 0;
    auto groups = scan(paths, where, dropped, opt.progress);
    const std::size_t chosen = select(groups, opt.series, where);
    Group& g = groups[chosen];
    auto& slices = g.slices;
    for (const auto& s : slices)
        if (!s.problem.empty()) throw Error(s.file, s.problem);
    const Slice& first = slices[0];
    std::vector<std::string> warnings;
    if (dropped) warnings.push_back(std::to_string(dropped) + " localizer image(s) ignored");
    if (first.frames > 1)
        throw Error(first.file, "multi-frame (enhanced) DICOM with " + std::to_string(first.frames) +
                                    " frames is not supported yet");
    if (first.samples != 1)
        throw Error(first.file, "colour images (" + std::to_string(first.samples) + " samples per pixel) are not supported");
    if (first.rows <= 0 || first.cols <= 0) throw Error(first.file, "image has no rows or columns");

    // Geometry.
    for (const auto& s : slices) {
        if (!s.has_ipp || !s.has_iop) {
            if (slices.size() == 1) break;
            throw Error(s.file, "has no ImagePositionPatient/ImageOrientationPatient: the slices cannot be placed");
        }
        if (!std::isfinite(s.ipp.x + s.ipp.y + s.ipp.z + s.row.x + s.row.y + s.row.z + s.col.x + s.col.y + s.col.z))
            throw Error(s.file, "ImagePositionPatient or ImageOrientationPatient is not a number");
    }
    if (!(first.row_spacing > 0 && first.col_spacing > 0) || !std::isfinite(first.row_spacing + first.col_spacing))
        throw Error(first.file, "PixelSpacing is zero, negative or not a number");
    if (!first.has_spacing) warnings.push_back("no PixelSpacing: 1 mm assumed");
    glm::dvec3 row = first.row, col = first.col;
    if (first.has_iop) {
        if (std::abs(glm::length(row) - 1) > 1e-3 || std::abs(glm::length(col) - 1) > 1e-3 || std::abs(glm::dot(row, col)) > 1e-3)
            throw Error(first.file, "ImageOrientationPatient is not two orthogonal unit vectors");
        row = glm::normalize(row);
        col = glm::normalize(col - glm::dot(col, row) * row);
    } else {
        warnings.push_back("no ImagePositionPatient/ImageOrientationPatient: placed at the origin, axes along L and P");
    }
    const glm::dvec3 normal = glm::cross(row, col);
    std::stable_sort(slices.begin(), slices.end(),
                     [&](const Slice& a, const Slice& b) { return glm::dot(a.ipp, normal) < glm::dot(b.ipp, normal); });
    const std::size_t n = slices.size();
    std::vector<double> steps;
    for (std::size_t i = 1; i < n; ++i) {
        const double d = glm::dot(slices[i].ipp - slices[i - 1].ipp, normal);
        if (std::abs(d) < 1e-3) {
            std::size_t same = 0;
            for (std::size_t k = 1; k < n; ++k)
                if (std::abs(glm::dot(slices[k].ipp - slices[k - 1].ipp, normal)) < 1e-3) ++same;
            throw Error(where, std::to_string(same + 1) + " or more slices share a position (e.g. " + slices[i - 1].file + " and " +
                                   slices[i].file + "): several acquisitions, echoes or phases in one series are not supported");
        }
        steps.push_back(d);
    }
    // Grid: slice k of the volume is at first + k * step along the normal.
    std::vector<int> grid_index(n, 0);
    double step = 1.0;
    glm::dvec3 step_vec = normal;
    std::size_t nz = n;
    if (n > 1) {
        std::vector<double> sorted = steps;
        std::sort(sorted.begin(), sorted.end());
        step = sorted.front(); // the smallest step: gaps are multiples of it
        const double tol = std::max(0.01, 1e-3 * step);
        bool uniform = true, gaps = false;
        std::string gap_text;
        int k = 0;
        for (std::size_t i = 0; i < steps.size(); ++i) {
            const double m = std::round(steps[i] / step);
            if (std::abs(steps[i] - step) <= tol) {
                ++k;
            } else if (m >= 2 && std::abs(steps[i] - m * step) <= tol * m) {
                gaps = true;
                gap_text += (gap_text.empty() ? "" : "; ") + std::to_string(int(m) - 1) + " between " + fs::path(slices[i].file).filename().string() +
                            " and " + fs::path(slices[i + 1].file).filename().string();
                k += int(m);
            } else {
                uniform = false;
                k += std::max(1, int(m));
            }
            grid_index[i + 1] = k;
        }
        nz = std::size_t(grid_index[n - 1]) + 1;
        if (!uniform) {
            warnings.push_back("non-uniform slice spacing (steps from " + std::to_string(sorted.front()) + " to " +
                               std::to_string(sorted.back()) + " mm): slices are placed on a regular grid of " +
                               std::to_string(step) + " mm and may be off by up to " +
                               std::to_string(sorted.back() - step) + " mm");
        }
        if (gaps)
            warnings.push_back("missing slices (" + gap_text + "): " + std::to_string(nz - n) +
                               " slice(s) filled by linear interpolation of their neighbours");
        // The mean step vector: along the normal unless the gantry was tilted.
        step_vec = (slices[n - 1].ipp - slices[0].ipp) / double(nz - 1);
        const glm::dvec3 inplane = step_vec - glm::dot(step_vec, normal) * normal;
        if (glm::length(inplane) > 1e-3 * std::max(1.0, glm::dot(step_vec, normal)) + 1e-4) {
            const double tilt = std::atan2(glm::length(inplane), glm::dot(step_vec, normal)) * 180.0 / M_PI;
            std::ostringstream os;
            os.precision(3);
            os << "gantry tilt of " << tilt << " degrees (slice positions are sheared): kept as a sheared index-to-LPS "
               << "matrix, which places every voxel where it was acquired";
            warnings.push_back(os.str());
        }
    }

    // Pixels, in our slice order.
    vtkNew<vtkStringArray> names;
    for (const auto& s : slices) names->InsertNextValue(s.file);
    vtkNew<vtkDICOMReader> reader;
    vtkNew<VtkMessages> msgs;
    msgs->watch(reader);
    reader->SetFileNames(names);
    reader->SortingOff();                     // keep our order
    reader->SetMemoryRowOrderToFileNative();  // voxel (i, j) = column i of row j, as DICOM stores it
    reader->AutoRescaleOn();                  // RescaleSlope/Intercept per slice
    reader->Update();
    if (reader->GetErrorCode() || msgs->has_error())
        throw Error(where, "cannot read the pixel data: " + msgs->first_error());
    vtkImageData* img = reader->GetOutput();
    vtkDataArray* arr = img ? img->GetPointData()->GetScalars() : nullptr;
    if (!arr || arr->GetNumberOfComponents() != 1) throw Error(where, "pixel data could not be read as one scalar per voxel");
    int d[3];
    img->GetDimensions(d);
    if (d[0] != first.cols || d[1] != first.rows || std::size_t(d[2]) != n)
        throw Error(where, "pixel data does not match the headers (truncated or corrupt files?)");
    const VoxelType type = type_of(arr, where);
    const std::array<std::int64_t, 3> dims{first.cols, first.rows, std::int64_t(nz)};
    checked_byte_size(where, dims, type);

    glm::dmat4 affine(1.0);
    affine[0] = glm::dvec4(row * first.col_spacing, 0.0);
    affine[1] = glm::dvec4(col * first.row_spacing, 0.0);
    affine[2] = glm::dvec4(n > 1 ? step_vec : normal * 1.0, 0.0);
    affine[3] = glm::dvec4(first.ipp, 1.0);
    check_affine(where, affine, /*allow_shear=*/true);

    Volume v = Volume::dense(dims, type, affine);
    const std::size_t slice_bytes = std::size_t(dims[0] * dims[1]) * voxel_size(type);
    const auto* src = static_cast<const std::byte*>(arr->GetVoidPointer(0));
    for (std::size_t i = 0; i < n; ++i)
        std::memcpy(v.bytes().data() + std::size_t(grid_index[i]) * slice_bytes, src + i * slice_bytes, slice_bytes);
    // Fill gaps by linear interpolation between the real neighbours.
    for (std::size_t i = 0; i + 1 < n; ++i) {
        const int a = grid_index[i], b = grid_index[i + 1];
        for (int k = a + 1; k < b; ++k) {
            const double w = double(k - a) / double(b - a);
            dispatch_voxel_type(type, [&](auto tag) {
                using T = decltype(tag);
                auto s = v.as<T>();
                const std::size_t plane = std::size_t(dims[0] * dims[1]);
                for (std::size_t p = 0; p < plane; ++p) {
                    const double x = (1 - w) * double(s[std::size_t(a) * plane + p]) + w * double(s[std::size_t(b) * plane + p]);
                    s[std::size_t(k) * plane + p] = std::is_integral_v<T> ? T(std::lround(x)) : T(x);
                }
                return 0;
            });
        }
    }
    report(opt.progress, 1.0, "reading DICOM", "read_dicom");

    v.meta.source = where;
    v.meta.format = "DICOM";
    v.meta.modality = first.modality;
    v.meta.patient_name = first.patient_name;
    v.meta.patient_id = first.patient_id;
    v.meta.study_uid = first.study_uid;
    v.meta.series_uid = g.info.uid;
    v.meta.series_description = first.description;
    for (const auto& gr : groups) v.meta.series.push_back(gr.info);
    v.meta.selected_series = int(chosen);
    v.meta.warnings = std::move(warnings);
    warn_non_finite(v);
    return v;
}

} // namespace iso
