// DICOM series reader: series written here with vtkDICOMWriter (known voxel
// pattern value = i + 10*j + 100*k), edited with vtkDICOMCompiler where a
// case needs headers the writer cannot produce (gantry tilt, bad geometry,
// localizer inside a series), plus the real Siemens files in datasets/.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include <vtkDICOMCTGenerator.h>
#include <vtkDICOMCompiler.h>
#include <vtkDICOMMRGenerator.h>
#include <vtkDICOMSCGenerator.h>
#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMValue.h>
#include <vtkDICOMWriter.h>
#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>

#include "io/error.hpp"
#include "io/volume_io.hpp"
#include "renderer/core/api.hpp"
#include "tests/support/dicom_fixtures.hpp"
#include "tests/support/expect.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::error_of;
using iso::test::pattern;
using iso::test::rot_x;
using iso::test::rot_z;
using iso::test::SeriesSpec;
using iso::test::TempDir;
using iso::test::write_series;
namespace fs = std::filesystem;

namespace {

constexpr double kMm = 1e-4;

struct Header {
    std::string file;
    glm::dvec3 ipp{0}, row{0}, col{0};
    double ps[2] = {0, 0};
    int rows = 0, cols = 0;
    std::string series_uid;
};

vtkSmartPointer<vtkDICOMMetaData> parse(const std::string& file) {
    auto md = vtkSmartPointer<vtkDICOMMetaData>::New();
    vtkNew<vtkDICOMParser> p;
    p->SetMetaData(md);
    p->SetFileName(file.c_str());
    p->Update();
    EXPECT_EQ(p->GetErrorCode(), 0u) << file;
    return md;
}

Header header(const std::string& file) {
    auto md = parse(file);
    Header h;
    h.file = file;
    double v[6];
    md->Get(DC::ImagePositionPatient).GetValues(v, 3);
    h.ipp = {v[0], v[1], v[2]};
    md->Get(DC::ImageOrientationPatient).GetValues(v, 6);
    h.row = {v[0], v[1], v[2]};
    h.col = {v[3], v[4], v[5]};
    md->Get(DC::PixelSpacing).GetValues(h.ps, 2);
    h.rows = md->Get(DC::Rows).AsInt();
    h.cols = md->Get(DC::Columns).AsInt();
    h.series_uid = md->Get(DC::SeriesInstanceUID).AsString();
    return h;
}

std::vector<std::string> dcm_files(const std::string& dir) {
    std::vector<std::string> out;
    for (auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".dcm") out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// Headers sorted by position along the normal (computed here, from the files).
std::vector<Header> sorted_headers(const std::string& dir) {
    std::vector<Header> hs;
    for (auto& f : dcm_files(dir)) hs.push_back(header(f));
    const glm::dvec3 n = glm::cross(hs[0].row, hs[0].col);
    std::sort(hs.begin(), hs.end(),
              [&](const Header& a, const Header& b) { return glm::dot(a.ipp, n) < glm::dot(b.ipp, n); });
    return hs;
}

// The affine DICOM defines, from the header fields of the sorted files.
glm::dmat4 expected_affine(const std::vector<Header>& hs, int steps) {
    glm::dmat4 m(1.0);
    m[0] = glm::dvec4(hs[0].row * hs[0].ps[1], 0);
    m[1] = glm::dvec4(hs[0].col * hs[0].ps[0], 0);
    m[2] = glm::dvec4((hs.back().ipp - hs.front().ipp) / double(steps), 0);
    m[3] = glm::dvec4(hs[0].ipp, 1);
    return m;
}

void expect_affine_mm(const glm::dmat4& a, const glm::dmat4& b, double tol = kMm) {
    test::expect_affine_near(a, b, tol);
}

// Raw stored pixel values of an uncompressed 16-bit file: the PixelData value is
// the last rows*cols*2 bytes of the files vtkDICOMWriter writes.
std::vector<short> raw_pixels(const Header& h) {
    std::ifstream in(h.file, std::ios::binary | std::ios::ate);
    const auto size = static_cast<std::streamoff>(in.tellg());
    const std::streamoff n = std::streamoff(h.rows) * h.cols * 2;
    std::vector<short> px(size_t(h.rows) * h.cols);
    in.seekg(size - n);
    in.read(reinterpret_cast<char*>(px.data()), n);
    return px;
}

// Re-writes a file with edited metadata (same UIDs, same pixel bytes).
void rewrite(const std::string& src, const std::string& dst, const std::function<void(vtkDICOMMetaData*)>& edit,
             const char* transfer_syntax = nullptr) {
    auto md = parse(src);
    const Header h = header(src);
    std::vector<short> px = raw_pixels(h);
    edit(md);
    vtkNew<vtkDICOMCompiler> c;
    const std::string series = md->Get(DC::SeriesInstanceUID).AsString();
    const std::string sop = md->Get(DC::SOPInstanceUID).AsString();
    const std::string study = md->Get(DC::StudyInstanceUID).AsString();
    c->SetFileName(dst.c_str());
    c->SetMetaData(md);
    c->SetSeriesInstanceUID(series.c_str());
    c->SetSOPInstanceUID(sop.c_str());
    c->SetStudyInstanceUID(study.c_str());
    if (transfer_syntax) c->SetTransferSyntaxUID(transfer_syntax);
    c->WriteHeader();
    c->WritePixelData(reinterpret_cast<const unsigned char*>(px.data()), vtkIdType(px.size() * 2));
    c->Close();
    ASSERT_EQ(c->GetErrorCode(), 0u) << dst;
}

void set_ds(vtkDICOMMetaData* md, vtkDICOMTag tag, std::vector<double> v) {
    md->Set(tag, vtkDICOMValue(vtkDICOMVR::DS, v.data(), v.size()));
}

bool any_warning(const Volume& v, const std::string& needle) {
    return std::any_of(v.meta.warnings.begin(), v.meta.warnings.end(),
                       [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

// The series chooser's warnings (SeriesInfo::warnings): from the headers
// alone, the same as loading gives.
bool any_listed_warning(const SeriesInfo& si, const std::string& needle) {
    return std::any_of(si.warnings.begin(), si.warnings.end(),
                       [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

std::string all_warnings(const Volume& v) {
    std::string s;
    for (auto& w : v.meta.warnings) s += w + "\n";
    return s;
}

} // namespace

TEST(Dicom, AxialCtDimsValuesAndAffine) {
    TempDir tmp;
    const std::string dir = tmp / "ct";
    SeriesSpec spec;
    write_series(dir, spec);
    const Volume v = load_volume(dir);
    ASSERT_EQ(v.dims[0], 16);
    ASSERT_EQ(v.dims[1], 12);
    ASSERT_EQ(v.dims[2], 8);
    EXPECT_EQ(v.type, VoxelType::I16); // integral rescale, range fits int16
    EXPECT_EQ(v.meta.format, "DICOM");
    EXPECT_EQ(v.meta.source, dir);
    EXPECT_EQ(v.meta.modality, "CT");
    EXPECT_EQ(v.meta.series_description, "test series");
    EXPECT_FALSE(v.meta.series_uid.empty());
    EXPECT_FALSE(v.meta.study_uid.empty());
    ASSERT_EQ(v.meta.series.size(), 1u);
    EXPECT_EQ(v.meta.selected_series, 0);
    EXPECT_EQ(v.meta.series[0].files, 8u);
    EXPECT_TRUE(v.meta.warnings.empty()) << all_warnings(v);

    // Affine from the header fields of the written files.
    const auto hs = sorted_headers(dir);
    ASSERT_EQ(hs.size(), 8u);
    expect_affine_mm(v.index_to_lps, expected_affine(hs, 7));
    // ... and from the construction.
    glm::dmat4 built(1.0);
    for (int a = 0; a < 3; ++a) built[a] = glm::dvec4(spec.rot[a] * spec.spacing[a], 0);
    built[3] = glm::dvec4(spec.origin, 1);
    expect_affine_mm(v.index_to_lps, built);

    // HU = stored + intercept; voxel (i, j, k) = pattern.
    for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 16; ++i) ASSERT_EQ(v.value(i, j, k), pattern(i, j, k) - 1024) << i << j << k;

    // Independent read of raw pixels: voxel (i, j, k) = pixel (column i, row j) of the k-th file.
    for (int k = 0; k < 8; ++k) {
        const auto px = raw_pixels(hs[size_t(k)]);
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 16; ++i) ASSERT_EQ(v.value(i, j, k), px[size_t(j * 16 + i)] - 1024);
    }
}

TEST(Dicom, NonIntegralRescaleGivesFloat) {
    TempDir tmp;
    SeriesSpec spec;
    spec.slope = 0.5;
    spec.intercept = -100.25;
    write_series(tmp / "ct", spec);
    const Volume v = load_volume(tmp / "ct");
    ASSERT_EQ(v.type, VoxelType::F32);
    EXPECT_FLOAT_EQ(float(v.value(3, 4, 5)), float(pattern(3, 4, 5) * 0.5 - 100.25));
}

TEST(Dicom, PerSliceRescaleIsAppliedPerSlice) {
    TempDir tmp;
    write_series(tmp / "w", SeriesSpec{});
    const auto hs = sorted_headers(tmp / "w");
    auto edit_slope = [&](const std::string& dir, double slope) {
        fs::create_directories(dir);
        for (size_t k = 0; k < hs.size(); ++k) {
            const std::string dst = dir + "/" + fs::path(hs[k].file).filename().string();
            if (k == 5)
                rewrite(hs[k].file, dst, [&](vtkDICOMMetaData* md) { set_ds(md, DC::RescaleSlope, {slope}); });
            else
                fs::copy_file(hs[k].file, dst);
        }
        return load_volume(dir);
    };
    // Integral and within int16: int16, slice 5 doubled.
    const Volume a = edit_slope(tmp / "a", 2);
    EXPECT_EQ(a.type, VoxelType::I16);
    EXPECT_EQ(a.value(3, 4, 5), 2 * pattern(3, 4, 5) - 1024);
    EXPECT_EQ(a.value(3, 4, 4), pattern(3, 4, 4) - 1024);
    // Beyond int16 (825 * 100 - 1024): float32.
    const Volume b = edit_slope(tmp / "b", 100);
    EXPECT_EQ(b.type, VoxelType::F32);
    EXPECT_EQ(b.value(15, 11, 5), 100.0 * pattern(15, 11, 5) - 1024);
    EXPECT_EQ(b.value(15, 11, 6), pattern(15, 11, 6) - 1024);
}

TEST(Dicom, MrWithoutRescaleKeepsStoredType) {
    TempDir tmp;
    SeriesSpec spec;
    spec.ct = false; // MR, no rescale
    write_series(tmp / "mr", spec);
    const Volume v = load_volume(tmp / "mr");
    EXPECT_TRUE(v.type == VoxelType::I16 || v.type == VoxelType::U16) << voxel_type_name(v.type);
    EXPECT_EQ(v.value(15, 11, 7), pattern(15, 11, 7));
}

TEST(Dicom, ObliqueAffineIsRotatedAndMatchesHeaders) {
    TempDir tmp;
    SeriesSpec spec;
    spec.rot = rot_z(30) * rot_x(30);
    write_series(tmp / "obl", spec);
    const Volume v = load_volume(tmp / "obl");
    const auto hs = sorted_headers(tmp / "obl");
    expect_affine_mm(v.index_to_lps, expected_affine(hs, 7));
    const glm::dvec3 c0 = glm::dvec3(v.index_to_lps[0]), c1 = glm::dvec3(v.index_to_lps[1]),
                     c2 = glm::dvec3(v.index_to_lps[2]);
    EXPECT_NEAR(glm::length(c0), 0.7, kMm);
    EXPECT_NEAR(glm::length(c1), 0.8, kMm);
    EXPECT_NEAR(glm::length(c2), 2.5, kMm);
    EXPECT_NEAR(glm::dot(c0, c1), 0, kMm);
    EXPECT_NEAR(glm::dot(c0, c2), 0, kMm);
    EXPECT_NEAR(glm::dot(c1, c2), 0, kMm);
    // Really rotated: not axis-aligned.
    EXPECT_GT(std::abs(c0.y), 0.1);
    EXPECT_GT(std::abs(c2.y), 0.1);
    for (int a = 0; a < 3; ++a)
        for (int r = 0; r < 3; ++r) EXPECT_NEAR(v.index_to_lps[a][r], spec.rot[a][r] * spec.spacing[a], kMm);
    EXPECT_TRUE(v.meta.warnings.empty()) << all_warnings(v);
    EXPECT_EQ(v.value(5, 6, 7), pattern(5, 6, 7) - 1024);
}

TEST(Dicom, ReverseFileOrderAndShuffledNamesStillSort) {
    TempDir tmp;
    SeriesSpec spec;
    spec.rot = rot_x(20);
    write_series(tmp / "w", spec);
    // Rename the files to shuffled names (and a file order unrelated to position).
    auto files = dcm_files(tmp / "w");
    std::vector<int> perm(files.size());
    for (size_t i = 0; i < perm.size(); ++i) perm[i] = int(i);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(42));
    fs::create_directories(tmp / "s");
    for (size_t i = 0; i < files.size(); ++i)
        fs::rename(files[i], tmp / ("s/img" + std::to_string(perm[i] * 7 % 11) + "_" + std::to_string(perm[i])));
    const Volume v = load_volume(tmp / "s");
    ASSERT_EQ(v.dims[2], 8);
    for (int k = 0; k < 8; ++k) EXPECT_EQ(v.value(1, 2, k), pattern(1, 2, k) - 1024) << k;
    glm::dmat4 built(1.0);
    for (int a = 0; a < 3; ++a) built[a] = glm::dvec4(spec.rot[a] * spec.spacing[a], 0);
    built[3] = glm::dvec4(spec.origin, 1);
    expect_affine_mm(v.index_to_lps, built);
}

TEST(Dicom, MissingSliceIsReportedAndInterpolated) {
    TempDir tmp;
    write_series(tmp / "gap", SeriesSpec{});
    const auto hs = sorted_headers(tmp / "gap");
    fs::remove(hs[3].file); // slice k = 3 missing
    const Volume v = load_volume(tmp / "gap");
    ASSERT_EQ(v.dims[2], 8); // the regular grid, gap filled
    EXPECT_TRUE(any_warning(v, "missing slice")) << all_warnings(v);
    EXPECT_TRUE(any_warning(v, "between slice 2")) << all_warnings(v);
    EXPECT_TRUE(any_warning(v, "interpolat")) << all_warnings(v);
    expect_affine_mm(v.index_to_lps, expected_affine(hs, 7));
    // The pattern is linear in k, so the interpolated slice equals the missing one.
    for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 16; ++i) ASSERT_EQ(v.value(i, j, 3), pattern(i, j, 3) - 1024);
    EXPECT_EQ(v.value(4, 5, 4), pattern(4, 5, 4) - 1024);
    // Listed before loading: the same warnings, and the depth the load gives.
    const auto list = list_dicom_series({tmp / "gap"});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].files, 7u);
    EXPECT_EQ(list[0].dims[2], 8);
    EXPECT_EQ(list[0].warnings, v.meta.warnings);
    EXPECT_TRUE(any_listed_warning(list[0], "missing slice"));
}

TEST(Dicom, NonUniformSpacingWarns) {
    TempDir tmp;
    write_series(tmp / "w", SeriesSpec{});
    const auto hs = sorted_headers(tmp / "w");
    // Move the last slice by 1 mm (a step of 3.5 mm, not a multiple of 2.5).
    rewrite(hs[7].file, hs[7].file + ".moved.dcm", [&](vtkDICOMMetaData* md) {
        set_ds(md, DC::ImagePositionPatient, {hs[7].ipp.x, hs[7].ipp.y, hs[7].ipp.z + 1.0});
    });
    fs::remove(hs[7].file);
    const Volume v = load_volume(tmp / "w");
    EXPECT_EQ(v.dims[2], 8);
    EXPECT_TRUE(any_warning(v, "not uniform")) << all_warnings(v);
    EXPECT_TRUE(any_warning(v, "3.5")) << all_warnings(v);
    const auto list = list_dicom_series({tmp / "w"});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].warnings, v.meta.warnings);
    EXPECT_TRUE(any_listed_warning(list[0], "not uniform"));
}

