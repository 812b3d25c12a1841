// The peer for the transparency benchmark: VTK 9.1 drawing the same meshes,
// colours, opacities, camera and image size with its weighted-blended OIT
// (its default for translucent geometry) or dual depth peeling (a number of
// peels, 0 = until converged). Flat shading as ours: ambient 1, diffuse 0,
// specular 0, so a fragment is its colour. VTK blends the colours it is
// given in framebuffer space: they are passed linear, and the image is read
// back linear (8 bits). VTK renders through X here: run under xvfb-run.
//
//   oit_peer --mesh a.ply --color R,G,B --opacity A [--mesh ... ...] --eye X,Y,Z --target X,Y,Z --up X,Y,Z
//            --fov DEG --near MM --far MM --size WxH --background R,G,B --mode wboit|peel [--peels N]
//            [--frames 10] [--warmup 2] --out image.png
// Prints one JSON line: median and quartiles of ms per frame, the renderer.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderer.h>
#include <vtkOutputWindow.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkUnsignedCharArray.h>

#include "io/error.hpp"
#include "io/image.hpp"
#include "io/mesh.hpp"
#include "io/vtk_mesh.hpp"
#include "vtk_peer.hpp"

namespace {

using iso::vtk_peer::quantile;
using iso::vtk_peer::vec3;

struct Surface {
    std::string mesh;
    double color[3] = {1, 1, 1};
    double opacity = 1;
};

} // namespace

int main(int argc, char** argv) {
    std::vector<Surface> surfaces;
    double eye[3] = {0, 0, 0}, target[3] = {0, 0, 0}, up[3] = {0, 0, 1}, background[3] = {0, 0, 0};
    double fov = 30, near_plane = 1, far_plane = 1000;
    int W = 512, H = 512, peels = 4, frames = 10, warmup = 2;
    std::string mode = "wboit", out;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::cerr << "oit_peer: " << a << " needs a value\n";
            return 2;
        }
        const std::string v = argv[++i];
        bool ok = true;
        if (a == "--mesh") surfaces.push_back({v});
        else if (a == "--color") ok = !surfaces.empty() && vec3(v, surfaces.back().color);
        else if (a == "--opacity") ok = !surfaces.empty() && (surfaces.back().opacity = std::stod(v), true);
        else if (a == "--eye") ok = vec3(v, eye);
        else if (a == "--target") ok = vec3(v, target);
        else if (a == "--up") ok = vec3(v, up);
        else if (a == "--background") ok = vec3(v, background);
        else if (a == "--fov") fov = std::stod(v);
        else if (a == "--near") near_plane = std::stod(v);
        else if (a == "--far") far_plane = std::stod(v);
        else if (a == "--size") ok = std::sscanf(v.c_str(), "%dx%d", &W, &H) == 2 && W > 0 && H > 0;
        else if (a == "--mode") ok = (mode = v, v == "wboit" || v == "peel");
        else if (a == "--peels") peels = std::stoi(v);
        else if (a == "--frames") frames = std::stoi(v);
        else if (a == "--warmup") warmup = std::stoi(v);
        else if (a == "--out") out = v;
        else ok = false;
        if (!ok) {
            std::cerr << "oit_peer: bad option " << a << " " << v << "\n";
            return 2;
        }
    }
    if (surfaces.empty() || out.empty()) {
        std::cerr << "oit_peer: needs --mesh and --out\n";
        return 2;
    }
    try {
        vtkOutputWindow::GetInstance()->SetDisplayModeToAlwaysStdErr();
        vtkNew<vtkOpenGLRenderer> ren;
        ren->SetBackground(background);
        for (const auto& s : surfaces) {
            vtkNew<vtkPolyDataMapper> mapper;
            mapper->SetInputData(iso::to_polydata(iso::load_mesh(s.mesh), false));
            mapper->ScalarVisibilityOff();
            vtkNew<vtkActor> actor;
            actor->SetMapper(mapper);
            auto* p = actor->GetProperty();
            p->SetColor(s.color[0], s.color[1], s.color[2]);
            p->SetOpacity(s.opacity);
            p->SetAmbient(1.0);
            p->SetDiffuse(0.0);
            p->SetSpecular(0.0);
            p->BackfaceCullingOff();
            ren->AddActor(actor);
        }
        if (mode == "peel") {
            ren->SetUseDepthPeeling(true);
            ren->SetMaximumNumberOfPeels(peels);
            ren->SetOcclusionRatio(0.0);
        } else {
            ren->SetUseDepthPeeling(false);
            // VTK 9.1 draws translucent geometry with its weighted-blended
            // OIT pass (McGuire and Bavoil) whenever depth peeling is off.
        }
        vtkCamera* cam = ren->GetActiveCamera();
        cam->SetPosition(eye);
        cam->SetFocalPoint(target);
        cam->SetViewUp(up);
        cam->SetViewAngle(fov);
        vtkNew<vtkRenderWindow> win;
        win->SetMultiSamples(0);
        win->SetAlphaBitPlanes(1);
        win->SetSize(W, H);
        win->AddRenderer(ren);
        win->SetOffScreenRendering(1);
        using clock = std::chrono::steady_clock;
        std::vector<double> ms;
        for (int f = 0; f < warmup + frames; ++f) {
            cam->SetClippingRange(near_plane, far_plane);
            const auto t0 = clock::now();
            win->Render();
            win->WaitForCompletion();
            if (f >= warmup) ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
        }
        int* sz = win->GetSize();
        if (sz[0] != W || sz[1] != H) throw iso::Error("oit_peer", "window is " + std::to_string(sz[0]) + "x" + std::to_string(sz[1]));
        vtkNew<vtkUnsignedCharArray> rgb;
        win->GetPixelData(0, 0, W - 1, H - 1, 0, rgb, 0);
        iso::Image img;
        img.width = W;
        img.height = H;
        img.channels = 4;
        img.bytes.resize(std::size_t(W) * std::size_t(H) * 4);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const std::size_t src = (std::size_t(y) * std::size_t(W) + std::size_t(x)) * 3; // bottom-up
                const std::size_t dst = (std::size_t(H - 1 - y) * std::size_t(W) + std::size_t(x)) * 4;
                for (int c = 0; c < 3; ++c) img.bytes[dst + std::size_t(c)] = rgb->GetValue(vtkIdType(src + std::size_t(c)));
                img.bytes[dst + 3] = 255;
            }
        iso::save_image(img, out);
        const std::string renderer = iso::vtk_peer::renderer_name(win);
        std::printf("{\"ms_median\": %.4f, \"ms_p25\": %.4f, \"ms_p75\": %.4f, \"renderer\": \"%s\", \"mode\": \"%s\", \"peels\": %d}\n",
                    quantile(ms, 0.5), quantile(ms, 0.25), quantile(ms, 0.75), renderer.c_str(), mode.c_str(), peels);
    } catch (const std::exception& e) {
        std::cerr << "oit_peer: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
