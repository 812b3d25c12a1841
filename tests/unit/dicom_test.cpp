// DICOM series: generated with vtkDICOMWriter (axial CT with rescale,
// oblique, a missing slice, gantry tilt, two series, a localizer), the real
// MR files in datasets/, and bad input. Geometry is checked against an
// independent computation from each written file's header fields.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>
#include <vtkDICOMCTGenerator.h>
#include <vtkDICOMCompiler.h>
#include <vtkDICOMMRGenerator.h>
#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMReader.h>
#include <vtkDICOMValue.h>
#include <vtkDICOMWriter.h>
#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkShortArray.h>
#include <vtkStringArray.h>

#include "io/volume_io.hpp"
#include "test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

constexpr int NX = 16, NY = 12;

// Sample value of voxel (i, j, k) in HU: checks voxel order and rescale.
std::int16_t pattern(int i, int j, int k) { return std::int16_t(-1000 + i + 20 * j + 300 * k); }

// Writes an n-slice CT series into `dir` with file names PREFIX_NNNN.dcm.
// `matrix`: patient matrix (rotation columns + origin), slices along its third column with `dz` mm steps.
void write_series(const std::string& dir, const std::string& prefix, int n, const glm::dmat4& matrix, double dz,
                  const char* image_type = "ORIGINAL\\PRIMARY\\AXIAL", const char* description = "test series") {
    vtkNew<vtkImageData> img;
    img->SetDimensions(NX, NY, n);
    img->SetSpacing(0.75, 0.6, dz);
    vtkNew<vtkShortArray> a;
    a->SetNumberOfTuples(NX * NY * n);
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < NY; ++j)
            for (int i = 0; i < NX; ++i) a->SetValue(i + NX * (j + NY * k), pattern(i, j, k));
    img->GetPointData()->SetScalars(a);
    vtkNew<vtkMatrix4x4> m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m->SetElement(r, c, matrix[c][r]);
    vtkNew<vtkDICOMCTGenerator> gen;
    vtkNew<vtkDICOMWriter> w;
    w->SetInputData(img);
    w->SetGenerator(gen);
    w->SetPatientMatrix(m);
    w->SetFilePrefix(dir.c_str());
    w->SetFilePattern(("%s/" + prefix + "_%04d.dcm").c_str());
    w->SetSeriesDescription(description);
    w->SetImageType(image_type);
    w->SetMemoryRowOrderToFileNative();
    w->SetFileSliceOrderToSame();
    w->Write();
    ASSERT_EQ(w->GetErrorCode(), 0u);
}

struct Header {
    glm::dvec3 ipp, row, col;
    double row_spacing = 0, col_spacing = 0;
    std::string series_uid;
};

Header read_header(const std::string& file) {
    vtkNew<vtkDICOMMetaData> meta;
    vtkNew<vtkDICOMParser> p;
    p->SetMetaData(meta);
    p->SetFileName(file.c_str());
    p->Update();
    Header h;
    double v[6];
    meta->Get(DC::ImagePositionPatient).GetValues(v, 3);
    h.ipp = {v[0], v[1], v[2]};
    meta->Get(DC::ImageOrientationPatient).GetValues(v, 6);
    h.row = {v[0], v[1], v[2]};
    h.col = {v[3], v[4], v[5]};
    meta->Get(DC::PixelSpacing).GetValues(v, 2);
    h.row_spacing = v[0];
    h.col_spacing = v[1];
    h.series_uid = meta->Get(DC::SeriesInstanceUID).AsString();
    return h;
}

// Rewrites a file with changed header attributes, keeping its pixels.
void rewrite(const std::string& file, const std::function<void(vtkDICOMMetaData*)>& change) {
    vtkNew<vtkDICOMReader> r;
    r->SetFileName(file.c_str());
    r->AutoRescaleOff();
    r->SetMemoryRowOrderToFileNative();
    r->Update();
    vtkDICOMMetaData* meta = r->GetMetaData();
    change(meta);
    vtkDataArray* px = r->GetOutput()->GetPointData()->GetScalars();
    const std::string tmp = file + ".new";
    vtkNew<vtkDICOMCompiler> c;
    c->SetFileName(tmp.c_str());
    c->SetMetaData(meta);
    // The compiler makes new UIDs unless it is given them.
    const std::string sop = meta->Get(DC::SOPInstanceUID).AsString(), series = meta->Get(DC::SeriesInstanceUID).AsString(),
                      study = meta->Get(DC::StudyInstanceUID).AsString();
    c->SetSOPInstanceUID(sop.c_str());
    c->SetSeriesInstanceUID(series.c_str());
    c->SetStudyInstanceUID(study.c_str());
    c->KeepOriginalPixelDataVROn();
    c->WriteHeader();
    c->WritePixelData(static_cast<const unsigned char*>(px->GetVoidPointer(0)), px->GetNumberOfValues() * px->GetDataTypeSize());
    c->Close();
    fs::rename(tmp, file);
}