TEST(Dicom, GantryTiltIsDetectedAndAffineIsSheared) {
    TempDir tmp;
    SeriesSpec spec;
    write_series(tmp / "w", spec);
    const double tilt = 15.0;
    const auto hs = sorted_headers(tmp / "w");
    fs::create_directories(tmp / "tilt");
    std::vector<glm::dvec3> ipps;
    for (size_t k = 0; k < hs.size(); ++k) {
        // Shift each slice along the column direction (y) in proportion to its z.
        const double z = glm::dot(hs[k].ipp - hs[0].ipp, glm::cross(hs[k].row, hs[k].col));
        glm::dvec3 ipp = hs[k].ipp + hs[k].col * (z * std::tan(tilt * M_PI / 180));
        ipps.push_back(ipp);
        rewrite(hs[k].file, tmp / ("tilt/T" + std::to_string(k) + ".dcm"), [&](vtkDICOMMetaData* md) {
            set_ds(md, DC::ImagePositionPatient, {ipp.x, ipp.y, ipp.z});
        });
    }
    const Volume v = load_volume(tmp / "tilt");
    ASSERT_EQ(v.dims[2], 8);
    bool found = false;
    for (const auto& w : v.meta.warnings) {
        auto p = w.find("gantry tilt of ");
        if (p == std::string::npos) continue;
        found = true;
        EXPECT_NEAR(std::stod(w.substr(p + 15)), tilt, 0.05) << w;
    }
    EXPECT_TRUE(found) << all_warnings(v);
    const auto list = list_dicom_series({tmp / "tilt"});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].warnings, v.meta.warnings);
    EXPECT_TRUE(any_listed_warning(list[0], "gantry tilt of 15"));
    // Each slice origin maps to its IPP.
    for (int k = 0; k < 8; ++k) {
        const glm::dvec3 w = v.index_to_world({0, 0, double(k)});
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], ipps[size_t(k)][a], kMm) << k;
    }
    // In-plane columns unchanged.
    EXPECT_NEAR(v.index_to_lps[0][0], 0.7, kMm);
    EXPECT_NEAR(v.index_to_lps[1][1], 0.8, kMm);
    EXPECT_NEAR(v.index_to_lps[2][2], 2.5, kMm);
    EXPECT_EQ(v.value(3, 3, 3), pattern(3, 3, 3) - 1024);
}

