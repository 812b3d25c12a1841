#include "renderer/surface/box_clip.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include <glm/glm.hpp>
#include <vtkCellArray.h>
#include <vtkClipClosedSurface.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPlaneCollection.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <vtkTriangleFilter.h>

#include "io/error.hpp"
#include "io/vtk_mesh.hpp"

namespace iso {

namespace {

void check(const LpsBox& b, const std::string& what) {
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(b.lo[i]) || !std::isfinite(b.hi[i])) throw Error(what, "the box is not finite");
        if (!(b.lo[i] < b.hi[i])) throw Error(what, "the box is flat (its corners share a coordinate)");
    }
}

} // namespace

LpsBox parse_box(const std::string& what, const std::string& text) {
    std::vector<double> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        std::size_t used = 0;
        double x = 0;
        try {
            x = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos)
            throw Error(what, "expected six numbers x0,y0,z0,x1,y1,z1 (LPS mm), got '" + text + "'");
        v.push_back(x);
    }
    if (v.size() != 6) throw Error(what, "expected six numbers x0,y0,z0,x1,y1,z1 (LPS mm), got '" + text + "'");
    LpsBox b;
    for (int i = 0; i < 3; ++i) {
        b.lo[i] = std::min(v[std::size_t(i)], v[std::size_t(i) + 3]);
        b.hi[i] = std::max(v[std::size_t(i)], v[std::size_t(i) + 3]);
    }
    check(b, what);
    return b;
}

Mesh clip_to_box(const Mesh& m, const LpsBox& box) {
    check(box, "clip to a box");
    if (m.empty()) return m;
    bool all_in = true, any_in = false;
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const auto& p : m.positions) {
        const bool in = box.contains(glm::dvec3(p));
        all_in = all_in && in;
        any_in = any_in || in;
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    if (all_in) return m;
    // No corner inside can still cut (a box inside a large solid); no overlap of the bounds cannot.
    for (int i = 0; i < 3; ++i)
        if (hi[i] < box.lo[i] || lo[i] > box.hi[i]) return Mesh{};
    std::vector<HalfSpace> region;
    for (int face = 0; face < 6; ++face) {
        const int axis = face / 2;
        const bool upper = face % 2 == 1;
        HalfSpace h;
        h.origin = box.lo;
        if (upper) h.origin[axis] = box.hi[axis];
        h.normal = glm::dvec3(0.0);
        h.normal[axis] = upper ? -1.0 : 1.0; // inwards
        region.push_back(h);
    }
    return clip_closed(m, region);
}

Mesh clip_closed(const Mesh& m, const std::vector<HalfSpace>& region) {
    if (m.empty()) return m;
    vtkNew<vtkPlaneCollection> planes;
    for (const HalfSpace& h : region) {
        // vtkClipClosedSurface keeps what the planes' normals point to.
        vtkNew<vtkPlane> p;
        p->SetOrigin(h.origin.x, h.origin.y, h.origin.z);
        p->SetNormal(h.normal.x, h.normal.y, h.normal.z);
        planes->AddItem(p);
    }
    vtkNew<vtkClipClosedSurface> clip;
    clip->SetInputData(to_polydata(m, false));
    clip->SetClippingPlanes(planes);
    clip->SetGenerateFaces(1);
    clip->SetGenerateOutline(0);
    clip->SetScalarModeToNone();
    clip->TriangulationErrorDisplayOff();
    vtkNew<vtkTriangleFilter> tri;
    tri->SetInputConnection(clip->GetOutputPort());
    tri->PassLinesOff();
    tri->PassVertsOff();
    vtkNew<vtkPolyDataNormals> n;
    n->SetInputConnection(tri->GetOutputPort());
    n->SplittingOff(); // one vertex per point: the part stays closed by index
    n->ConsistencyOff();
    n->AutoOrientNormalsOff();
    n->ComputeCellNormalsOff();
    n->Update();
    return from_polydata(n->GetOutput(), "clip a closed surface");
}

std::array<double, 6> cap_areas(const Mesh& m, const LpsBox& box) {
    std::array<double, 6> area{};
    const double tol = 1e-5 * std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    for (const auto& t : m.triangles) {
        const glm::dvec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
        for (int face = 0; face < 6; ++face) {
            const int axis = face / 2;
            const double plane = face % 2 ? box.hi[axis] : box.lo[axis];
            if (std::abs(a[axis] - plane) <= tol && std::abs(b[axis] - plane) <= tol &&
                std::abs(c[axis] - plane) <= tol) {
                area[std::size_t(face)] += 0.5 * glm::length(glm::cross(b - a, c - a));
                break;
            }
        }
    }
    return area;
}

const char* box_face_name(int face) {
    static const char* kNames[] = {"right", "left", "anterior", "posterior", "inferior", "superior"};
    return face >= 0 && face < 6 ? kNames[face] : "?";
}

} // namespace iso
