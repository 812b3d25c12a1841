// An int16 volume as VTK image data, for the benchmarks that run VTK's
// filters on our samples (isosurface_bench, measure_bench).
#pragma once

#include <cstdint>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkShortArray.h>

#include "io/volume.hpp"

namespace iso::bench {

// Shares the samples (no copy): `v` must outlive the image. Axis-aligned
// grids only (spacing and origin; VTK 9.1's filters ignore directions).
inline vtkNew<vtkImageData> as_vtk(const Volume& v) {
    vtkNew<vtkImageData> img;
    img->SetDimensions(int(v.dims[0]), int(v.dims[1]), int(v.dims[2]));
    const auto sp = v.spacing();
    img->SetSpacing(sp.x, sp.y, sp.z);
    img->SetOrigin(v.index_to_lps[3][0], v.index_to_lps[3][1], v.index_to_lps[3][2]);
    vtkNew<vtkShortArray> arr;
    arr->SetArray(const_cast<std::int16_t*>(v.as<std::int16_t>().data()), v.voxel_count(), /*save=*/1);
    img->GetPointData()->SetScalars(arr);
    return img;
}

} // namespace iso::bench