TEST(Dicom, TwoSeriesAreListedAndChosen) {
    TempDir tmp;
    const std::string dir = tmp / "two";
    SeriesSpec a;
    a.description = "first";
    a.series_number = 1;
    a.pattern = "%s/A-%04d.dcm";
    SeriesSpec b;
    b.description = "second";
    b.series_number = 2;
    b.nz = 5;
    b.pattern = "%s/B-%04d.dcm";
    b.origin = {0, 0, 0};
    write_series(dir, a);
    write_series(dir, b);

    const auto list = list_dicom_series({dir});
    ASSERT_EQ(list.size(), 2u);
    int ia = list[0].description == "first" ? 0 : 1, ib = 1 - ia;
    EXPECT_EQ(list[size_t(ia)].description, "first");
    EXPECT_EQ(list[size_t(ib)].description, "second");
    EXPECT_EQ(list[size_t(ia)].files, 8u);
    EXPECT_EQ(list[size_t(ib)].dims[2], 5);
    EXPECT_NE(list[0].uid, list[1].uid);
    EXPECT_TRUE(list[0].warnings.empty());
    EXPECT_TRUE(list[1].warnings.empty());

    const std::string msg = error_of([&] { load_volume(dir); });
    EXPECT_NE(msg.find("2 series"), std::string::npos) << msg;
    // The library names the setting (LoadOptions::series), not the CLI's flag.
    EXPECT_NE(msg.find("DICOM series: "), std::string::npos) << msg;
    EXPECT_NE(msg.find("by its index in this list or its SeriesInstanceUID"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("--series"), std::string::npos) << msg;
    EXPECT_NE(msg.find(dir), std::string::npos) << msg;
    EXPECT_NE(msg.find("first"), std::string::npos) << msg;
    EXPECT_NE(msg.find(list[0].uid), std::string::npos) << msg;

    LoadOptions by_index;
    by_index.series = std::to_string(ib);
    const Volume vb = load_volume(dir, by_index);
    EXPECT_EQ(vb.dims[2], 5);
    EXPECT_EQ(vb.meta.series_description, "second");
    EXPECT_EQ(vb.meta.selected_series, ib);
    EXPECT_EQ(vb.meta.series.size(), 2u);

    LoadOptions by_uid;
    by_uid.series = list[size_t(ia)].uid;
    const Volume va = load_volume(dir, by_uid);
    EXPECT_EQ(va.dims[2], 8);
    EXPECT_EQ(va.meta.series_description, "first");
    EXPECT_EQ(va.meta.selected_series, ia);

    LoadOptions bad;
    bad.series = "7";
    EXPECT_NE(error_of([&] { load_volume(dir, bad); }).find("no series 7"), std::string::npos);
    bad.series = "1.2.3.4";
    EXPECT_NE(error_of([&] { load_volume(dir, bad); }).find("no series with UID"), std::string::npos);
}

TEST(Dicom, LocalizerSeriesIsDropped) {
    TempDir tmp;
    const std::string dir = tmp / "loc";
    write_series(dir, SeriesSpec{});
    SeriesSpec loc;
    loc.nz = 1;
    loc.rot = rot_x(90); // coronal scout
    loc.image_type = "ORIGINAL/PRIMARY/LOCALIZER";
    loc.description = "scout";
    loc.pattern = "%s/LOC-%04d.dcm";
    write_series(dir, loc);
    ASSERT_EQ(dcm_files(dir).size(), 9u);
    const auto list = list_dicom_series({dir});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].description, "test series");
    const Volume v = load_volume(dir);
    EXPECT_EQ(v.dims[2], 8);
    EXPECT_TRUE(any_warning(v, "localizer")) << all_warnings(v);
}

