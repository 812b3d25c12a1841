// Volume loading and saving, dispatched on the file name (or a folder, for
// DICOM). Every loader returns a whole volume or throws iso::Error naming the
// file and the reason: nothing half-loads.
#pragma once

#include <string>
#include <vector>

#include "io/progress.hpp"
#include "io/volume.hpp"

namespace iso {

struct LoadOptions {
    // DICOM: which series to load when a folder holds several, by index into
    // the listing ("0", "1", ...) or by SeriesInstanceUID. Empty: the only
    // series, or an error listing them when there are several.
    std::string series;
    ProgressFn progress;
};

enum class VolumeFormat { Unknown, Dicom, Nifti, Nrrd, MetaImage, Vti, Vdb };
VolumeFormat volume_format_of(const std::string& path); // by extension; folders are DICOM
const char* volume_format_name(VolumeFormat f);

// `path` is a file or a folder (DICOM).
Volume load_volume(const std::string& path, const LoadOptions& opt = {});
// An explicit list of DICOM files (one or more series).
Volume load_dicom_files(const std::vector<std::string>& files, const LoadOptions& opt = {});

// Writes .nrrd/.nhdr (NRRD, gzip for .nrrd unless `compress` is false) or
// .nii/.nii.gz (NIfTI-1). Writes to a temporary file first and renames it, so
// an existing file is never left half-written.
void save_volume(const Volume& v, const std::string& path, bool compress = true);

// ---- per-format entry points (io/<format>.cpp) ------------------------------
std::vector<SeriesInfo> list_dicom_series(const std::vector<std::string>& files_or_folder);
Volume read_dicom(const std::vector<std::string>& files_or_folder, const LoadOptions& opt);
Volume read_nifti(const std::string& path);
void write_nifti(const Volume& v, const std::string& path);
Volume read_nrrd(const std::string& path);
void write_nrrd(const Volume& v, const std::string& path, bool compress);
Volume read_metaimage(const std::string& path);
Volume read_vti(const std::string& path);
Volume read_vdb(const std::string& path);
void write_vdb(const Volume& v, const std::string& path); // for tests and round trips

} // namespace iso
