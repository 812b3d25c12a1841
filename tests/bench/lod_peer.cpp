// The peer for the level-of-detail benchmark (lod_bench.cpp): VTK 9.1
// drawing the same mesh, camera and image size two ways a VTK user would:
//  - vtkPolyDataMapper with every triangle (what a render window does);
//  - vtkQuadricClustering, the decimation ParaView's LOD uses while the user
//    interacts (its "LOD resolution" is the number of divisions per axis),
//    timed for its build and its frames.
// It writes both images (full.png, lod.png: vtkWindowToImageFilter, RGB)
// and both depth buffers (full.depth, lod.depth: raw float32, GL's 0..1,
// rows bottom-up) into --out, so that the benchmark measures VTK's LOD
// against VTK's own full image, as it measures ours against ours. VTK renders
// through X here: run under xvfb-run.
//
//   lod_peer --mesh a.ply --eye X,Y,Z --target X,Y,Z --up X,Y,Z --fov DEG --near MM --far MM --size WxH
//            --background R,G,B --out DIR [--divisions 128,256] [--frames 5] [--warmup 1]
// Prints one JSON line.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkQuadricClustering.h>
#include <vtkWindowToImageFilter.h>

#include "tests/bench/vtk_peer.hpp"

using namespace iso;

namespace {

void save(vtk_peer::View& v, const std::string& dir, const std::string& name) {
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(v.win);
    grab->SetInputBufferTypeToRGB();
    grab->ReadFrontBufferOff();
    grab->Update();
    vtkNew<vtkPNGWriter> w;
    w->SetInputConnection(grab->GetOutputPort());
    w->SetFileName((dir + "/" + name + ".png").c_str());
    w->Write();
    vtkNew<vtkWindowToImageFilter> z;
    z->SetInput(v.win);
    z->SetInputBufferTypeToZBuffer();
    z->ReadFrontBufferOff();
    z->Update();
    auto* a = vtkFloatArray::SafeDownCast(z->GetOutput()->GetPointData()->GetScalars());
    std::ofstream f(dir + "/" + name + ".depth", std::ios::binary);
    if (a) f.write(reinterpret_cast<const char*>(a->GetPointer(0)), std::streamsize(a->GetNumberOfValues() * 4));
}

} // namespace

int main(int argc, char** argv) {
    vtk_peer::Scene sc;
    std::string out = ".";
    std::vector<int> divisions{128, 256};
    int frames = 5, warmup = 1;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        bool ok = true;
        if (sc.option(a, v, ok)) {
            if (!ok) return std::fprintf(stderr, "lod_peer: bad %s '%s'\n", a.c_str(), v.c_str()), 2;
        } else if (a == "--out") {
            out = v;
        } else if (a == "--divisions") {
            divisions.clear();
            for (std::size_t p = 0; p != std::string::npos;) {
                const auto q = v.find(',', p);
                divisions.push_back(std::stoi(v.substr(p, q == std::string::npos ? q : q - p)));
                p = q == std::string::npos ? q : q + 1;
            }
        } else if (a == "--frames") {
            frames = std::stoi(v);
        } else if (a == "--warmup") {
            warmup = std::stoi(v);
        } else {
            return std::fprintf(stderr, "lod_peer: unknown option %s\n", a.c_str()), 2;
        }
    }
    try {
        auto view = vtk_peer::make_view(sc);
        nlohmann::json j;
        const auto full = vtk_peer::timed_frames(*view, sc, warmup, frames, "lod_peer");
        j["renderer"] = vtk_peer::renderer_name(view->win);
        j["full_ms"] = vtk_peer::quantile(full);
        j["full_triangles"] = view->data[0]->GetNumberOfCells();
        save(*view, out, "full");
        for (int d : divisions) {
            const auto t0 = std::chrono::steady_clock::now();
            vtkNew<vtkQuadricClustering> qc;
            qc->SetInputData(view->data[0]);
            qc->SetNumberOfDivisions(d, d, d);
            qc->AutoAdjustNumberOfDivisionsOff();
            qc->Update();
            const double build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            auto* mapper = vtkPolyDataMapper::SafeDownCast(view->actors[0]->GetMapper());
            mapper->SetInputData(qc->GetOutput());
            const auto lod = vtk_peer::timed_frames(*view, sc, warmup, frames, "lod_peer");
            save(*view, out, "lod" + std::to_string(d));
            j["lod"].push_back({{"divisions", d},
                                {"build_s", build},
                                {"triangles", qc->GetOutput()->GetNumberOfCells()},
                                {"ms", vtk_peer::quantile(lod)}});
        }
        std::cout << j.dump() << "\n";
    } catch (const std::exception& e) {
        std::fprintf(stderr, "lod_peer: %s\n", e.what());
        return 1;
    }
    return 0;
}
