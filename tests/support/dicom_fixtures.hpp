// DICOM series written with vtkDICOMWriter for the tests (the reader's
// unit tests, tests/unit/dicom_test.cpp, and the desktop app's series
// chooser, tests/gl/gui_views_test.cpp): one file per slice, stored value
// pattern(i, j, k) = i + 10*j + 100*k at voxel (i, j, k).
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <vtkDICOMCTGenerator.h>
#include <vtkDICOMMRGenerator.h>
#include <vtkDICOMMetaData.h>
#include <vtkDICOMWriter.h>
#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>

#include <gtest/gtest.h>

namespace iso::test {

namespace fs = std::filesystem;

inline int pattern(int i, int j, int k) { return i + 10 * j + 100 * k; }

inline glm::dmat3 rot_x(double deg) {
    const double a = deg * M_PI / 180, c = std::cos(a), s = std::sin(a);
    return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, c, s), glm::dvec3(0, -s, c));
}
inline glm::dmat3 rot_z(double deg) {
    const double a = deg * M_PI / 180, c = std::cos(a), s = std::sin(a);
    return glm::dmat3(glm::dvec3(c, s, 0), glm::dvec3(-s, c, 0), glm::dvec3(0, 0, 1));
}

struct SeriesSpec {
    int nx = 16, ny = 12, nz = 8;
    glm::dvec3 spacing{0.7, 0.8, 2.5};
    glm::dmat3 rot{1.0};            // columns: row direction, column direction, slice normal
    glm::dvec3 origin{-10, 20, 30}; // IPP of slice k = 0
    bool ct = true;                 // CT generator with rescale; else MR (no rescale)
    double slope = 1, intercept = -1024;
    std::string description = "test series";
    std::string image_type; // e.g. "ORIGINAL/PRIMARY/LOCALIZER"
    std::string pattern = "%s/IM-%04d.dcm";
    int series_number = 0;
};

// Writes one series, one file per slice; stored value = pattern(i, j, k).
inline void write_series(const std::string& dir, const SeriesSpec& s) {
    fs::create_directories(dir);
    vtkNew<vtkImageData> img;
    img->SetDimensions(s.nx, s.ny, s.nz);
    img->SetSpacing(s.spacing.x, s.spacing.y, s.spacing.z);
    img->SetOrigin(0, 0, 0);
    img->AllocateScalars(VTK_SHORT, 1);
    auto* p = static_cast<short*>(img->GetScalarPointer());
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) *p++ = short(pattern(i, j, k));
    vtkNew<vtkMatrix4x4> m;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m->SetElement(r, c, s.rot[c][r]);
        m->SetElement(r, 3, s.origin[r]);
    }
    vtkNew<vtkDICOMWriter> w;
    vtkNew<vtkDICOMCTGenerator> ct;
    vtkNew<vtkDICOMMRGenerator> mr;
    if (s.ct)
        w->SetGenerator(ct);
    else
        w->SetGenerator(mr);
    if (s.series_number) {
        vtkNew<vtkDICOMMetaData> md;
        md->Set(DC::SeriesNumber, s.series_number);
        w->SetMetaData(md);
    }
    w->SetInputData(img);
    w->SetMemoryRowOrderToFileNative(); // VTK row j = file row j
    w->SetPatientMatrix(m);
    w->SetFilePrefix(dir.c_str());
    w->SetFilePattern(s.pattern.c_str());
    w->SetSeriesDescription(s.description.c_str());
    if (!s.image_type.empty()) w->SetImageType(s.image_type.c_str());
    if (s.ct) {
        w->SetRescaleSlope(s.slope);
        w->SetRescaleIntercept(s.intercept);
    }
    w->Write();
    ASSERT_EQ(w->GetErrorCode(), 0u);
}

} // namespace iso::test
