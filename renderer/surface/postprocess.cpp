#include "renderer/surface/postprocess.hpp"

#include "io/error.hpp"
#include "io/vtk_mesh.hpp"
#include "renderer/surface/analysis.hpp"
#include "renderer/surface/closest.hpp"

#include <cmath>

#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkPolyDataNormals.h>
#include <vtkQuadricDecimation.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkWindowedSincPolyDataFilter.h>

namespace iso {

bool needs_postprocess(const PostProcessOptions& o) {
    return o.smooth > 0.0 || o.decimate > 0.0 || o.keep_largest || o.keep_at.has_value() || o.keep_within.has_value() ||
           !o.steps.empty();
}

bool keeps_a_part(const PostProcessOptions& o) {
    return o.keep_largest || o.keep_at.has_value() || o.keep_within.has_value() || !o.steps.empty();
}

std::optional<glm::dvec3> kept_at(const PostProcessOptions& o) {
    for (auto s = o.steps.rbegin(); s != o.steps.rend(); ++s)
        if (s->keep_at) return s->keep_at;
    return o.keep_at;
}

Mesh apply_steps(const Mesh& m, const std::vector<PartStep>& steps) {
    for (const PartStep& s : steps)
        if (s.keep_at && !(std::isfinite(s.keep_at->x) && std::isfinite(s.keep_at->y) && std::isfinite(s.keep_at->z)))
            throw Error("component point", "the point is not finite");
    Mesh out = m;
    for (const PartStep& s : steps) {
        if (s.within && !out.empty()) out = clip_to_box(out, *s.within);
        if (s.keep_at && !out.empty()) out = component_at(out, *s.keep_at);
        if (s.outline) out = scissors_cut(out, *s.outline).part; // checks the outline, empty or not
    }
    return out;
}

Mesh component_at(const Mesh& m, const glm::dvec3& at) {
    if (m.empty()) return m;
    const NearestComponent c = nearest_component(m, at);
    return component_mesh(m, c.triangle_component, c.component);
}

namespace {

// Everything but the steps.
Mesh postprocess_body(const Mesh& in, const PostProcessOptions& o, const ProgressFn& progress) {
    if (!(o.smooth >= 0.0 && o.smooth <= 1.0)) throw Error("smoothing factor", "must be between 0 and 1");
    if (!(o.decimate >= 0.0 && o.decimate < 1.0)) throw Error("decimation fraction", "must be at least 0 and below 1");
    if (o.keep_at && !(std::isfinite(o.keep_at->x) && std::isfinite(o.keep_at->y) && std::isfinite(o.keep_at->z)))
        throw Error("component point", "the point is not finite");
    if (!needs_postprocess(o) || in.empty()) return in;
    int step = 0;
    const int steps = (o.keep_at ? 1 : 0) + (o.keep_within ? 1 : 0) + (o.keep_largest ? 1 : 0) +
                      (o.smooth > 0 ? 1 : 0) + (o.decimate > 0 ? 1 : 0) + 1;
    auto next = [&](const char* stage) { report(progress, double(step++) / steps, stage, "postprocess"); };
    Mesh kept;
    const bool keeps = o.keep_at || o.keep_within;
    if (o.keep_at) {
        next("keeping the component at a point");
        kept = component_at(in, *o.keep_at);
    }
    if (o.keep_within) {
        next("cutting it at the box");
        kept = clip_to_box(o.keep_at ? kept : in, *o.keep_within);
        // The cut may leave pieces of the component apart: the one at the point.
        if (o.keep_at) kept = component_at(kept, *o.keep_at);
    }
    // Nothing else asked: the part as extracted (its normals, its exact triangles).
    if (keeps && !o.keep_largest && !(o.smooth > 0) && !(o.decimate > 0)) {
        report(progress, 1.0, "done", "postprocess");
        return kept;
    }
    vtkSmartPointer<vtkPolyData> pd = to_polydata(keeps ? kept : in, false);

    if (o.keep_largest) {
        next("keeping the largest component");
        vtkNew<vtkPolyDataConnectivityFilter> c;
        c->SetInputData(pd);
        c->SetExtractionModeToLargestRegion();
        c->Update();
        // The filter keeps every point; drop the unused ones with a clean pass.
        pd = vtkSmartPointer<vtkPolyData>::New();
        pd->ShallowCopy(c->GetOutput());
        pd->RemoveDeletedCells();
        Mesh compact = from_polydata(pd, "postprocess");
        std::vector<std::uint32_t> remap(compact.positions.size(), 0xFFFFFFFFu);
        Mesh out;
        for (auto& t : compact.triangles)
            for (auto& v : t) {
                if (remap[v] == 0xFFFFFFFFu) {
                    remap[v] = std::uint32_t(out.positions.size());
                    out.positions.push_back(compact.positions[v]);
                }
                v = remap[v];
            }
        out.triangles = std::move(compact.triangles);
        pd = to_polydata(out, false);
    }
    if (o.smooth > 0.0) {
        next("smoothing");
        vtkNew<vtkWindowedSincPolyDataFilter> s;
        s->SetInputData(pd);
        s->SetNumberOfIterations(20);
        s->SetPassBand(std::pow(10.0, -4.0 * o.smooth));
        s->BoundarySmoothingOff();
        s->FeatureEdgeSmoothingOff();
        s->NonManifoldSmoothingOn();
        s->NormalizeCoordinatesOn();
        s->Update();
        pd = s->GetOutput();
    }
    if (o.decimate > 0.0) {
        next("decimating");
        vtkNew<vtkTriangleFilter> tri;
        tri->SetInputData(pd);
        vtkNew<vtkQuadricDecimation> d;
        d->SetInputConnection(tri->GetOutputPort());
        d->SetTargetReduction(o.decimate);
        d->VolumePreservationOn();
        d->Update();
        pd = d->GetOutput();
    }
    next("normals");
    vtkNew<vtkPolyDataNormals> n;
    n->SetInputData(pd);
    n->SplittingOff();
    n->ConsistencyOff(); // keep the extractor's outward orientation
    n->AutoOrientNormalsOff();
    n->ComputeCellNormalsOff();
    n->Update();
    Mesh out = from_polydata(n->GetOutput(), "postprocess");
    report(progress, 1.0, "done", "postprocess");
    return out;
}

} // namespace

Mesh postprocess(const Mesh& in, const PostProcessOptions& o, const ProgressFn& progress) {
    if (o.steps.empty()) return postprocess_body(in, o, progress);
    PostProcessOptions rest = o;
    rest.steps.clear();
    const ProgressFn first =
        progress ? ProgressFn([&progress](double f, std::string_view stage) { return progress(0.8 * f, stage); })
                 : ProgressFn();
    const Mesh body = postprocess_body(in, rest, first);
    report(progress, 0.8, "cutting the part", "postprocess");
    Mesh out = apply_steps(body, o.steps);
    report(progress, 1.0, "done", "postprocess");
    return out;
}

} // namespace iso
