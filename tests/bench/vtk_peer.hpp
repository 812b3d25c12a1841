// What the VTK peer programs of the benchmarks (ssao_peer, oit_peer,
// pick_peer) share: quantiles of frame times, "X,Y,Z" arguments, the GL
// renderer's name, and (oit_peer, pick_peer) the scene they are given on
// the command line, its window and its timed frames.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderer.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>

#include "io/error.hpp"
#include "io/mesh.hpp"
#include "io/vtk_mesh.hpp"

namespace iso::vtk_peer {

inline double quantile(std::vector<double> v, double q = 0.5) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

inline bool vec3(const std::string& s, double out[3]) {
    return std::sscanf(s.c_str(), "%lf,%lf,%lf", &out[0], &out[1], &out[2]) == 3;
}

// "OpenGL renderer string" of the window's context, or "unknown".
inline std::string renderer_name(vtkRenderWindow* win) {
    const char* caps = win->ReportCapabilities();
    if (!caps) return "unknown";
    const std::string c = caps;
    const auto p = c.find("OpenGL renderer string:");
    if (p == std::string::npos) return "unknown";
    std::string r = c.substr(p + 23, c.find('\n', p) - p - 23);
    r.erase(0, r.find_first_not_of(' '));
    return r;
}

// The scene a peer draws: meshes with their colour and opacity, the camera,
// the background and the image size, as the benchmark passes them.
struct Scene {
    struct Surface {
        std::string mesh;
        double color[3] = {1, 1, 1};
        double opacity = 1;
    };
    std::vector<Surface> surfaces;
    double eye[3] = {0, 0, 0}, target[3] = {0, 0, 0}, up[3] = {0, 0, 1}, background[3] = {0, 0, 0};
    double fov = 30, near_plane = 1, far_plane = 1000;
    int W = 512, H = 512;

    // Takes option `a` with value `v` if it is one of the scene's (--mesh,
    // --color, --opacity for the last mesh, --eye, --target, --up,
    // --background, --fov, --near, --far, --size WxH): true, and `ok` says
    // whether the value was good.
    bool option(const std::string& a, const std::string& v, bool& ok) {
        ok = true;
        if (a == "--mesh")
            surfaces.push_back({v});
        else if (a == "--color")
            ok = !surfaces.empty() && vec3(v, surfaces.back().color);
        else if (a == "--opacity")
            ok = !surfaces.empty() && (surfaces.back().opacity = std::stod(v), true);
        else if (a == "--eye")
            ok = vec3(v, eye);
        else if (a == "--target")
            ok = vec3(v, target);
        else if (a == "--up")
            ok = vec3(v, up);
        else if (a == "--background")
            ok = vec3(v, background);
        else if (a == "--fov")
            fov = std::stod(v);
        else if (a == "--near")
            near_plane = std::stod(v);
        else if (a == "--far")
            far_plane = std::stod(v);
        else if (a == "--size")
            ok = std::sscanf(v.c_str(), "%dx%d", &W, &H) == 2 && W > 0 && H > 0;
        else
            return false;
        return true;
    }
};

// The scene in an offscreen window: one actor per mesh (its colour and
// opacity), the camera, no multisampling (the selector's colour-coded ids
// break under it), alpha bit planes.
struct View {
    vtkNew<vtkOpenGLRenderer> ren;
    vtkNew<vtkRenderWindow> win;
    std::vector<vtkSmartPointer<vtkPolyData>> data;
    std::vector<vtkSmartPointer<vtkActor>> actors;
    vtkCamera* cam = nullptr;
};

inline std::unique_ptr<View> make_view(const Scene& sc) {
    auto v = std::make_unique<View>();
    v->ren->SetBackground(sc.background);
    for (const auto& s : sc.surfaces) {
        v->data.push_back(iso::to_polydata(iso::load_mesh(s.mesh), false));
        vtkNew<vtkPolyDataMapper> mapper;
        mapper->SetInputData(v->data.back());
        mapper->ScalarVisibilityOff();
        auto actor = vtkSmartPointer<vtkActor>::New();
        actor->SetMapper(mapper);
        actor->GetProperty()->SetColor(s.color[0], s.color[1], s.color[2]);
        actor->GetProperty()->SetOpacity(s.opacity);
        v->ren->AddActor(actor);
        v->actors.push_back(actor);
    }
    v->cam = v->ren->GetActiveCamera();
    v->cam->SetPosition(sc.eye);
    v->cam->SetFocalPoint(sc.target);
    v->cam->SetViewUp(sc.up);
    v->cam->SetViewAngle(sc.fov);
    v->win->SetMultiSamples(0);
    v->win->SetAlphaBitPlanes(1);
    v->win->SetSize(sc.W, sc.H);
    v->win->AddRenderer(v->ren);
    v->win->SetOffScreenRendering(1);
    return v;
}

// Renders warmup + frames frames (the scene's clipping range set each time,
// as VTK would reset it) and returns the last `frames` times in ms; throws
// iso::Error(who, ...) if the window did not get the scene's size.
inline std::vector<double> timed_frames(View& v, const Scene& sc, int warmup, int frames, const std::string& who) {
    using clock = std::chrono::steady_clock;
    std::vector<double> ms;
    for (int f = 0; f < warmup + frames; ++f) {
        v.cam->SetClippingRange(sc.near_plane, sc.far_plane);
        const auto t0 = clock::now();
        v.win->Render();
        v.win->WaitForCompletion();
        if (f >= warmup) ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
    }
    const int* sz = v.win->GetSize();
    if (sz[0] != sc.W || sz[1] != sc.H)
        throw iso::Error(who, "window is " + std::to_string(sz[0]) + "x" + std::to_string(sz[1]));
    return ms;
}

} // namespace iso::vtk_peer
