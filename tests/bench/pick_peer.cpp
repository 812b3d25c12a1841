// The peer for the picking benchmark: VTK 9.1 drawing the same meshes,
// colours, opacities, camera and image size, and picking the same pixels two
// ways a VTK user would:
//  - vtkHardwareSelector (the OpenGL one), a 1x1 area, cell association:
//    Select() renders its own selection passes (actor id, cell id, ...) and
//    reads them back; it gives the actor and the cell, no point. During
//    selection VTK draws translucent actors as opaque (vtkActor::
//    RenderOpaqueGeometry renders any actor with opacity > 0 when a selector
//    is set), so it returns the nearest surface whatever its opacity.
//  - vtkCellPicker with one vtkCellLocator per mesh, built once before the
//    picks (the way its documentation advises for large data): a CPU ray
//    cast from the near to the far plane through the pixel's centre, no
//    rendering; it returns the first cell the ray meets, whatever its
//    opacity, and the point there.
// Pixels are given from the image's top-left, as the benchmark's; VTK's
// display coordinates start at the bottom-left corner of the bottom-left
// pixel (vtkViewport::DisplayToView), so pixel (x, y)'s centre is
// (x + 0.5, H - y - 0.5) for the picker and pixel (x, H - 1 - y) for the
// selector. Translucent frames are drawn with VTK's default (weighted-blended
// OIT), as a user's window would. VTK renders through X here: run under
// xvfb-run.
//
//   pick_peer --mesh a.ply --color R,G,B --opacity A [--mesh ...] --eye X,Y,Z --target X,Y,Z --up X,Y,Z
//             --fov DEG --near MM --far MM --size WxH --background R,G,B --pixel X,Y [--pixel ...]
//             [--reps 3] [--frames 5] [--warmup 2]
// Prints one JSON line: the frame time, the locators' build times, and per
// pixel each method's median time over the repetitions and what it picked.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellLocator.h>
#include <vtkCellPicker.h>
#include <vtkDataObject.h>
#include <vtkHardwareSelector.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderer.h>
#include <vtkOutputWindow.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkSelection.h>
#include <vtkSelectionNode.h>
#include <vtkSmartPointer.h>

#include "io/error.hpp"
#include "io/mesh.hpp"
#include "io/vtk_mesh.hpp"
#include "vtk_peer.hpp"

namespace {

using iso::vtk_peer::quantile;
using clock_type = std::chrono::steady_clock;

double ms_since(clock_type::time_point t0) {
    return std::chrono::duration<double, std::milli>(clock_type::now() - t0).count();
}

} // namespace

