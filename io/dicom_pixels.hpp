// Decoding a DICOM series' pixel data (inside the DICOM reader, io/dicom.cpp).
//
// vtkDICOMReader decodes uncompressed pixel data itself; for every other
// transfer syntax it hands the file to GDCM (JPEG, JPEG-LS, JPEG 2000 ...) or
// to its own RLE decoder. Debian builds GDCM with its assertions on, and the
// fuzzer found GDCM aborting the process on a mutated JPEG file, and vtk-dicom's
// RLE decoder dividing by a segment count read from the file. No walk of the
// element structure (io/dicom_structure.hpp) can vouch for a compressed
// stream's insides, so compressed series are decoded in a child process
// (io/child_process.hpp) that hands the decoded voxels back through a pipe:
// whatever a decoder does to its process, the reading program gets an
// iso::Error naming the folder. Uncompressed series, the common case for CT,
// are decoded here.
#pragma once

#include <string>
#include <vector>

#include <vtkDataArray.h>
#include <vtkSmartPointer.h>

#include "io/progress.hpp"

namespace iso {

struct DecodedPixels {
    vtkSmartPointer<vtkDataArray> array; // stored values, slice after slice, rows as in the files
    int dims[3] = {0, 0, 0};
    int components = 0;
    std::vector<int> file_index; // output slice k holds files[file_index[k]]; empty: in order
    // What the decoder (GDCM) said while decoding, deduplicated with counts,
    // as warnings naming `where` (its messages never reach the terminal).
    std::vector<std::string> notes;
};

// Whether vtk-dicom decodes this transfer syntax itself without a codec.
bool dicom_is_native(const std::string& transfer_syntax);

// vtkDICOMReader over `files` in this order (no sorting, rows as stored, no
// rescaling), in a child process when `isolate`. Progress is reported from
// `from` to `to` of the load under `stage`. Errors name `where`; a stop asked
// for by `progress` throws iso::Cancelled.
DecodedPixels decode_dicom_pixels(const std::vector<std::string>& files, bool isolate, const std::string& where,
                                  const ProgressFn& progress, double from, double to, const char* stage);

} // namespace iso
