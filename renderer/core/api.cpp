#include "renderer/core/api.hpp"

#include <filesystem>

namespace iso::core {

const char* version() { return ISOSCOPE_VERSION; }

Volume open_volume(const std::string& path, const LoadOptions& opt) { return load_volume(path, opt); }

Mesh open_mesh(const std::string& path) { return load_mesh(path); }

std::vector<SeriesInfo> list_series(const std::string& path) { return list_dicom_series({path}); }

nlohmann::json describe(const Volume& v) {
    using nlohmann::json;
    json j;
    j["source"] = v.meta.source;
    j["format"] = v.meta.format;
    j["dims"] = {v.dims[0], v.dims[1], v.dims[2]};
    j["type"] = voxel_type_name(v.type);
    const auto sp = v.spacing();
    j["spacing"] = {sp.x, sp.y, sp.z};
    json m = json::array();
    for (int r = 0; r < 4; ++r) m.push_back({v.index_to_lps[0][r], v.index_to_lps[1][r], v.index_to_lps[2][r],
                                             v.index_to_lps[3][r]});
    j["index_to_lps"] = m;
    const auto range = v.value_range();
    j["range"] = {range.min, range.max};
    j["nan_count"] = range.nan_count;
    j["inf_count"] = range.inf_count;
    j["memory_bytes"] = v.memory_bytes();
    j["storage"] = v.is_sparse() ? "sparse" : "dense";
    json meta;
    meta["modality"] = v.meta.modality;
    meta["patient_name"] = v.meta.patient_name;
    meta["patient_id"] = v.meta.patient_id;
    meta["study_uid"] = v.meta.study_uid;
    meta["series_uid"] = v.meta.series_uid;
    meta["series_description"] = v.meta.series_description;
    j["metadata"] = meta;
    j["warnings"] = v.meta.warnings;
    if (!v.meta.series.empty()) {
        json s = json::array();
        for (const auto& si : v.meta.series)
            s.push_back({{"uid", si.uid}, {"description", si.description}, {"modality", si.modality},
                         {"number", si.number}, {"dims", si.dims}, {"files", si.files}});
        j["series"] = s;
        j["selected_series"] = v.meta.selected_series;
    }
    return j;
}

} // namespace iso::core