std::vector<std::string> files_with_prefix(const std::string& dir, const std::string& prefix) {
    std::vector<std::string> f;
    for (auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().rfind(prefix, 0) == 0) f.push_back(e.path().string());
    std::sort(f.begin(), f.end());
    return f;
}

// The index -> LPS matrix DICOM defines, computed from the first (lowest)
// slice's header and the step to the last one.
glm::dmat4 expected_affine(const Header& first, const Header& last, int nz) {
    glm::dmat4 m(1.0);
    m[0] = glm::dvec4(first.row * first.col_spacing, 0);
    m[1] = glm::dvec4(first.col * first.row_spacing, 0);
    m[2] = glm::dvec4((last.ipp - first.ipp) / double(nz - 1), 0);
    m[3] = glm::dvec4(first.ipp, 1);
    return m;
}

void expect_affine_near(const glm::dmat4& a, const glm::dmat4& b, double tol) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tol) << "[col " << c << "][row " << r << "]";
}

bool has_warning(const Volume& v, const std::string& s) {
    for (const auto& w : v.meta.warnings)
        if (w.find(s) != std::string::npos) return true;
    return false;
}

glm::dmat4 oblique_matrix() {
    glm::dmat4 r = glm::rotate(glm::dmat4(1.0), glm::radians(30.0), glm::normalize(glm::dvec3(1, 0, 0)));
    r = glm::rotate(r, glm::radians(20.0), glm::dvec3(0, 1, 0));
    r[3] = glm::dvec4(-120.5, 33.25, 410.0, 1.0);
    return r;
}

} // namespace

TEST(Dicom, AxialCtSeriesWithRescale) {
    TempDir dir;
    write_series(dir.path().string(), "ct", 6, glm::translate(glm::dmat4(1.0), glm::dvec3(-50, -40, 100)), 2.5);
    const Volume v = load_volume(dir.path().string());
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{NX, NY, 6}));
    EXPECT_EQ(v.meta.modality, "CT");
    ASSERT_EQ(v.type, VoxelType::I16);
    for (int k : {0, 3, 5})
        for (int j : {0, 7, NY - 1})
            for (int i : {0, 5, NX - 1}) EXPECT_EQ(v.value(i, j, k), pattern(i, j, k)) << i << "," << j << "," << k;
    const auto files = files_with_prefix(dir.path().string(), "ct");
    auto h0 = read_header(files.front()), h1 = read_header(files.back());
    if (h0.ipp.z > h1.ipp.z) std::swap(h0, h1);
    expect_affine_near(v.index_to_lps, expected_affine(h0, h1, 6), 1e-4);
    EXPECT_NEAR(v.spacing().z, 2.5, 1e-6);
    EXPECT_TRUE(v.meta.warnings.empty()) << v.meta.warnings.front();
}

TEST(Dicom, ObliqueSeriesAndShuffledNames) {
    TempDir dir;
    write_series(dir.path().string(), "ob", 5, oblique_matrix(), 3.0);
    // Shuffle file names so that name order is not slice order.
    auto files = files_with_prefix(dir.path().string(), "ob");
    const std::vector<std::string> names = {"z.dcm", "a.dcm", "m.dcm", "c.dcm", "b.dcm"};
    for (std::size_t i = 0; i < files.size(); ++i) fs::rename(files[i], dir / names[i]);
    const Volume v = load_volume(dir.path().string());
    ASSERT_EQ(v.dims[2], 5);
    // The lowest slice along the normal is the one written first ("z.dcm").
    const Header h0 = read_header(dir / "z.dcm"), h4 = read_header(dir / "b.dcm");
    expect_affine_near(v.index_to_lps, expected_affine(h0, h4, 5), 1e-4);
    // Axes are rotated, orthogonal, of the right length.
    const glm::dmat3 lin(v.index_to_lps);
    EXPECT_NEAR(glm::dot(lin[0], lin[1]), 0.0, 1e-6);
    EXPECT_NEAR(glm::dot(lin[0], lin[2]), 0.0, 1e-4);
    EXPECT_NEAR(glm::length(lin[0]), 0.75, 1e-6);
    EXPECT_NEAR(glm::length(lin[1]), 0.6, 1e-6);
    EXPECT_GT(std::abs(lin[0].y) + std::abs(lin[0].z), 0.1) << "rows not rotated";
    for (int k = 0; k < 5; ++k) EXPECT_EQ(v.value(3, 4, k), pattern(3, 4, k));
}

