// Figures to PACS: `isoscope render --dicom DIR` as a real process, the
// Secondary Capture files it writes read back with vtk-dicom (attributes and
// pixels against the PNG of the same run) and by DCMTK's dcmdump and GDCM's
// gdcmdump, as a PACS's tools would read them.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMReader.h>
#include <vtkDICOMValue.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include "io/image.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;
namespace fs = std::filesystem;

namespace {

const char* kSecondaryCapture = "1.2.840.10008.5.1.4.1.1.7";

vtkSmartPointer<vtkDICOMMetaData> header(const std::string& file) {
    auto md = vtkSmartPointer<vtkDICOMMetaData>::New();
    vtkNew<vtkDICOMParser> p;
    p->SetMetaData(md);
    p->SetFileName(file.c_str());
    p->Update();
    EXPECT_EQ(p->GetErrorCode(), 0u) << file;
    return md;
}

std::string tag_text(vtkDICOMMetaData* md, vtkDICOMTag tag) {
    std::string s = md->Get(tag).AsUTF8String();
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
    return s;
}

std::vector<std::string> dcm_files(const std::string& dir) {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".dcm") v.push_back(e.path().string());
    std::sort(v.begin(), v.end());
    return v;
}

std::string run(const std::string& args) {
    const auto r = test::run_command(test::cli() + " render " + args, true);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return r.out;
}

// The DICOM figure's RGB pixels (first row at the top) equal the PNG's.
void expect_same_pixels(const std::string& dcm, const std::string& png) {
    vtkNew<vtkDICOMReader> reader;
    reader->SetFileName(dcm.c_str());
    reader->SetMemoryRowOrderToFileNative();
    reader->Update();
    ASSERT_EQ(reader->GetErrorCode(), 0u) << dcm;
    vtkImageData* img = reader->GetOutput();
    int dims[3];
    img->GetDimensions(dims);
    auto* px = vtkUnsignedCharArray::SafeDownCast(img->GetPointData()->GetScalars());
    ASSERT_NE(px, nullptr);
    ASSERT_EQ(px->GetNumberOfComponents(), 3);
    const Image ref = load_image(png);
    ASSERT_EQ(dims[0], ref.width);
    ASSERT_EQ(dims[1], ref.height);
    std::size_t differ = 0;
    for (int i = 0; i < ref.width * ref.height; ++i)
        for (int c = 0; c < 3; ++c)
            differ += px->GetValue(vtkIdType(i) * 3 + c) != ref.bytes[std::size_t(i) * std::size_t(ref.channels) + c];
    EXPECT_EQ(differ, 0u) << dcm << " against " << png;
}

// DCMTK's and GDCM's dumps of the file name `needle` (both ship with
// ./setup.sh --tests: dcmtk, libgdcm-tools).
void expect_tools_read(const std::string& file, const std::string& needle) {
    for (const std::string tool : {"dcmdump", "gdcmdump"}) {
        const auto r = test::run_command(tool + " " + file, true);
        EXPECT_EQ(r.exit_code, 0) << tool << " (./setup.sh --tests installs it): " << r.out;
        EXPECT_NE(r.out.find(needle), std::string::npos) << tool << ": " << r.out;
        EXPECT_EQ(r.out.find("E: "), std::string::npos) << tool << " reported an error: " << r.out;
    }
}

} // namespace