TEST(Dicom, DifferentlyOrientedImagesInOneSeriesAreSplitOff) {
    TempDir tmp;
    const std::string dir = tmp / "mix";
    write_series(dir, SeriesSpec{});
    const auto hs = sorted_headers(dir);
    // A scout with the main series' UID but sagittal orientation, not tagged LOCALIZER.
    rewrite(hs[0].file, dir + "/scout.dcm", [&](vtkDICOMMetaData* md) {
        set_ds(md, DC::ImageOrientationPatient, {0, 1, 0, 0, 0, -1});
        md->Set(DC::SOPInstanceUID, std::string("1.2.826.0.1.3680043.2.1125.99.1"));
    });
    const auto list = list_dicom_series({dir});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].files, 8u);
    EXPECT_EQ(list[0].uid, hs[0].series_uid);
    const Volume v = load_volume(dir);
    EXPECT_EQ(v.dims[2], 8);
    EXPECT_TRUE(any_warning(v, "localizer/scout")) << all_warnings(v);
}

TEST(Dicom, DuplicateFileIsReadOnceButConflictingImagesAreAnError) {
    TempDir tmp;
    const std::string dir = tmp / "dup";
    write_series(dir, SeriesSpec{});
    const auto hs = sorted_headers(dir);
    fs::create_directories(dir + "/copy");
    fs::copy_file(hs[2].file, dir + "/copy/same.dcm");
    const Volume v = load_volume(dir);
    EXPECT_EQ(v.dims[2], 8);
    EXPECT_TRUE(any_warning(v, "duplicate")) << all_warnings(v);

    rewrite(hs[2].file, dir + "/copy/other.dcm",
            [&](vtkDICOMMetaData* md) { md->Set(DC::SOPInstanceUID, std::string("1.2.826.0.1.3680043.2.1125.99.2")); });
    const std::string msg = error_of([&] { load_volume(dir); });
    EXPECT_NE(msg.find("same position"), std::string::npos) << msg;
}