TEST(Dicom, MissingSliceIsReportedAndFilled) {
    TempDir dir;
    write_series(dir.path().string(), "gap", 7, glm::dmat4(1.0), 2.0);
    auto files = files_with_prefix(dir.path().string(), "gap");
    // Remove the slice at z = 6 mm (the fourth from the bottom).
    std::string removed;
    for (auto& f : files)
        if (std::abs(read_header(f).ipp.z - 6.0) < 1e-6) removed = f;
    ASSERT_FALSE(removed.empty());
    fs::remove(removed);
    const Volume v = load_volume(dir.path().string());
    EXPECT_EQ(v.dims[2], 7) << "the grid keeps the missing slice";
    EXPECT_TRUE(has_warning(v, "missing slices")) << (v.meta.warnings.empty() ? "" : v.meta.warnings[0]);
    EXPECT_NEAR(v.spacing().z, 2.0, 1e-6);
    // The filled slice is the mean of its neighbours (the pattern is linear in k).
    for (int j : {0, 5}) EXPECT_EQ(v.value(2, j, 3), pattern(2, j, 3));
    EXPECT_EQ(v.value(2, 2, 4), pattern(2, 2, 4));
    EXPECT_NEAR(v.index_to_world({0, 0, 6}).z, 12.0, 1e-6);
}

TEST(Dicom, GantryTiltIsReportedAndKeptSheared) {
    TempDir dir;
    write_series(dir.path().string(), "tilt", 5, glm::dmat4(1.0), 2.0);
    const auto files = files_with_prefix(dir.path().string(), "tilt");
    // Shear: each slice moves 0.35 mm along y (posterior) per mm along z: 19.3 degrees.
    std::string uid;
    for (const auto& f : files) {
        const Header h = read_header(f);
        rewrite(f, [&](vtkDICOMMetaData* m) {
            const double ipp[3] = {h.ipp.x, h.ipp.y + 0.35 * h.ipp.z, h.ipp.z};
            m->Set(DC::ImagePositionPatient, vtkDICOMValue(vtkDICOMVR::DS, ipp, 3));
        });
    }
    const Volume v = load_volume(dir.path().string());
    ASSERT_EQ(v.dims[2], 5);
    bool found = false;
    for (const auto& w : v.meta.warnings)
        if (w.find("gantry tilt of 19.3") != std::string::npos) found = true;
    EXPECT_TRUE(found) << (v.meta.warnings.empty() ? "(no warning)" : v.meta.warnings[0]);
    // Every slice's first voxel sits at that file's IPP.
    for (const auto& f : files) {
        const Header h = read_header(f);
        const int k = int(std::lround(h.ipp.z / 2.0));
        const glm::dvec3 w = v.index_to_world({0, 0, double(k)});
        EXPECT_NEAR(glm::length(w - h.ipp), 0.0, 1e-4) << f;
    }
}

TEST(Dicom, TwoSeriesAreListedNotMerged) {
    TempDir dir;
    write_series(dir.path().string(), "a", 4, glm::dmat4(1.0), 1.0, "ORIGINAL\\PRIMARY\\AXIAL", "first");
    write_series(dir.path().string(), "b", 6, glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, 50)), 2.0,
                 "ORIGINAL\\PRIMARY\\AXIAL", "second");
    const auto series = list_dicom_series({dir.path().string()});
    ASSERT_EQ(series.size(), 2u);
    try {
        load_volume(dir.path().string());
        FAIL() << "loaded a folder of two series without a choice";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--series"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("first"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("second"), std::string::npos) << e.what();
    }
    for (std::size_t i = 0; i < 2; ++i) {
        const Volume by_index = load_volume(dir.path().string(), {.series = std::to_string(i)});
        const Volume by_uid = load_volume(dir.path().string(), {.series = series[i].uid});
        EXPECT_EQ(by_index.dims[2], series[i].dims[2]);
        EXPECT_EQ(by_uid.dims, by_index.dims);
        EXPECT_EQ(by_uid.meta.selected_series, int(i));
        EXPECT_EQ(by_index.meta.series.size(), 2u);
    }
    EXPECT_THROW(load_volume(dir.path().string(), {.series = "7"}), Error);
    EXPECT_THROW(load_volume(dir.path().string(), {.series = "1.2.3.no.such.uid"}), Error);

    // The CLI: --series and the JSON affine.
    const auto res = test::run_command(test::cli() + " info " + dir.path().string() + " --series 1 --json");
    ASSERT_EQ(res.exit_code, 0) << res.out;
    const auto j = nlohmann::json::parse(res.out);
    EXPECT_EQ(j["series"].size(), 2u);
    EXPECT_EQ(j["selected_series"], 1);
    const Volume v1 = load_volume(dir.path().string(), {.series = "1"});
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(j["index_to_lps"][r][c].get<double>(), v1.index_to_lps[c][r], 1e-4);
    const auto fail = test::run_command(test::cli() + " info " + dir.path().string(), true);
    EXPECT_EQ(fail.exit_code, 1);
    EXPECT_NE(fail.out.find("holds 2 series"), std::string::npos) << fail.out;
}

