// A rendered figure as a DICOM Secondary Capture image, the form in which key
// images reach a PACS (docs/dicom_export.md).
//
// For a volume read from DICOM the figure joins the source's study: the
// patient and general study attributes (Study Instance UID among them) are
// copied from one file of the source series, in a series of its own
// ("isoscope 3D"). For any other input it starts a new study whose
// description says so ("not from a DICOM study"). One series holds the
// figures of one session: the caller names it (the desktop app keeps one per
// opened data), or else the folder's isoscope series of the same study gets
// the new instance (the command line run again into one folder), or else a
// new series is made. Burned In Annotation is YES (the legend, scale bar,
// orientation letters are pixels); the provenance the PNG carries (input,
// its SHA-256, iso values, camera, matrices, version, commit) is in Image
// Comments, a summary in Derivation Description.
//
// Written with vtk-dicom (vtkDICOMWriter, vtkDICOMSCGenerator): RGB, 8 bits,
// explicit VR little endian; into a new file (never over one), through a
// temporary name.
#pragma once

#include <string>

#include "io/image.hpp"
#include "io/volume.hpp"

namespace iso {

struct DicomCaptureOptions {
    // The series to add the figure to (the desktop app's session); empty:
    // the folder's isoscope series of the same study, else a new one.
    std::string series_uid;
    std::string series_description = "isoscope 3D";
};

struct DicomCaptureResult {
    std::string file; // what was written
    std::string study_uid, series_uid, sop_uid;
    int series_number = 0, instance_number = 0;
    bool source_study = false; // joined the source's DICOM study (else a new study)
    bool new_series = false;   // the series started with this figure
};

// Writes `image` (8-bit RGB or RGBA, first row at the top; alpha is
// composited over black) with its metadata as the next instance in folder
// `dir` (created if missing). `source` is the volume's metadata (its format,
// UIDs and reference file say where it came from). Throws iso::Error naming
// the folder or file.
DicomCaptureResult write_dicom_capture(const Image& image, const ImageMetadata& meta, const Metadata& source,
                                       const std::string& dir, const DicomCaptureOptions& opt = {});

} // namespace iso
