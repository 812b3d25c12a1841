// Writes a small seed corpus for every fuzz target with the project's own
// writers (and, for DICOM, vtkDICOMWriter; for markups, the Slicer-style
// fixtures in datasets/markups/ too): fuzz_seeds OUT_DIR
#include <filesystem>
#include <fstream>
#include <iostream>

#include <vtkDICOMMRGenerator.h>
#include <vtkDICOMWriter.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkShortArray.h>
#include <vtkXMLImageDataWriter.h>

#include "io/markups.hpp"
#include "io/mesh.hpp"
#include "io/volume_io.hpp"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: fuzz_seeds OUT_DIR\n";
        return 2;
    }
    const fs::path out = argv[1];
    auto dir = [&](const char* name) {
        fs::create_directories(out / name);
        return out / name;
    };
    iso::Volume v = iso::Volume::dense({5, 4, 3}, iso::VoxelType::I16, iso::make_affine({0.5, 0.7, 2}, {1, 2, 3}));
    for (std::size_t i = 0; i < v.as<std::int16_t>().size(); ++i) v.as<std::int16_t>()[i] = std::int16_t(i * 37 - 500);
    iso::save_volume(v, (dir("nrrd") / "raw.nrrd").string(), false);
    iso::save_volume(v, (dir("nrrd") / "gz.nrrd").string(), true);
    iso::save_volume(v, (dir("nifti") / "a.nii").string());
    iso::save_volume(v, (dir("vdb") / "a.vdb").string());
    {
        std::ofstream f(dir("metaimage") / "a.mha", std::ios::binary);
        f << "ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementSpacing = 0.5 0.7 2\nOffset = 1 2 3\n"
             "TransformMatrix = 1 0 0 0 1 0 0 0 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n";
        f.write(reinterpret_cast<const char*>(v.bytes().data()), std::streamsize(v.bytes().size()));
    }
    vtkNew<vtkImageData> img;
    img->SetDimensions(5, 4, 3);
    vtkNew<vtkShortArray> arr;
    arr->SetNumberOfTuples(60);
    for (int i = 0; i < 60; ++i) arr->SetValue(i, short(i));
    img->GetPointData()->SetScalars(arr);
    {
        vtkNew<vtkXMLImageDataWriter> w;
        w->SetInputData(img);
        w->SetDataModeToAscii();
        w->SetFileName((dir("vti") / "a.vti").c_str());
        w->Write();
    }
    {
        vtkNew<vtkImageData> slice;
        slice->SetDimensions(5, 4, 1);
        vtkNew<vtkShortArray> a;
        a->SetNumberOfTuples(20);
        for (int i = 0; i < 20; ++i) a->SetValue(i, short(i * 3));
        slice->GetPointData()->SetScalars(a);
        vtkNew<vtkDICOMMRGenerator> gen;
        vtkNew<vtkDICOMWriter> w;
        w->SetInputData(slice);
        w->SetGenerator(gen);
        w->SetFilePrefix(dir("dicom").c_str());
        w->SetFilePattern("%s/a%d.dcm");
        w->Write();
    }
    iso::Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (const char* f : {"stl", "ply", "obj", "vtp"}) iso::save_mesh(m, (dir(f) / (std::string("a.") + f)).string());
    {
        std::ofstream f(out / "stl" / "ascii.stl");
        f << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 "
             "0\nendloop\nendfacet\nendsolid t\n";
        std::ofstream p(out / "ply" / "ascii.ply");
        p << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    }
    {
        const fs::path markups = dir("markups");
        for (const auto& e : fs::directory_iterator(fs::path(ISOSCOPE_DATA_DIR) / "markups"))
            if (e.path().string().ends_with(".mrk.json")) fs::copy_file(e.path(), markups / e.path().filename());
        iso::MarkupsFile f;
        iso::Markup pts, line, angle;
        pts.type = iso::MarkupType::Fiducial;
        pts.name = "F";
        pts.points.resize(2);
        pts.points[0].label = "F-1";
        pts.points[0].position = {1.5, -2, 3};
        pts.points[1].status = iso::PositionStatus::Undefined;
        line.type = iso::MarkupType::Line;
        line.points.resize(2);
        line.points[1].position = {3, 4, 0};
        line.color = glm::dvec3(1, 0, 0);
        angle.type = iso::MarkupType::Angle;
        angle.points.resize(3);
        angle.points[0].position = {1, 0, 0};
        angle.points[2].position = {0, 1, 0};
        angle.measurements.push_back({"HU mean", 12.5, "[hnsf'U]", true, "", ""});
        f.markups = {pts, line, angle};
        iso::save_markups(f, (markups / "ours.mrk.json").string());
    }
    std::cout << "seeds written to " << out << "\n";
    return 0;
}