TEST(Dicom, RealSiemensMrScoutFolder) {
    // Three axial MR slices of one series "AX SCOUT" (ImageType ORIGINAL\PRIMARY\M\DIS2D,
    // same orientation, 12 mm apart) plus LICENSE.txt and CITATION.txt. They are
    // parallel and evenly spaced, so the user gets the 3-slice volume (the only
    // series in the folder), told that it looks like a scout.
    const std::string dir = test::data("dicom-mr-forearm");
    const auto list = list_dicom_series({dir});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].files, 3u);
    EXPECT_EQ(list[0].modality, "MR");
    EXPECT_EQ(list[0].description, "AX SCOUT");
    const Volume v = load_volume(dir);
    ASSERT_EQ(v.dims[0], 512);
    ASSERT_EQ(v.dims[1], 512);
    ASSERT_EQ(v.dims[2], 3);
    EXPECT_EQ(v.type, VoxelType::U16);
    EXPECT_EQ(v.meta.modality, "MR");
    EXPECT_EQ(v.meta.patient_id, "C3L-02846");
    std::vector<Header> hs;
    for (const char* f : {"1-1.dcm", "1-2.dcm", "1-3.dcm"}) hs.push_back(header(dir + "/" + f));
    std::sort(hs.begin(), hs.end(), [](const Header& a, const Header& b) { return a.ipp.z < b.ipp.z; });
    expect_affine_mm(v.index_to_lps, expected_affine(hs, 2));
    EXPECT_NEAR(v.spacing().z, 12.0, kMm);
    EXPECT_TRUE(any_warning(v, "scout")) << all_warnings(v);
    // Voxels against the raw pixel data of the middle file.
    const auto px = raw_pixels(hs[1]);
    for (int j = 0; j < 512; j += 37)
        for (int i = 0; i < 512; i += 41)
            ASSERT_EQ(v.value(i, j, 1), double(static_cast<std::uint16_t>(px[size_t(j * 512 + i)])));
}

TEST(Dicom, BadInputGivesClearErrors) {
    TempDir tmp;
    EXPECT_NE(error_of([&] { load_volume(tmp / "nothing-here"); }).find("no such file"), std::string::npos);

    fs::create_directories(tmp / "empty");
    EXPECT_NE(error_of([&] { read_dicom({tmp / "empty"}, {}); }).find("empty"), std::string::npos);

    fs::create_directories(tmp / "text");
    std::ofstream(tmp / "text/LICENSE.txt") << "not DICOM at all\n";
    std::ofstream(tmp / "text/data.bin") << std::string(300, '\x01');
    const std::string none = error_of([&] { load_volume(tmp / "text"); });
    EXPECT_NE(none.find("no DICOM images"), std::string::npos) << none;
    EXPECT_NE(none.find(tmp / "text"), std::string::npos) << none;

    write_series(tmp / "w", SeriesSpec{});
    const auto files = dcm_files(tmp / "w");
    fs::create_directories(tmp / "trunc");
    for (auto& f : files) fs::copy_file(f, tmp / ("trunc/" + fs::path(f).filename().string()));
    const std::string cut = tmp / ("trunc/" + fs::path(files[4]).filename().string());
    fs::resize_file(cut, fs::file_size(cut) / 2);
    // The file named: an error. In a folder: skipped, named in the warnings,
    // and the series loads from the other files.
    const std::string t = error_of([&] { load_volume(cut); });
    EXPECT_NE(t.find("truncated"), std::string::npos) << t;
    EXPECT_NE(t.find(cut), std::string::npos) << t;
    const Volume v = load_volume(tmp / "trunc");
    EXPECT_TRUE(any_warning(v, "skipped 1 unreadable DICOM file(s): " + cut + ": malformed DICOM at byte "))
        << all_warnings(v);
    EXPECT_TRUE(any_warning(v, "truncated")) << all_warnings(v);
    // Only slightly short: the header is intact, the pixels are not.
    fs::copy_file(files[4], cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, fs::file_size(cut) - 10);
    const std::string t2 = error_of([&] { load_volume(cut); });
    EXPECT_NE(t2.find("truncated"), std::string::npos) << t2;
    // Every file unreadable: the error says why.
    fs::create_directories(tmp / "allbad");
    fs::copy_file(cut, tmp / "allbad/a.dcm");
    const std::string t3 = error_of([&] { load_volume(tmp / "allbad"); });
    EXPECT_NE(t3.find("no DICOM images found"), std::string::npos) << t3;
    EXPECT_NE(t3.find("skipped 1 unreadable DICOM file(s)"), std::string::npos) << t3;
}