TEST(Dicom, LocalizerInTheSeriesIsDropped) {
    TempDir dir;
    write_series(dir.path().string(), "ax", 4, glm::dmat4(1.0), 1.5);
    glm::dmat4 sagittal(glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, -1, 0), glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 0, 0, 1));
    write_series(dir.path().string(), "loc", 1, sagittal, 1.0, "ORIGINAL\\PRIMARY\\LOCALIZER", "scout");
    const std::string uid = read_header(files_with_prefix(dir.path().string(), "ax")[0]).series_uid;
    for (const auto& f : files_with_prefix(dir.path().string(), "loc"))
        rewrite(f, [&](vtkDICOMMetaData* m) { m->Set(DC::SeriesInstanceUID, uid); });
    const Volume v = load_volume(dir.path().string());
    EXPECT_EQ(v.dims[2], 4);
    EXPECT_TRUE(has_warning(v, "localizer"));
    EXPECT_EQ(v.meta.series.size(), 1u);
}

TEST(Dicom, RealForearmMrFiles) {
    // Three parallel axial slices 12 mm apart from TCIA (CC BY 3.0, datasets/dicom-mr-forearm).
    const Volume v = load_volume(test::data("dicom-mr-forearm"));
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{512, 512, 3}));
    EXPECT_EQ(v.meta.modality, "MR");
    EXPECT_EQ(v.type, VoxelType::U16);
    const Header top = read_header(test::data("dicom-mr-forearm/1-1.dcm")), bottom = read_header(test::data("dicom-mr-forearm/1-3.dcm"));
    expect_affine_near(v.index_to_lps, expected_affine(bottom, top, 3), 1e-4);
    EXPECT_EQ(v.index_to_lps[3][2], -12.0); // the lowest slice first
    // The license files in the folder are not DICOM and are skipped quietly.
    EXPECT_TRUE(v.meta.warnings.empty());
    // An explicit file list works too.
    const Volume w = load_dicom_files({test::data("dicom-mr-forearm/1-2.dcm"), test::data("dicom-mr-forearm/1-3.dcm")});
    EXPECT_EQ(w.dims[2], 2);
}

TEST(Dicom, BadInput) {
    TempDir dir;
    fs::create_directories(dir / "empty");
    EXPECT_THROW(load_volume(dir / "empty"), Error);
    fs::create_directories(dir / "text");
    std::ofstream(dir / "text/readme.txt") << "hello";
    try {
        load_volume(dir / "text");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no DICOM files"), std::string::npos) << e.what();
    }
    EXPECT_THROW(load_volume(dir / "nope"), Error);
    // A truncated file among good ones.
    fs::create_directories(dir / "cut");
    write_series((dir / "cut"), "s", 3, glm::dmat4(1.0), 1.0);
    const auto files = files_with_prefix(dir / "cut", "s");
    fs::resize_file(files[1], fs::file_size(files[1]) / 2);
    try {
        load_volume(dir / "cut");
        FAIL() << "a series with a truncated file loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cut"), std::string::npos) << e.what();
    }
    // Cut inside the pixel data: the header parses, the pixels are short.
    fs::create_directories(dir / "short");
    write_series((dir / "short"), "s", 3, glm::dmat4(1.0), 1.0);
    const auto sf = files_with_prefix(dir / "short", "s");
    fs::resize_file(sf[2], fs::file_size(sf[2]) - 100);
    try {
        load_volume(dir / "short");
        FAIL() << "a series with short pixel data loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(fs::path(sf[2]).filename().string()), std::string::npos) << e.what();
    }
}
