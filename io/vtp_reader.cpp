// VTK XML PolyData (.vtp) read in a child process (io/child_process.hpp).
//
// VTK 9.1's XML parser trusts what a file says: the fuzzer found it writing
// through null pointers on compression headers (now checked first,
// io/vtp_check.cpp) and, with the headers valid, reading through a null block
// table when an array's type does not match its data (a one-byte mutation of
// our own writer's output). Checking every way the parser can go wrong would
// mean rewriting it; instead the headers are checked here (cheap refusals,
// and our check is what the fuzzer exercises) and VTK's reader runs in a
// child that hands back the mesh (positions, normals, colours, triangles,
// the SPACE tag, warnings) through a pipe. A crash, hang or runaway
// allocation in VTK is an iso::Error naming the file.
#include "io/vtp_reader.hpp"

#include <cstdint>
#include <cstring>
#include <istream>
#include <sstream>

#include <ext/stdio_filebuf.h> // std::ostream over the pipe to the reading program (libstdc++)
#include <unistd.h>

#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include "io/child_process.hpp"
#include "io/error.hpp"
#include "io/vtk_mesh.hpp"
#include "io/vtk_util.hpp"
#include "io/vtp_check.hpp"

namespace iso::detail {

namespace {

constexpr const char* kChildFlag = "--isoscope-vtp-reader";

template <class T> void put_all(std::ostream& os, const std::vector<T>& v) {
    child_put<std::uint64_t>(os, v.size());
    if (!v.empty()) os.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}
void put_text(std::ostream& os, const std::string& s) {
    child_put<std::uint64_t>(os, s.size());
    os.write(s.data(), std::streamsize(s.size()));
}

// ---- in the child ------------------------------------------------------------

// VTK's reader over the file (read_vtp checked its headers before starting
// this process), the mesh as from_polydata makes it.
Mesh read_with_vtk(const std::string& path, std::string& space) {
    quiet_vtk();
    vtkNew<vtkXMLPolyDataReader> r;
    r->SetFileName(path.c_str());
    vtkNew<VtkMessages> msgs;
    msgs->watch(r);
    r->Update();
    if (msgs->has_error()) throw Error(path, msgs->first_error());
    auto* pd = vtkPolyData::SafeDownCast(r->GetOutputDataObject(0));
    if (!pd) throw Error(path, "the reader produced no polygon data");
    if (auto* s = vtkStringArray::SafeDownCast(pd->GetFieldData()->GetAbstractArray("SPACE"));
        s && s->GetNumberOfValues() > 0)
        space = s->GetValue(0);
    return from_polydata(pd, path);
}

int child_main(char** argv) {
    child_begin(argv);
    const std::string path = read_fd(STDIN_FILENO);
    try {
        std::string space;
        const Mesh m = read_with_vtk(path, space);
        __gnu_cxx::stdio_filebuf<char> buf(kChildOutFd, std::ios::out, 1 << 16);
        std::ostream os(&buf);
        put_all(os, m.positions);
        put_all(os, m.normals);
        put_all(os, m.colors);
        put_all(os, m.triangles);
        put_text(os, space);
        child_put<std::uint64_t>(os, m.warnings.size());
        for (const auto& w : m.warnings) put_text(os, w);
        os.flush();
        if (!os) return 3;
    } catch (const Error& e) {
        child_write(kChildStatusFd, e.reason());
        return 2;
    } catch (const std::exception& e) {
        child_write(kChildStatusFd, e.what());
        return 2;
    }
    child_write(kChildStatusFd, "ok\n");
    return 0;
}

__attribute__((constructor)) void child_entry(int argc, char** argv, char**) {
    if (is_child(argc, argv, kChildFlag)) ::_exit(child_main(argv)); // no exit handlers of a program that never started
}

// ---- in the reading program ------------------------------------------------------

// A count the child sent, checked against what the file could hold.
std::uint64_t count(std::istream& is, std::uint64_t most) {
    const auto n = child_get<std::uint64_t>(is, "the reader");
    if (n > most) throw std::runtime_error("the reader's output is garbled");
    return n;
}

template <class T> void get_all(std::istream& is, std::vector<T>& v, std::uint64_t most) {
    v.resize(std::size_t(count(is, most)));
    if (!v.empty()) is.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
    if (!is) throw std::runtime_error("the reader's output ended early");
}

std::string get_text(std::istream& is) {
    std::string s(std::size_t(count(is, 1 << 20)), '\0');
    is.read(s.data(), std::streamsize(s.size()));
    if (!is) throw std::runtime_error("the reader's output ended early");
    return s;
}

} // namespace

Mesh read_vtp(const std::string& path, std::string& space, std::uint64_t file_size) {
    // Refused here when the headers are wrong: no process started for them.
    {
        quiet_vtk();
        vtkNew<vtkXMLPolyDataReader> r;
        if (!r->CanReadFile(path.c_str())) throw Error(path, "not a VTK XML PolyData file");
    }
    check_vtk_xml_headers(path);
    ChildJob job;
    job.flag = kChildFlag;
    job.path = path;
    job.input = path;
    job.memory_cap = default_child_memory_cap("ISOSCOPE_VTP_READ_MEMORY");
    job.reader = "VTK's XML PolyData reader";
    job.memory_env = "ISOSCOPE_VTP_READ_MEMORY";
    job.timeout_env = "ISOSCOPE_VTP_READ_TIMEOUT";
    // What the file can hold: compressed data inflate at most ~1032 times.
    const std::uint64_t most = (file_size + 1024) * 1100;
    Mesh m;
    run_child(job, [&](std::istream& is) {
        get_all(is, m.positions, most);
        get_all(is, m.normals, most);
        get_all(is, m.colors, most);
        get_all(is, m.triangles, most);
        space = get_text(is);
        const auto nw = count(is, 1000);
        for (std::uint64_t i = 0; i < nw; ++i) m.warnings.push_back(get_text(is));
    });
    if ((!m.normals.empty() && m.normals.size() != m.positions.size()) ||
        (!m.colors.empty() && m.colors.size() != m.positions.size()))
        throw Error(path, "the reader's output is inconsistent");
    return m;
}

} // namespace iso::detail
