// `isoscope render`: surfaces of a volume or a mesh, or a session of the
// desktop app, to an annotated image or an AOV (core::render_image).
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>

#include "app/cli/commands.hpp"
#include "app/cli/frame_options.hpp"
#include "io/atomic_file.hpp"
#include "io/markups.hpp"
#include "renderer/core/session.hpp"

namespace iso::cli {

namespace {

struct RenderArgs {
    FrameArgs frame;
    std::string out, aov, cache, session, dicom;
    std::vector<std::string> markups;
    bool stats = false, no_annotations = false, no_legend = false, no_markups = false;
    bool view_given = false, ao_given = false;     // with --session: replace the session's camera / AO method
    bool volume_given = false, mode_given = false; // --volume, --volume-mode: replace the session's
};

void print_volume_stats(const iso::VolumeStats& v) {
    if (!v.drawn) return;
    const double taken = double(v.samples), all = double(v.samples + v.skipped);
    std::cout << "volume: step " << std::setprecision(3) << v.step_mm << " mm; " << v.rays << " rays, " << v.samples
              << " samples, " << v.skipped << " skipped in empty chunks (" << std::setprecision(1)
              << (all > 0 ? 100.0 * (1.0 - taken / all) : 0.0) << " %), " << v.terminated << " rays ended early; "
              << v.empty_chunks << " of " << v.chunks << " chunks empty under the transfer function; texture "
              << human_bytes(double(v.texture_bytes)) << "\n";
}

void print_stats(const iso::graph::FrameStats& stats, const iso::OitStats& oit) {
    std::cout << std::left << std::setw(14) << "pass" << std::setw(8) << "ran" << std::setw(12) << "ms"
              << "created\n";
    double total = 0;
    for (const auto& p : stats.passes) {
        std::cout << std::setw(14) << p.name << std::setw(8) << (p.ran ? "yes" : "culled") << std::setw(12)
                  << std::fixed << std::setprecision(2) << p.ms << human_bytes(double(p.bytes_created)) << "\n";
        total += p.ms;
    }
    std::cout << "total " << total << " ms; " << stats.physical_resources << " resources created, "
              << stats.reused_resources << " reused; peak " << human_bytes(double(stats.peak_bytes)) << "\n";
    if (oit.fragments > 0)
        std::cout << "transparency: " << oit.fragments << " fragments in " << oit.lists << " pixel lists (longest "
                  << oit.max_list << "), " << oit.shaded << " shaded, " << oit.merged << " merged past the cap; pool "
                  << oit.capacity << " nodes, " << oit.redraws << " redraw(s)\n";
    if (oit.merged > 0)
        std::cout << "transparency: merged fragments in " << oit.merged_pixels << " pixels, error at most "
                  << std::setprecision(4) << oit.merge_error_max << " (linear colour, per channel)\n";
}

void print_lod_stats(const iso::LodStats& s, const char* which) {
    if (!s.used) return;
    std::cout << "levels of detail (" << which << " frame): " << s.triangles_drawn << " of " << s.triangles_full
              << " triangles drawn; clusters " << s.clusters << ", tested " << s.tested << ", culled "
              << s.culled_frustum << " outside the view, " << s.culled_backface << " facing away, "
              << s.culled_occlusion << " hidden; drawn " << s.drawn << " in " << s.phases << " phases";
    if (s.build_seconds > 0) std::cout << "; levels built in " << std::setprecision(2) << s.build_seconds << " s";
    std::cout << "\n";
}

void print_dicom(const iso::DicomCaptureResult& d) {
    std::cout << "DICOM Secondary Capture -> " << d.file << "\n  "
              << (d.source_study ? "in the source's study " : "in a new study (not from DICOM) ") << d.study_uid
              << "\n  series " << d.series_number << " " << d.series_uid << (d.new_series ? " (new)" : " (added to)")
              << ", instance " << d.instance_number << "\n";
}

// `isoscope render --session`: the request comes from core::session_request,
// as the desktop app's File > Export image builds it; the frame's other
// options (size, background, AO settings, ...) are the command line's.
iso::core::RenderRequest session_render_request(const RenderArgs& a, iso::core::OpenedSession& opened) {
    const auto& f = a.frame;
    if (!f.in.empty()) throw iso::Error("--session", "the session names its input: give INPUT or --session, not both");
    for (const auto& [given, flag] : {std::pair{!f.req.isos.empty(), "--iso"},
                                      {!f.req.series.empty(), "--series"},
                                      {!f.look.opacity.empty(), "--opacity"},
                                      {!f.look.color.empty(), "--color"}})
        if (given) throw iso::Error(flag, "the session holds the surfaces and the series: not with --session");
    iso::core::SessionParts take;
    take.camera = !a.view_given;
    take.markups = !a.no_markups;
    take.ao = !a.ao_given;
    const iso::core::RenderRequest cli = frame_request(f);
    iso::core::RenderRequest req = iso::core::session_request(opened.session, a.session, cli, take);
    // What the command line gives replaces the session's, as --view and --ao do.
    if (a.volume_given)
        req.look.volume = cli.look.volume;
    else if (a.mode_given)
        req.look.volume.mode = cli.look.volume.mode;
    // Sessions keep the volume's look, not how it is marched.
    req.look.volume.integration = cli.look.volume.integration;
    if (!f.clip.empty()) req.look.clip = cli.look.clip;
    return req;
}

int run_render(const RenderArgs& a) {
    if (a.session.empty() && a.frame.in.empty())
        throw iso::Error("isoscope render", "give an INPUT (or --session FILE)");
    if (a.no_markups && a.session.empty())
        throw iso::Error("--no-markups", "only with --session (without it, give no --markups)");
    if (a.out.empty() && a.dicom.empty()) throw iso::Error("isoscope render", "give -o FILE, --dicom DIR or both");
    if (!a.dicom.empty() && !a.aov.empty())
        throw iso::Error("--dicom", "a DICOM figure is the colour image, not an AOV (--aov)");
    std::optional<iso::core::OpenedSession> opened;
    iso::core::RenderRequest req;
    if (a.session.empty()) {
        req = frame_request(a.frame);
    } else {
        if (!a.out.empty()) iso::check_writable_destination(a.out);
        opened = iso::core::open_session(a.session, progress_bar());
        for (const auto& w : opened->session.warnings) std::cerr << "warning: " << a.session << ": " << w << "\n";
        req = session_render_request(a, *opened);
    }
    req.aov = iso::aov_from_name(a.aov);
    req.cache_dir = a.cache;
    req.annotations = !a.no_annotations;
    req.legend = !a.no_legend;
    req.time_passes = a.stats;
    if (!a.markups.empty() && !a.aov.empty())
        throw iso::Error("--markups", "markups are drawn on the colour image, not on an AOV (--aov)");
    if (!a.out.empty()) iso::check_writable_destination(a.out);
    // Markups before the volume: a bad file fails fast, naming itself.
    for (const auto& path : a.markups) {
        auto f = iso::load_markups(path);
        for (const auto& w : f.warnings) std::cerr << "warning: " << path << ": " << w << "\n";
        for (auto& m : f.markups) req.markups.push_back(std::move(m));
        req.markups_files.push_back(path);
    }
    iso::core::Scene local;
    if (!opened) open_input(local, a.frame.in, req.series, req.isos, a.frame.look, "render", req.look.volume.enabled);
    iso::core::Scene& scene = opened ? *opened->scene : local;
    const auto out = iso::core::render_image(scene, req);
    if (!a.out.empty()) {
        iso::core::export_image(out.image, out.meta, a.out);
        std::cout << "rendered " << out.image.width << "x" << out.image.height << " (" << out.gl_renderer << ") -> "
                  << a.out << "\n";
    }
    if (!a.dicom.empty()) print_dicom(iso::core::export_dicom(scene, out.image, out.meta, a.dicom));
    if (a.stats) {
        if (out.aa_frames > 1) {
            std::cout << "first frame of " << out.aa_frames << ":\n";
            print_stats(out.first_stats, {});
            std::cout << "last frame:\n";
        }
        print_stats(out.stats, out.oit);
        print_volume_stats(out.volume);
        print_lod_stats(out.lod_first, "first");
        print_lod_stats(out.lod, "last");
    }
    if (out.oit.merged > 0)
        std::cerr << "warning: " << out.oit.merged << " translucent fragments in " << out.oit.merged_pixels
                  << " pixels did not fit the " << req.look.oit_memory_mib
                  << " MiB pool (--oit-memory) and were merged, order-independently: error at most "
                  << std::setprecision(3) << out.oit.merge_error_max << " per channel\n";
    return 0;
}

} // namespace

RunFn add_render(CLI::App& cmd, char*) {
    const auto args = std::make_shared<RenderArgs>();
    RenderArgs& a = *args;
    CLI::App* c = &cmd;
    add_frame_options(c, a.frame, false);
    c->add_option("--session", a.session,
                  "Render a session file of the desktop app (its input, surfaces, camera, markups, AO) "
                  "instead of INPUT; --view replaces its camera, --ao its AO setting, --volume and --volume-mode its "
                  "volume, --clip its crop");
    c->add_flag("--no-markups", a.no_markups, "With --session: leave out the session's markups");
    c->add_option("--scale", a.frame.req.scale, "Scale of text, lines and glyphs (e.g. 2 for a 2x export)")
        ->check(CLI::Range(0.1, 20.0));
    c->add_option("--aov", a.aov, "Write a buffer instead of the colour image: depth, normal, id or ao (EXR)");
    c->add_option("--ao-rays", a.frame.req.look.ao_rays, "--ao raytraced: the most rays per pixel (default 1024)")
        ->check(CLI::Range(1, 1 << 20));
    c->add_option("--ao-error", a.frame.req.look.ao_error,
                  "--ao raytraced: add rays until every pixel's standard error is at most this (default 0.005)")
        ->check(CLI::Range(1e-4, 0.5));
    c->add_option("--ao-cache", a.cache, "Folder caching ray-traced AO ('-': none; default ~/.cache/isoscope)");
    c->add_flag("--no-annotations", a.no_annotations,
                "No scale bar, orientation letters, legend or labels (--markups are still drawn)");
    c->add_flag("--no-legend", a.no_legend,
                "No legend (the surfaces' names, colours, opacities and iso values in a corner box)");
    c->add_option("--markups", a.markups,
                  "3D Slicer markups file (.mrk.json) to draw: points with their labels, lines and angles "
                  "with their names and values (repeatable; dimmed where a surface hides them)")
        ->allow_extra_args(false);
    c->add_flag("--transparent", a.frame.req.look.transparent_background, "Transparent background");
    c->add_flag("--stats", a.stats, "Print per-pass statistics");
    c->add_option("-o,--output", a.out, "Output .png, .tif or .exr");
    c->add_option("--dicom", a.dicom,
                  "Also (or only) write the figure as a DICOM Secondary Capture into this folder: in the source's "
                  "study for a DICOM input (a new study otherwise), in the folder's isoscope series of that study");
    return [args, c] {
        args->view_given = c->get_option("--view")->count() > 0;
        args->ao_given = c->get_option("--ao")->count() > 0;
        args->volume_given = c->get_option("--volume")->count() > 0;
        args->mode_given = c->get_option("--volume-mode")->count() > 0;
        return run_render(*args);
    };
}

} // namespace iso::cli