TEST(Dicom, AFileThatAbortedTheReaderIsAnErrorAloneAndSkippedInAFolder) {
    // The 443-byte file that made vtk-dicom assert (issue 42).
    const std::string crash =
        std::string(ISOSCOPE_SOURCE_DIR) +
        "/tests/fuzz/regressions/dicom/crash-dicom-crash-314510707ba2abecdd6ccdea964749af198ea78c";
    TempDir tmp;
    const std::string alone = tmp / "bad.dcm";
    fs::copy_file(crash, alone);
    const std::string e = error_of([&] { load_volume(alone); });
    EXPECT_NE(e.find(alone + ": malformed DICOM at byte "), std::string::npos) << e;
    // The real series with the bad file among its files.
    fs::create_directories(tmp / "series");
    for (int i = 1; i <= 3; ++i) {
        const std::string name = "1-" + std::to_string(i) + ".dcm";
        fs::copy_file(iso::test::data("dicom-mr-forearm/" + name), tmp / ("series/" + name));
    }
    fs::copy_file(crash, tmp / "series/1-2b.dcm");
    const Volume v = load_volume(tmp / "series");
    EXPECT_EQ(v.dims[2], 3);
    EXPECT_TRUE(any_warning(v, "skipped 1 unreadable DICOM file(s): " + (tmp / "series/1-2b.dcm"))) << all_warnings(v);
}

TEST(Dicom, CorruptCompressedPixelDataIsSkippedInAFolderAndAnErrorAlone) {
    // Header says JPEG baseline, the pixel data are raw bytes (not the
    // fragments a compressed transfer syntax needs): the structure walk
    // refuses it, naming the offset. Alone: an error naming the file. In its
    // series' folder: skipped, named in the warnings, the slice filled in.
    TempDir tmp;
    write_series(tmp / "w", SeriesSpec{});
    const auto hs = sorted_headers(tmp / "w");
    fs::create_directories(tmp / "jpeg");
    for (size_t k = 0; k < hs.size(); ++k) {
        const std::string dst = tmp / ("jpeg/" + fs::path(hs[k].file).filename().string());
        if (k == 2)
            rewrite(
                hs[k].file, dst, [](vtkDICOMMetaData*) {}, "1.2.840.10008.1.2.4.50");
        else
            fs::copy_file(hs[k].file, dst);
    }
    const std::string bad = tmp / ("jpeg/" + fs::path(hs[2].file).filename().string());
    const std::string e = error_of([&] { load_volume(bad); });
    EXPECT_NE(e.find(bad + ": malformed DICOM at byte "), std::string::npos) << e;
    EXPECT_NE(e.find("expected a fragment item"), std::string::npos) << e;
    const Volume v = load_volume(tmp / "jpeg");
    EXPECT_EQ(v.dims[2], int(hs.size()));
    EXPECT_TRUE(any_warning(v, "skipped 1 unreadable DICOM file(s): " + bad)) << all_warnings(v);
    EXPECT_TRUE(any_warning(v, "missing slice")) << all_warnings(v);
}

TEST(Dicom, ADecoderThatAbortsIsAnErrorNotACrash) {
    // A JPEG-LS file whose pixel data element was renamed (7FE0,4910) by the
    // fuzzer: GDCM, which decodes compressed files, asserted on it and ended
    // the process. Compressed files are decoded in a child process: its
    // abort is an error naming the file, with what it said.
    const std::string f = std::string(ISOSCOPE_SOURCE_DIR) +
                          "/tests/fuzz/regressions/dicom/crash-dicom-crash-f4d43161c4de314a563f1e1049f8c2f792d2f0f4";
    TempDir tmp;
    const std::string copy = tmp / "a.dcm";
    fs::copy_file(f, copy);
    const std::string e = error_of([&] { load_volume(copy); });
    EXPECT_NE(e.find(copy + ": the DICOM decoder failed on this file"), std::string::npos) << e;
    EXPECT_NE(e.find("Assertion"), std::string::npos) << e;
}

