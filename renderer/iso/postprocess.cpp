#include "renderer/iso/postprocess.hpp"

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

namespace {

vtkSmartPointer<vtkPolyData> to_vtk(const Mesh& m) {
    auto pd = vtkSmartPointer<vtkPolyData>::New();
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToFloat();
    pts->SetNumberOfPoints(vtkIdType(m.positions.size()));
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        pts->SetPoint(vtkIdType(i), m.positions[i].x, m.positions[i].y, m.positions[i].z);
    pd->SetPoints(pts);
    vtkNew<vtkCellArray> polys;
    polys->AllocateExact(vtkIdType(m.triangles.size()), vtkIdType(3 * m.triangles.size()));
    for (const auto& t : m.triangles) {
        const vtkIdType ids[3] = {t[0], t[1], t[2]};
        polys->InsertNextCell(3, ids);
    }
    pd->SetPolys(polys);
    return pd;
}

Mesh from_vtk(vtkPolyData* pd) {
    Mesh m;
    m.positions.resize(std::size_t(pd->GetNumberOfPoints()));
    for (vtkIdType i = 0; i < pd->GetNumberOfPoints(); ++i) {
        double p[3];
        pd->GetPoint(i, p);
        m.positions[std::size_t(i)] = glm::vec3(float(p[0]), float(p[1]), float(p[2]));
    }
    if (auto* n = pd->GetPointData()->GetNormals()) {
        m.normals.resize(m.positions.size());
        for (vtkIdType i = 0; i < n->GetNumberOfTuples(); ++i) {
            double v[3];
            n->GetTuple(i, v);
            m.normals[std::size_t(i)] = glm::vec3(float(v[0]), float(v[1]), float(v[2]));
        }
    }
    auto* polys = pd->GetPolys();
    m.triangles.reserve(std::size_t(polys->GetNumberOfCells()));
    vtkIdType npts;
    const vtkIdType* ids;
    for (polys->InitTraversal(); polys->GetNextCell(npts, ids);)
        if (npts == 3) m.triangles.push_back({std::uint32_t(ids[0]), std::uint32_t(ids[1]), std::uint32_t(ids[2])});
    return m;
}

} // namespace

bool needs_postprocess(const PostProcessOptions& o) { return o.smooth > 0.0 || o.decimate > 0.0 || o.keep_largest; }

Mesh postprocess(const Mesh& in, const PostProcessOptions& o, const ProgressFn& progress) {
    if (!(o.smooth >= 0.0 && o.smooth <= 1.0)) throw Error("--smooth", "must be between 0 and 1");
    if (!(o.decimate >= 0.0 && o.decimate < 1.0)) throw Error("--decimate", "must be at least 0 and below 1");
    if (!needs_postprocess(o) || in.empty()) return in;
    vtkSmartPointer<vtkPolyData> pd = to_vtk(in);
    int step = 0;
    const int steps = (o.keep_largest ? 1 : 0) + (o.smooth > 0 ? 1 : 0) + (o.decimate > 0 ? 1 : 0) + 1;
    auto next = [&](const char* stage) { report(progress, double(step++) / steps, stage, "postprocess"); };

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
        Mesh compact = from_vtk(pd);
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
        pd = to_vtk(out);
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
    n->ConsistencyOff();      // keep the extractor's outward orientation
    n->AutoOrientNormalsOff();
    n->ComputeCellNormalsOff();
    n->Update();
    Mesh out = from_vtk(n->GetOutput());
    report(progress, 1.0, "done", "postprocess");
    return out;
}

} // namespace iso
