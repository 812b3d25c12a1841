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

std::vector<Surface> extract_surfaces(const Volume& v, const SurfaceRequest& req) {
    std::vector<Surface> out;
    // Extraction is most of the work; post-processing shares the rest of the bar.
    const bool post = needs_postprocess(req.post);
    const double share = post ? 0.6 : 1.0;
    ExtractOptions eo = req.extract;
    if (req.progress)
        eo.progress = [&](double f, std::string_view stage) { return req.progress(f * share, stage); };
    if (req.labels) {
        for (auto& ls : extract_labels(v, req.label_values, eo)) {
            char name[64];
            std::snprintf(name, sizeof name, "label %g", ls.label);
            out.push_back({name, ls.label, std::move(ls.mesh)});
        }
    } else {
        if (req.isos.empty()) throw Error("extract_surfaces", "no iso value given");
        const auto range = v.value_range();
        for (std::size_t i = 0; i < req.isos.size(); ++i) {
            char name[64];
            std::snprintf(name, sizeof name, "iso %g", req.isos[i]);
            out.push_back({name, req.isos[i], {}});
        }
        auto meshes = extract_isosurfaces(v, req.isos, eo);
        for (std::size_t i = 0; i < meshes.size(); ++i) {
            out[i].mesh = std::move(meshes[i]);
            if (req.isos[i] > range.max || req.isos[i] <= range.min) {
                char w[160];
                std::snprintf(w, sizeof w, "iso value %g is outside the volume's value range [%g, %g]: the surface is empty",
                              req.isos[i], range.min, range.max);
                out[i].mesh.warnings.push_back(w);
            }
        }
    }
    if (post) {
        for (std::size_t i = 0; i < out.size(); ++i) {
            const double base = share + (1.0 - share) * double(i) / double(out.size());
            ProgressFn pp;
            if (req.progress)
                pp = [&](double f, std::string_view stage) {
                    return req.progress(base + f * (1.0 - share) / double(out.size()), stage);
                };
            auto warnings = out[i].mesh.warnings;
            out[i].mesh = postprocess(out[i].mesh, req.post, pp);
            out[i].mesh.warnings = std::move(warnings);
        }
    }
    report(req.progress, 1.0, "done", "extract_surfaces");
    return out;
}

} // namespace iso::core