TEST(Dicom, CompressedSeriesDecodeToTheSameVoxelsAsUncompressed) {
    // The real header in every transfer syntax (tests/fuzz/corpus/dicom):
    // lossless ones decoded (in the child, for the compressed) to the same
    // voxels, and GDCM's chatter as at most one warning per message.
    const std::string dir = std::string(ISOSCOPE_SOURCE_DIR) + "/tests/fuzz/corpus/dicom/";
    const Volume ref = load_volume(dir + "mr32.dcm");
    for (const char* name : {"mr32-implicit.dcm", "mr32-bigendian.dcm", "mr32-jpeg.dcm", "mr32-j2k.dcm",
                             "mr32-jpegls.dcm", "mr32-rle.dcm"}) {
        SCOPED_TRACE(name);
        const Volume v = load_volume(dir + name);
        ASSERT_EQ(v.dims, ref.dims);
        for (int j = 0; j < 32; ++j)
            for (int i = 0; i < 32; ++i) ASSERT_EQ(v.value(i, j, 0), ref.value(i, j, 0)) << i << "," << j;
        std::size_t gdcm = 0;
        for (const auto& w : v.meta.warnings) gdcm += w.find("GDCM") != std::string::npos;
        EXPECT_LE(gdcm, 1u) << all_warnings(v);
    }
}

TEST(Dicom, BadGeometryGivesClearErrors) {
    TempDir tmp;
    write_series(tmp / "w", SeriesSpec{});
    const auto hs = sorted_headers(tmp / "w");
    auto with_edit = [&](const std::string& name, const std::function<void(vtkDICOMMetaData*)>& edit) {
        const std::string dir = tmp / name;
        fs::create_directories(dir);
        for (size_t k = 0; k < hs.size(); ++k) {
            const std::string dst = dir + "/" + fs::path(hs[k].file).filename().string();
            if (k == 4)
                rewrite(hs[k].file, dst, edit);
            else
                fs::copy_file(hs[k].file, dst);
        }
        return error_of([&] { load_volume(dir); });
    };
    std::string e = with_edit("iop", [](vtkDICOMMetaData* md) {
        set_ds(md, DC::ImageOrientationPatient, {1, 0, 0, 0.2, 1, 0});
    });
    // Another IOP splits the series first; load the split part by UID suffix to hit the check.
    EXPECT_NE(e.find("holds 2 series"), std::string::npos) << e;
    LoadOptions opt;
    opt.series = hs[0].series_uid + ".2";
    e = error_of([&] { load_volume(tmp / "iop", opt); });
    EXPECT_NE(e.find("not orthonormal"), std::string::npos) << e;

    e = with_edit("ps", [](vtkDICOMMetaData* md) { set_ds(md, DC::PixelSpacing, {0, 0}); });
    opt.series = "1";
    if (e.find("holds") != std::string::npos) e = error_of([&] { load_volume(tmp / "ps", opt); });
    EXPECT_NE(e.find("PixelSpacing is zero"), std::string::npos) << e;

    e = with_edit("nan", [](vtkDICOMMetaData* md) {
        md->Set(DC::ImagePositionPatient, vtkDICOMValue(vtkDICOMVR::DS, std::string("nan\\0\\0")));
    });
    EXPECT_NE(e.find("not finite"), std::string::npos) << e;
}

TEST(Dicom, ColourImagesAreRefused) {
    TempDir tmp;
    vtkNew<vtkImageData> img;
    img->SetDimensions(8, 6, 3);
    img->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
    std::fill_n(static_cast<unsigned char*>(img->GetScalarPointer()), 8 * 6 * 3 * 3, 100);
    vtkNew<vtkDICOMWriter> w;
    w->SetInputData(img);
    const std::string dir = tmp / "rgb";
    fs::create_directories(dir);
    w->SetFilePrefix(dir.c_str());
    w->SetFilePattern("%s/RGB-%04d.dcm");
    w->Write();
    ASSERT_EQ(w->GetErrorCode(), 0u);
    const std::string e = error_of([&] { load_volume(dir); });
    EXPECT_NE(e.find("colour"), std::string::npos) << e;
}

TEST(Dicom, MultiFrameFileIsListedAndRefusedClearly) {
    TempDir tmp;
    vtkNew<vtkImageData> img;
    img->SetDimensions(8, 6, 4);
    img->AllocateScalars(VTK_SHORT, 1);
    std::fill_n(static_cast<short*>(img->GetScalarPointer()), 8 * 6 * 4, short(7));
    vtkNew<vtkDICOMWriter> w;
    vtkNew<vtkDICOMSCGenerator> gen;
    gen->MultiFrameOn();
    w->SetGenerator(gen);
    w->SetInputData(img);
    const std::string file = tmp / "mf.dcm";
    w->SetFileName(file.c_str());
    w->SetFileDimensionality(3); // all slices as frames of one file
    w->Write();
    ASSERT_EQ(w->GetErrorCode(), 0u);
    const auto list = list_dicom_series({file});
    ASSERT_EQ(list.size(), 1u);
    EXPECT_EQ(list[0].dims[2], 4);
    // The chooser says so before a load is tried.
    EXPECT_TRUE(any_listed_warning(list[0], "cannot be loaded")) << list[0].warnings.size();
    EXPECT_TRUE(any_listed_warning(list[0], "multi-frame"));
    const std::string e = error_of([&] { load_dicom_files({file}); });
    EXPECT_NE(e.find("multi-frame"), std::string::npos) << e;
}

TEST(Dicom, ExplicitFileListAndProgressAndCancel) {
    TempDir tmp;
    write_series(tmp / "w", SeriesSpec{});
    auto files = dcm_files(tmp / "w");
    std::vector<double> seen;
    LoadOptions opt;
    opt.progress = [&](double f, std::string_view stage) {
        EXPECT_EQ(stage, "reading DICOM");
        seen.push_back(f);
        return true;
    };
    std::reverse(files.begin(), files.end());
    const Volume v = load_dicom_files(files, opt);
    EXPECT_EQ(v.dims[2], 8);
    EXPECT_EQ(v.value(2, 3, 6), pattern(2, 3, 6) - 1024);
    ASSERT_GE(seen.size(), 3u);
    EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);

    int calls = 0;
    opt.progress = [&](double, std::string_view) { return ++calls < 3; };
    EXPECT_THROW(load_dicom_files(files, opt), Cancelled);
}

