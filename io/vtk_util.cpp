#include "io/vtk_util.hpp"

#include <cctype>
#include <mutex>

#include <vtkLogger.h>
#include <vtkOutputWindow.h>

namespace iso {

namespace {
// Keeps every VTK message off stderr; the readers turn them into iso::Error.
class SilentOutputWindow : public vtkOutputWindow {
public:
    static SilentOutputWindow* New() { return new SilentOutputWindow; }
    void DisplayText(const char*) override {}
};
} // namespace

void quiet_vtk() {
    static std::once_flag once;
    std::call_once(once, [] {
        auto* w = SilentOutputWindow::New();
        vtkOutputWindow::SetInstance(w);
        w->Delete();
        // Some classes (vtk-dicom's among them) also log through vtkLogger.
        vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    });
}

void VtkMessages::Execute(vtkObject*, unsigned long event, void* data) {
    const char* text = static_cast<const char*>(data);
    std::string& target = event == vtkCommand::ErrorEvent ? errors : warnings;
    if (text) target += std::string(text) + "\n";
    if (text && event == vtkCommand::ErrorEvent) error_list.emplace_back(text);
}

void VtkMessages::watch(vtkObject* o) {
    o->AddObserver(vtkCommand::ErrorEvent, this);
    o->AddObserver(vtkCommand::WarningEvent, this);
}

std::string VtkMessages::first_error() const {
    // VTK's text: "ERROR: In <file>, line <n>\n<class> (<address>): <message>\n\n".
    const auto p = errors.find("): ");
    std::string e = p == std::string::npos ? errors : errors.substr(p + 3);
    e = e.substr(0, e.find('\n'));
    return e.empty() ? "unknown VTK error" : e;
}

std::string VtkMessages::joined_errors() const {
    std::string out;
    for (std::string m : error_list) {
        if (const auto p = m.rfind("): "); p != std::string::npos) m = m.substr(p + 3);
        while (!m.empty() && std::isspace(static_cast<unsigned char>(m.back()))) m.pop_back();
        out += (out.empty() ? "" : "; ") + m;
    }
    return out;
}

} // namespace iso
