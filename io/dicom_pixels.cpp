#include "io/dicom_pixels.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <sstream>

#include <ext/stdio_filebuf.h> // std::ostream over the pipe to the reading program (libstdc++)
#include <unistd.h>

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkDICOMReader.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>

#include "io/child_process.hpp"
#include "io/error.hpp"
#include "io/vtk_util.hpp"

namespace iso {

bool dicom_is_native(const std::string& ts) {
    // vtkDICOMReader::ReadOneFile's list, less RLE (its decoder trusts the
    // segment header it reads from the file).
    return ts.empty() || ts == "1.2.840.10008.1.2" || ts == "1.2.840.10008.1.20" || ts == "1.2.840.10008.1.2.1" ||
           ts == "1.2.840.10008.1.2.2" || ts == "1.2.840.113619.5.2";
}

namespace {

constexpr const char* kChildFlag = "--isoscope-dicom-decoder";

struct ReadOutcome {
    vtkSmartPointer<vtkDICOMReader> reader; // owns the data
    std::string error;                      // what vtk-dicom (or GDCM) said went wrong
    bool cancelled = false;
};

// vtkDICOMReader over the files in this order; `on_progress` gets each
// progress event's fraction and returns false to stop.
ReadOutcome run_vtk_dicom(const std::vector<std::string>& files, const std::function<bool(double)>& on_progress) {
    vtkNew<vtkStringArray> names;
    for (const auto& f : files) names->InsertNextValue(f);
    ReadOutcome out;
    out.reader = vtkSmartPointer<vtkDICOMReader>::New();
    vtkDICOMReader* reader = out.reader;
    vtkNew<VtkMessages> msgs;
    msgs->watch(reader);
    reader->SetFileNames(names);
    reader->SortingOff();
    reader->SetMemoryRowOrderToFileNative();
    reader->AutoRescaleOff();
    struct Ctx {
        const std::function<bool(double)>* fn;
        ReadOutcome* out;
    } ctx{&on_progress, &out};
    vtkNew<vtkCallbackCommand> cb;
    cb->SetClientData(&ctx);
    cb->SetCallback([](vtkObject*, unsigned long, void* client, void* call) {
        auto* c = static_cast<Ctx*>(client);
        if (!(*c->fn)(call ? *static_cast<double*>(call) : 0.0)) {
            c->out->cancelled = true;
            c->out->reader->AbortExecuteOn();
        }
    });
    if (on_progress) reader->AddObserver(vtkCommand::ProgressEvent, cb);
    reader->Update();
    reader->RemoveAllObservers(); // they point at this function's locals; the reader lives on with the data
    if (reader->GetErrorCode() != 0 || msgs->has_error()) out.error = msgs->joined_errors();
    return out;
}

DecodedPixels from_reader(vtkDICOMReader* reader) {
    DecodedPixels px;
    vtkImageData* img = reader->GetOutput();
    img->GetDimensions(px.dims);
    px.array = img->GetPointData() ? img->GetPointData()->GetScalars() : nullptr;
    px.components = px.array ? px.array->GetNumberOfComponents() : 0;
    if (vtkIntArray* fidx = reader->GetFileIndexArray(); fidx && fidx->GetNumberOfTuples() == px.dims[2])
        for (vtkIdType k = 0; k < px.dims[2]; ++k) px.file_index.push_back(int(fidx->GetComponent(k, 0)));
    return px;
}

// ---- in the child ------------------------------------------------------------
// Frames on kChildOutFd: 'P' and a double (progress, 0..1), then 'D' and the
// image: dims, VTK type, components, the file index count and indices (all
// int32), the byte count (uint64) and the bytes.

int child_main(char** argv) {
    child_begin(argv);
    std::vector<std::string> files;
    std::istringstream list(read_fd(STDIN_FILENO));
    for (std::string f; std::getline(list, f);) files.push_back(f);
    __gnu_cxx::stdio_filebuf<char> buf(kChildOutFd, std::ios::out, 1 << 16);
    std::ostream os(&buf);
    const ReadOutcome r = run_vtk_dicom(files, [&](double f) {
        os.put('P');
        child_put(os, f);
        os.flush();
        return bool(os);
    });
    if (!r.error.empty()) {
        child_write(kChildStatusFd, "cannot read the pixel data: " + r.error);
        return 2;
    }
    const DecodedPixels px = from_reader(r.reader);
    if (!px.array) {
        child_write(kChildStatusFd, "cannot read the pixel data: the decoder gave no image");
        return 2;
    }
    os.put('D');
    for (int d : px.dims) child_put<std::int32_t>(os, d);
    child_put<std::int32_t>(os, px.array->GetDataType());
    child_put<std::int32_t>(os, px.components);
    child_put<std::int32_t>(os, std::int32_t(px.file_index.size()));
    for (int i : px.file_index) child_put<std::int32_t>(os, i);
    const std::uint64_t bytes =
        std::uint64_t(px.array->GetNumberOfValues()) * std::uint64_t(px.array->GetDataTypeSize());
    child_put(os, bytes);
    os.write(static_cast<const char*>(px.array->GetVoidPointer(0)), std::streamsize(bytes));
    os.flush();
    if (!os) return 3;
    child_write(kChildStatusFd, "ok\n");
    return 0;
}

__attribute__((constructor)) void child_entry(int argc, char** argv, char**) {
    if (is_child(argc, argv, kChildFlag)) ::_exit(child_main(argv)); // no exit handlers of a program that never started
}

// ---- in the reading program ------------------------------------------------------

// Reads the child's frames (see child_main) into `px`, reporting progress.
void receive(std::istream& is, DecodedPixels& px, const std::function<void(double)>& progress) {
    for (int c; (c = is.get()) != EOF;) {
        if (c == 'P') {
            progress(child_get<double>(is, "the decoder"));
            continue;
        }
        if (c != 'D') throw std::runtime_error("the decoder's output is garbled");
        for (int& d : px.dims) d = child_get<std::int32_t>(is, "the decoder");
        const int type = child_get<std::int32_t>(is, "the decoder");
        px.components = child_get<std::int32_t>(is, "the decoder");
        const int n = child_get<std::int32_t>(is, "the decoder");
        if (n < 0 || n > px.dims[2]) throw std::runtime_error("the decoder's output is garbled");
        for (int k = 0; k < n; ++k) px.file_index.push_back(child_get<std::int32_t>(is, "the decoder"));
        const auto bytes = child_get<std::uint64_t>(is, "the decoder");
        px.array = vtkSmartPointer<vtkDataArray>::Take(vtkDataArray::CreateDataArray(type));
        if (!px.array || px.components < 1 || px.dims[0] < 0 || px.dims[1] < 0 || px.dims[2] < 0)
            throw std::runtime_error("the decoder's output is garbled");
        px.array->SetNumberOfComponents(px.components);
        px.array->SetNumberOfTuples(vtkIdType(px.dims[0]) * px.dims[1] * px.dims[2]);
        if (bytes != std::uint64_t(px.array->GetNumberOfValues()) * std::uint64_t(px.array->GetDataTypeSize()))
            throw std::runtime_error("the decoder's output has the wrong size");
        is.read(static_cast<char*>(px.array->GetVoidPointer(0)), std::streamsize(bytes));
        if (std::uint64_t(is.gcount()) != bytes) throw std::runtime_error("the decoder's output ended early");
    }
    if (!px.array) throw std::runtime_error("the decoder gave no image");
}

// GDCM's messages ("Warning: In <file>, line <n>, function <f>" then the
// text, then a blank line; other lines are messages of their own), each
// distinct text once with its count, as warnings naming `where`.
std::vector<std::string> decoder_notes(const std::string& err, const std::string& where) {
    std::vector<std::pair<std::string, int>> seen;
    std::istringstream in(err);
    std::string line, text;
    auto flush = [&] {
        while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
        if (text.empty()) return;
        auto it = std::find_if(seen.begin(), seen.end(), [&](const auto& s) { return s.first == text; });
        if (it == seen.end())
            seen.emplace_back(text, 1);
        else
            ++it->second;
        text.clear();
    };
    bool in_block = false;
    while (std::getline(in, line)) {
        if (line.rfind("Warning: In ", 0) == 0 || line.rfind("Error: In ", 0) == 0) {
            flush();
            in_block = true;
        } else if (line.empty()) {
            flush();
            in_block = false;
        } else {
            text += (text.empty() ? "" : " ") + line;
            if (!in_block) flush();
        }
    }
    flush();
    std::vector<std::string> notes;
    for (std::size_t i = 0; i < seen.size() && i < 5; ++i)
        notes.push_back("the DICOM decoder (GDCM) said " +
                        (seen[i].second == 1 ? std::string("once") : std::to_string(seen[i].second) + " times") +
                        " while decoding " + where + ": " + seen[i].first);
    if (seen.size() > 5) notes.push_back("... and " + std::to_string(seen.size() - 5) + " other messages of GDCM");
    return notes;
}

DecodedPixels decode_in_child(const std::vector<std::string>& files, const std::string& where,
                              const std::function<void(double)>& progress) {
    ChildJob job;
    job.flag = kChildFlag;
    job.path = where;
    for (const auto& f : files) {
        if (f.find('\n') != std::string::npos) throw Error(f, "a file name with a line break cannot be decoded");
        job.input += f + "\n";
    }
    job.memory_cap = default_child_memory_cap("ISOSCOPE_DICOM_DECODE_MEMORY");
    job.reader = "the DICOM decoder";
    job.memory_env = "ISOSCOPE_DICOM_DECODE_MEMORY";
    job.timeout_env = "ISOSCOPE_DICOM_DECODE_TIMEOUT";
    job.timeout_s = unsigned(60 + 2 * files.size()); // a slow decoder on a large series, not a hang
    DecodedPixels px;
    std::string said;
    run_child(
        job, [&](std::istream& is) { receive(is, px, progress); }, &said);
    px.notes = decoder_notes(said, where);
    return px;
}

} // namespace

DecodedPixels decode_dicom_pixels(const std::vector<std::string>& files, bool isolate, const std::string& where,
                                  const ProgressFn& progress, double from, double to, const char* stage) {
    const auto at = [&](double f) { return from + (to - from) * f; };
    if (isolate) return decode_in_child(files, where, [&](double f) { report(progress, at(f), stage, where.c_str()); });
    const ReadOutcome r =
        run_vtk_dicom(files, progress ? std::function<bool(double)>([&](double f) { return progress(at(f), stage); })
                                      : std::function<bool(double)>());
    if (r.cancelled) throw Cancelled(where);
    if (!r.error.empty() || r.reader->GetErrorCode() != 0)
        throw Error(where, "cannot read the pixel data" + (r.error.empty() ? "" : ": " + r.error));
    DecodedPixels px = from_reader(r.reader);
    if (!px.array) throw Error(where, "cannot read the pixel data: the reader gave no image");
    return px;
}

} // namespace iso