namespace {
nlohmann::json cli_json(const std::string& args, int* code = nullptr) {
    const auto r = test::run_command(test::cli() + " info " + args + " --json");
    if (code) *code = r.exit_code;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}
void expect_json_affine(const nlohmann::json& m, const glm::dmat4& a) {
    ASSERT_EQ(m.size(), 4u);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(m[size_t(r)][size_t(c)].get<double>(), a[c][r], kMm) << r << c;
}
} // namespace

TEST(Dicom, CliInfoJsonAndSeriesChoice) {
    TempDir tmp;
    const std::string dir = tmp / "cli";
    SeriesSpec a;
    a.rot = rot_z(30) * rot_x(30);
    a.description = "oblique";
    a.series_number = 1;
    a.pattern = "%s/A-%04d.dcm";
    write_series(dir + "/one", a);
    int code = -1;
    const auto j = cli_json("'" + dir + "/one'", &code);
    ASSERT_EQ(code, 0);
    EXPECT_EQ(j["format"], "DICOM");
    EXPECT_EQ(j["dims"], nlohmann::json({16, 12, 8}));
    EXPECT_EQ(j["type"], "int16");
    EXPECT_EQ(j["selected_series"], 0);
    expect_json_affine(j["index_to_lps"], expected_affine(sorted_headers(dir + "/one"), 7));

    SeriesSpec b;
    b.description = "axial";
    b.series_number = 2;
    b.nz = 5;
    b.pattern = "%s/B-%04d.dcm";
    write_series(dir + "/one", b);
    const auto r = test::run_command(test::cli() + " info '" + dir + "/one' --json", true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("--series"), std::string::npos) << r.out;

    const auto j1 = cli_json("'" + dir + "/one' --series 1", &code);
    ASSERT_EQ(code, 0);
    EXPECT_EQ(j1["selected_series"], 1);
    ASSERT_EQ(j1["series"].size(), 2u);
    const std::string desc = j1["metadata"]["series_description"];
    EXPECT_EQ(desc, j1["series"][1]["description"].get<std::string>());
    const int nz = desc == "axial" ? 5 : 8;
    EXPECT_EQ(j1["dims"][2], nz);
    // Each listed series carries the warnings the listing found (the series chooser's column).
    const auto listed = list_dicom_series({dir + "/one"});
    ASSERT_EQ(listed.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i)
        EXPECT_EQ(j1["series"][i]["warnings"].get<std::vector<std::string>>(), listed[i].warnings) << i;
}

// The series offered first: the most slices among those fit for 3D (a scout
// with more slices is passed over); one DICOM file names its folder and series.
TEST(Dicom, SuggestedSeriesAndTheSeriesOfOneFile) {
    TempDir tmp;
    const std::string dir = tmp / "study";
    SeriesSpec scout;
    scout.description = "scout";
    scout.series_number = 1;
    scout.nz = 12;
    scout.spacing = {0.7, 0.8, 20.0};
    scout.pattern = "%s/S-%04d.dcm";
    SeriesSpec axial;
    axial.description = "axial";
    axial.series_number = 2;
    axial.pattern = "%s/A-%04d.dcm";
    SeriesSpec thin;
    thin.description = "thin";
    thin.series_number = 3;
    thin.nz = 5;
    thin.pattern = "%s/T-%04d.dcm";
    write_series(dir, scout);
    write_series(dir, axial);
    write_series(dir, thin);
    const auto list = core::list_series(dir);
    ASSERT_EQ(list.size(), 3u);
    const auto index_of = [&](const std::string& d) {
        for (std::size_t i = 0; i < list.size(); ++i)
            if (list[i].description == d) return int(i);
        return -1;
    };
    const int s = index_of("scout"), a = index_of("axial"), t = index_of("thin");
    ASSERT_TRUE(s >= 0 && a >= 0 && t >= 0);
    EXPECT_FALSE(list[std::size_t(s)].for_3d);
    EXPECT_TRUE(list[std::size_t(a)].for_3d);
    EXPECT_TRUE(list[std::size_t(t)].for_3d);
    EXPECT_EQ(core::suggested_series(list), a) << "the 12-slice scout is passed over";
    // None fit: the most slices of all; none at all: -1.
    auto unfit = list;
    for (auto& x : unfit) x.for_3d = false;
    EXPECT_EQ(core::suggested_series(unfit), s);
    EXPECT_EQ(core::suggested_series({}), -1);

    // ---- one file of the axial series: its folder and UID, which load the whole series
    const auto of = core::dicom_series_of_file(dir + "/A-0002.dcm");
    ASSERT_TRUE(of.has_value());
    EXPECT_EQ(fs::path(of->folder), fs::absolute(dir));
    EXPECT_EQ(of->uid, list[std::size_t(a)].uid);
    LoadOptions opt;
    opt.series = of->uid;
    EXPECT_EQ(load_volume(of->folder, opt).dims[2], 8);
    // Not DICOM by its name, a folder, missing, or unreadable: none (loading says why).
    EXPECT_FALSE(core::dicom_series_of_file(test::data("headsq.nhdr")).has_value());
    EXPECT_FALSE(core::dicom_series_of_file(dir).has_value());
    EXPECT_FALSE(core::dicom_series_of_file(dir + "/missing.dcm").has_value());
    std::ofstream(tmp / "broken.dcm") << "not DICOM";
    EXPECT_FALSE(core::dicom_series_of_file(tmp / "broken.dcm").has_value());
}
