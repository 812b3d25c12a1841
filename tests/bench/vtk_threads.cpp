// vtkSMPTools.h (VTK 9.1) does not compile as C++20 (a template-id used as a
// constructor name), so this one file is built as C++17 and keeps it away
// from the rest of the benchmark.
#include <vtkSMPTools.h>

namespace iso::bench {
void set_vtk_threads(int n) {
    vtkSMPTools::SetBackend("TBB");
    vtkSMPTools::Initialize(n);
}
} // namespace iso::bench
