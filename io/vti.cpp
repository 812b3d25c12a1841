// VTK image data (.vti) through vtkXMLImageDataReader. VTK has no patient
// convention: world coordinates in a .vti are taken as LPS millimetres, which
// is what isoscope writes and what ITK/Slicer-based tools produce.
#include <cstring>
#include <filesystem>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkXMLImageDataReader.h>

#include "io/vtk_util.hpp"
#include "io/vtp_check.hpp"
#include "io/volume_io.hpp"

namespace iso {

Volume read_vti(const std::string& path) {
    quiet_vtk();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, "no such file");
    if (std::filesystem::file_size(path, ec) == 0) throw Error(path, "file is empty");
    vtkNew<vtkXMLImageDataReader> r;
    if (!r->CanReadFile(path.c_str())) throw Error(path, "not a VTK XML image data file");
    detail::check_vtk_xml_headers(path);
    vtkNew<VtkMessages> msgs;
    msgs->watch(r);
    r->SetFileName(path.c_str());
    // Read the extent first so that huge dimensions are refused before allocation.
    r->UpdateInformation();
    if (msgs->has_error()) throw Error(path, msgs->first_error());
    r->Update();
    if (msgs->has_error()) throw Error(path, msgs->first_error());
    vtkImageData* img = r->GetOutput();
    if (!img) throw Error(path, "no image data");
    vtkDataArray* arr = img->GetPointData()->GetScalars();
    if (!arr && img->GetPointData()->GetNumberOfArrays() > 0) arr = img->GetPointData()->GetArray(0);
    if (!arr) throw Error(path, "no point data array (cell data images are not supported)");
    if (arr->GetNumberOfComponents() != 1)
        throw Error(path, std::string("array '") + (arr->GetName() ? arr->GetName() : "") + "' has " +
                              std::to_string(arr->GetNumberOfComponents()) +
                              " components: only scalar volumes are supported");
    VoxelType type;
    switch (arr->GetDataType()) {
    case VTK_SIGNED_CHAR:
    case VTK_CHAR: type = VoxelType::I8; break;
    case VTK_UNSIGNED_CHAR: type = VoxelType::U8; break;
    case VTK_SHORT: type = VoxelType::I16; break;
    case VTK_UNSIGNED_SHORT: type = VoxelType::U16; break;
    case VTK_INT: type = VoxelType::I32; break;
    case VTK_UNSIGNED_INT: type = VoxelType::U32; break;
    case VTK_FLOAT: type = VoxelType::F32; break;
    case VTK_DOUBLE: type = VoxelType::F64; break;
    default: throw Error(path, std::string("unsupported voxel type ") + arr->GetDataTypeAsString());
    }
    int ext[6];
    img->GetExtent(ext);
    const std::array<std::int64_t, 3> dims{ext[1] - ext[0] + 1, ext[3] - ext[2] + 1, ext[5] - ext[4] + 1};
    const std::size_t bytes = checked_byte_size(path, dims, type);
    if (std::size_t(arr->GetNumberOfValues()) * voxel_size(type) != bytes)
        throw Error(path, "array size does not match the extent (truncated or corrupt file)");
    double sp[3], org[3];
    img->GetSpacing(sp);
    img->GetOrigin(org);
    glm::dmat3 dir(1.0);
    const vtkMatrix3x3* d = img->GetDirectionMatrix();
    for (int c = 0; c < 3; ++c)
        for (int r2 = 0; r2 < 3; ++r2) dir[c][r2] = d->GetElement(r2, c);
    // The extent may not start at 0: index (0,0,0) of ours is extent start.
    glm::dmat4 affine = make_affine({sp[0], sp[1], sp[2]}, {org[0], org[1], org[2]}, dir);
    affine[3] = affine * glm::dvec4(ext[0], ext[2], ext[4], 1.0);
    for (int a = 0; a < 3; ++a)
        if (!(sp[a] > 0.0)) throw Error(path, std::string("spacing along ") + "ijk"[a] + " is zero or negative");
    check_affine(path, affine);
    Volume v = Volume::dense(dims, type, affine);
    std::memcpy(v.bytes().data(), arr->GetVoidPointer(0), bytes);
    v.meta.source = path;
    v.meta.format = "VTI";
    warn_non_finite(v);
    return v;
}

} // namespace iso
