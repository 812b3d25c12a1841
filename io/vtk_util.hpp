// Helpers for driving VTK readers and writers as library calls: VTK reports
// problems through its output window and error events instead of return
// values, so readers get an observer that collects the messages, and the
// output window is silenced once per process.
#pragma once

#include <string>
#include <vector>

#include <vtkCommand.h>
#include <vtkObject.h>

namespace iso {

// Routes VTK's global error/warning text away from stderr (call before use).
void quiet_vtk();

// Collects ErrorEvent and WarningEvent text of the objects it observes.
class VtkMessages : public vtkCommand {
public:
    static VtkMessages* New() { return new VtkMessages; }
    void Execute(vtkObject*, unsigned long event, void* data) override;
    void watch(vtkObject* o);
    bool has_error() const { return !errors.empty(); }
    // The first error, without VTK's "ERROR: In file, line N, vtkClass (0x...):" prefix.
    std::string first_error() const;
    // Every error, each without VTK's prefix, joined by "; ".
    std::string joined_errors() const;
    std::string errors, warnings;
    std::vector<std::string> error_list; // each error's text as VTK gave it
};

} // namespace iso