int main(int argc, char** argv) {
    iso::vtk_peer::Scene sc;
    std::vector<std::array<int, 2>> pixels;
    int reps = 3, frames = 5, warmup = 2;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::cerr << "pick_peer: " << a << " needs a value\n";
            return 2;
        }
        const std::string v = argv[++i];
        bool ok = true;
        if (!sc.option(a, v, ok)) {
            if (a == "--pixel") {
                std::array<int, 2> p{};
                ok = std::sscanf(v.c_str(), "%d,%d", &p[0], &p[1]) == 2;
                pixels.push_back(p);
            } else if (a == "--reps")
                ok = (reps = std::stoi(v)) > 0;
            else if (a == "--frames")
                ok = (frames = std::stoi(v)) > 0;
            else if (a == "--warmup")
                warmup = std::stoi(v);
            else
                ok = false;
        }
        if (!ok) {
            std::cerr << "pick_peer: bad option " << a << " " << v << "\n";
            return 2;
        }
    }
    if (sc.surfaces.empty() || pixels.empty()) {
        std::cerr << "pick_peer: needs --mesh and --pixel\n";
        return 2;
    }
    const int W = sc.W, H = sc.H;
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        const auto view = iso::vtk_peer::make_view(sc);
        vtkOpenGLRenderer* ren = view->ren;
        vtkRenderWindow* win = view->win;
        const auto& actors = view->actors;
        auto& data = view->data;
        // The frame a user looks at while picking.
        const std::vector<double> frame_ms = iso::vtk_peer::timed_frames(*view, sc, warmup, frames, "pick_peer");
        // The cell picker's locators: built once, before any pick.
        vtkNew<vtkCellPicker> picker;
        nlohmann::json locator_ms = nlohmann::json::array();
        std::vector<vtkSmartPointer<vtkCellLocator>> locators;
        for (auto& pd : data) {
            auto loc = vtkSmartPointer<vtkCellLocator>::New();
            loc->SetDataSet(pd);
            const auto t0 = clock_type::now();
            loc->BuildLocator();
            locator_ms.push_back(ms_since(t0));
            picker->AddLocator(loc);
            locators.push_back(loc);
        }
        vtkNew<vtkHardwareSelector> selector;
        selector->SetRenderer(ren);
        selector->SetFieldAssociation(vtkDataObject::FIELD_ASSOCIATION_CELLS);
        const auto actor_index = [&](vtkObjectBase* p) -> int {
            for (std::size_t i = 0; i < actors.size(); ++i)
                if (actors[i].GetPointer() == p) return int(i);
            return -1;
        };
        // One warm-up of each (the selector compiles its selection shaders).
        picker->Pick(W / 2 + 0.5, H / 2 + 0.5, 0, ren);
        selector->SetArea(unsigned(W / 2), unsigned(H / 2), unsigned(W / 2), unsigned(H / 2));
        vtkSmartPointer<vtkSelection>::Take(selector->Select());
        nlohmann::json picks = nlohmann::json::array();
        for (const auto& px : pixels) {
            nlohmann::json j;
            j["x"] = px[0];
            j["y"] = px[1];
            std::vector<double> pick_ms, select_ms;
            nlohmann::json cp, hs;
            for (int r = 0; r < reps; ++r) {
                // vtkCellPicker: the ray through the pixel's centre.
                auto t0 = clock_type::now();
                const int hit = picker->Pick(px[0] + 0.5, H - px[1] - 0.5, 0.0, ren);
                pick_ms.push_back(ms_since(t0));
                if (r == 0) {
                    cp["hit"] = hit != 0;
                    cp["actor"] = hit ? actor_index(picker->GetActor()) : -1;
                    cp["cell"] = hit ? picker->GetCellId() : -1;
                    const double* p = picker->GetPickPosition();
                    cp["point"] = {p[0], p[1], p[2]};
                }
                // vtkHardwareSelector: a one-pixel area.
                const unsigned sx = unsigned(px[0]), sy = unsigned(H - 1 - px[1]);
                t0 = clock_type::now();
                selector->SetArea(sx, sy, sx, sy);
                auto sel = vtkSmartPointer<vtkSelection>::Take(selector->Select());
                select_ms.push_back(ms_since(t0));
                if (r == 0) {
                    hs["actor"] = -1;
                    hs["cell"] = -1;
                    hs["nodes"] = sel ? sel->GetNumberOfNodes() : 0;
                    if (sel && sel->GetNumberOfNodes() > 0) {
                        vtkSelectionNode* node = sel->GetNode(0);
                        vtkInformation* props = node->GetProperties();
                        if (props->Has(vtkSelectionNode::PROP()))
                            hs["actor"] = actor_index(props->Get(vtkSelectionNode::PROP()));
                        if (auto* ids = vtkIdTypeArray::SafeDownCast(node->GetSelectionList());
                            ids && ids->GetNumberOfTuples() > 0) {
                            hs["cell"] = ids->GetValue(0);
                            hs["cells"] = ids->GetNumberOfTuples();
                        }
                    }
                }
            }
            cp["ms"] = quantile(pick_ms);
            cp["ms_all"] = pick_ms;
            hs["ms"] = quantile(select_ms);
            hs["ms_all"] = select_ms;
            j["cell_picker"] = std::move(cp);
            j["selector"] = std::move(hs);
            picks.push_back(std::move(j));
        }
        nlohmann::json out;
        out["renderer"] = iso::vtk_peer::renderer_name(win);
        out["frame_ms"] = quantile(frame_ms);
        out["frame_ms_all"] = frame_ms;
        out["locator_build_ms"] = std::move(locator_ms);
        out["picks"] = std::move(picks);
        std::printf("%s\n", out.dump().c_str());
    } catch (const std::exception& e) {
        std::cerr << "pick_peer: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