TEST(DicomExport, AFigureOfTheBundledMrJoinsItsStudyInOneSeries) {
    TempDir dir;
    const std::string src = test::data("dicom-mr-forearm");
    const auto source = header(src + "/1-1.dcm");
    const std::string pacs = dir / "pacs";
    const std::string common = src + " --size 160x120 --ao off --no-aa --dicom " + pacs;
    const std::string out1 = run(common + " --iso 200 -o " + (dir / "a.png"));
    EXPECT_NE(out1.find("in the source's study"), std::string::npos) << out1;
    run(common + " --iso 300 -o " + (dir / "b.png"));
    const auto files = dcm_files(pacs);
    ASSERT_EQ(files.size(), 2u);
    std::vector<vtkSmartPointer<vtkDICOMMetaData>> md;
    for (const auto& f : files) md.push_back(header(f));
    for (int i = 0; i < 2; ++i) {
        SCOPED_TRACE(files[std::size_t(i)]);
        vtkDICOMMetaData* m = md[std::size_t(i)];
        EXPECT_EQ(tag_text(m, DC::SOPClassUID), kSecondaryCapture);
        EXPECT_EQ(tag_text(m, DC::StudyInstanceUID), tag_text(source, DC::StudyInstanceUID));
        for (auto tag : {DC::PatientName, DC::PatientID, DC::PatientSex, DC::StudyDate, DC::StudyDescription})
            EXPECT_EQ(tag_text(m, tag), tag_text(source, tag)) << vtkDICOMTag(tag);
        EXPECT_NE(tag_text(m, DC::SeriesInstanceUID), tag_text(source, DC::SeriesInstanceUID));
        EXPECT_EQ(tag_text(m, DC::SeriesInstanceUID), tag_text(md[0], DC::SeriesInstanceUID));
        EXPECT_EQ(tag_text(m, DC::SeriesDescription), "isoscope 3D");
        EXPECT_EQ(m->Get(DC::InstanceNumber).AsInt(), i + 1);
        EXPECT_EQ(tag_text(m, DC::BurnedInAnnotation), "YES");
        EXPECT_EQ(tag_text(m, DC::PhotometricInterpretation), "RGB");
        EXPECT_EQ(m->Get(DC::SamplesPerPixel).AsInt(), 3);
        EXPECT_EQ(m->Get(DC::BitsAllocated).AsInt(), 8);
        EXPECT_EQ(m->Get(DC::Rows).AsInt(), 120);
        EXPECT_EQ(m->Get(DC::Columns).AsInt(), 160);
        EXPECT_EQ(tag_text(m, DC::ConversionType), "WSD");
        // The provenance the PNG carries.
        const std::string comments = tag_text(m, DC::ImageComments);
        EXPECT_NE(comments.find("isoscope:input: " + fs::absolute(src).lexically_normal().string()), std::string::npos)
            << comments;
        EXPECT_NE(comments.find(std::string("isoscope:iso: ") + (i == 0 ? "200" : "300")), std::string::npos)
            << comments;
        EXPECT_NE(comments.find("isoscope:commit: "), std::string::npos) << comments;
        EXPECT_NE(tag_text(m, DC::DerivationDescription).find(tag_text(source, DC::SeriesInstanceUID)),
                  std::string::npos);
    }
    EXPECT_NE(tag_text(md[0], DC::SOPInstanceUID), tag_text(md[1], DC::SOPInstanceUID));
    expect_same_pixels(files[0], dir / "a.png");
    expect_same_pixels(files[1], dir / "b.png");
    expect_tools_read(files[1], tag_text(source, DC::StudyInstanceUID));
}

TEST(DicomExport, AFigureOfAnotherFormatStartsANewStudyThatSaysSo) {
    TempDir dir;
    const std::string pacs = dir / "pacs";
    // --dicom alone: no PNG needed.
    const std::string out = run(test::data("headsq.nhdr") + " --iso 1150 --size 96x96 --ao off --dicom " + pacs);
    EXPECT_NE(out.find("in a new study"), std::string::npos) << out;
    run(test::data("headsq.nhdr") + " --iso 500 --size 96x96 --ao off --dicom " + pacs);
    const auto files = dcm_files(pacs);
    ASSERT_EQ(files.size(), 2u);
    const auto a = header(files[0]), b = header(files[1]);
    EXPECT_NE(tag_text(a, DC::StudyDescription).find("headsq.nhdr (not from a DICOM study)"), std::string::npos);
    EXPECT_EQ(tag_text(a, DC::StudyInstanceUID), tag_text(b, DC::StudyInstanceUID));
    EXPECT_EQ(tag_text(a, DC::SeriesInstanceUID), tag_text(b, DC::SeriesInstanceUID));
    EXPECT_EQ(b->Get(DC::InstanceNumber).AsInt(), 2);
    EXPECT_EQ(tag_text(a, DC::SOPClassUID), kSecondaryCapture);
    expect_tools_read(files[0], tag_text(a, DC::StudyInstanceUID));
}

TEST(DicomExport, ErrorsNameTheFlagAndNothingIsOverwritten) {
    TempDir dir;
    const std::string head = test::cli() + " render " + test::data("headsq.nhdr") + " --iso 500 --size 64x64 ";
    auto r = test::run_command(head + "--aov depth --dicom " + (dir / "d"), true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("--dicom"), std::string::npos) << r.out;
    r = test::run_command(head, true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("--dicom"), std::string::npos) << r.out;
    // A file where the folder should be: named, left as it was.
    test::write_file(dir / "taken", "user data");
    r = test::run_command(head + "--dicom " + (dir / "taken"), true);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find(dir / "taken"), std::string::npos) << r.out;
    EXPECT_EQ(test::read_file(dir / "taken"), "user data");
}
