#include "io/dicom_capture.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <optional>

#include <vtkDICOMMetaData.h>
#include <vtkDICOMParser.h>
#include <vtkDICOMSCGenerator.h>
#include <vtkDICOMTag.h>
#include <vtkDICOMValue.h>
#include <vtkDICOMWriter.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include "io/atomic_file.hpp"
#include "io/dicom_structure.hpp"
#include "io/error.hpp"
#include "io/vtk_util.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

constexpr const char* kManufacturer = "isoscope";

// vtkDICOMSCGenerator, with the series and instance numbered as we say: the
// generator always makes a new SeriesInstanceUID and numbers instances from 1.
class CaptureGenerator : public vtkDICOMSCGenerator {
public:
    static CaptureGenerator* New() { return new CaptureGenerator; }
    vtkTypeMacro(CaptureGenerator, vtkDICOMSCGenerator);
    bool GenerateInstance(vtkInformation* info) override {
        if (!vtkDICOMSCGenerator::GenerateInstance(info)) return false;
        if (!series_uid.empty()) this->MetaData->Set(DC::SeriesInstanceUID, series_uid);
        this->MetaData->Set(DC::InstanceNumber, instance);
        return true;
    }
    std::string series_uid;
    int instance = 1;
};

// A file's header, parsed only after its structure was walked (the reader's rule).
vtkSmartPointer<vtkDICOMMetaData> read_header(const std::string& file) {
    check_dicom_structure(file);
    auto md = vtkSmartPointer<vtkDICOMMetaData>::New();
    vtkNew<vtkDICOMParser> parser;
    vtkNew<VtkMessages> msgs;
    msgs->watch(parser);
    parser->SetMetaData(md);
    parser->SetFileName(file.c_str());
    parser->Update();
    if (parser->GetErrorCode() != 0 || msgs->has_error())
        throw Error(file, "cannot read the DICOM header: " + msgs->joined_errors());
    return md;
}

// The patient and general study attributes of the source, text in UTF-8.
void copy_patient_and_study(vtkDICOMMetaData* from, vtkDICOMMetaData* to) {
    static const DC::EnumType text[] = {
        DC::PatientName, DC::PatientID,       DC::IssuerOfPatientID, DC::ReferringPhysicianName,
        DC::StudyID,     DC::AccessionNumber, DC::StudyDescription};
    static const DC::EnumType other[] = {DC::PatientBirthDate, DC::PatientSex,       DC::PatientAge, DC::PatientSize,
                                         DC::PatientWeight,    DC::StudyInstanceUID, DC::StudyDate,  DC::StudyTime};
    for (auto tag : text)
        if (from->Has(tag)) to->Set(tag, from->Get(tag).AsUTF8String());
    for (auto tag : other)
        if (from->Has(tag)) to->Set(tag, from->Get(tag));
}

std::string trimmed(const vtkDICOMValue& v) {
    std::string s = v.AsUTF8String();
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
    return s;
}

// An isoscope series already in the folder for this study (the one named
// when `want` is given), with the last instance number it holds.
struct Existing {
    std::string study_uid, series_uid;
    int series_number = 0, last_instance = 0;
    fs::file_time_type newest{};
};

std::optional<Existing> find_series(const std::string& dir, const std::string& study_uid,
                                    const std::string& study_description, const std::string& want) {
    std::vector<Existing> found;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        if (!e.is_regular_file() || e.path().extension() != ".dcm") continue;
        vtkSmartPointer<vtkDICOMMetaData> md;
        try {
            md = read_header(e.path().string());
        } catch (const Error&) {
            continue; // not ours to judge here
        }
        if (trimmed(md->Get(DC::SecondaryCaptureDeviceManufacturer)) != kManufacturer) continue;
        const std::string study = trimmed(md->Get(DC::StudyInstanceUID));
        if (study_uid.empty() ? trimmed(md->Get(DC::StudyDescription)) != study_description : study != study_uid)
            continue;
        const std::string series = trimmed(md->Get(DC::SeriesInstanceUID));
        if (!want.empty() && series != want) continue;
        auto it = std::find_if(found.begin(), found.end(), [&](const Existing& x) { return x.series_uid == series; });
        if (it == found.end())
            it = found.insert(found.end(), Existing{study, series, md->Get(DC::SeriesNumber).AsInt()});
        it->last_instance = std::max(it->last_instance, md->Get(DC::InstanceNumber).AsInt());
        it->newest = std::max(it->newest, e.last_write_time());
    }
    if (found.empty()) return std::nullopt;
    return *std::max_element(found.begin(), found.end(),
                             [](const Existing& a, const Existing& b) { return a.newest < b.newest; });
}

// DICOM date and time (DA, TM) of now, local time.
std::pair<std::string, std::string> now_da_tm() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    localtime_r(&t, &tm);
    char d[16], h[16];
    std::strftime(d, sizeof d, "%Y%m%d", &tm);
    std::strftime(h, sizeof h, "%H%M%S", &tm);
    return {d, h};
}

// The provenance the PNG carries, as "key: value" lines (the matrices as
// space-separated numbers), within Image Comments' 10240 characters.
std::string provenance_text(const ImageMetadata& meta) {
    std::string out;
    for (const auto& [k, v] : meta.text) out += k + ": " + v + "\n";
    for (const auto& [k, v] : meta.float_arrays) {
        out += k + ":";
        for (float f : v) out += " " + std::to_string(f);
        out += "\n";
    }
    if (out.size() > 10240) out = out.substr(0, 10237) + "...";
    return out;
}

std::string text_of(const ImageMetadata& meta, const std::string& key) {
    const auto it = meta.text.find(key);
    return it == meta.text.end() ? std::string() : it->second;
}

// The image as VTK's RGB pixels, first row at the top as stored; alpha
// composited over black.
vtkSmartPointer<vtkImageData> rgb_pixels(const Image& image, const std::string& where) {
    if (image.is_float || (image.channels != 3 && image.channels != 4) || image.width <= 0 || image.height <= 0 ||
        image.bytes.size() != std::size_t(image.width) * std::size_t(image.height) * std::size_t(image.channels))
        throw Error(where, "a DICOM Secondary Capture needs an 8-bit RGB or RGBA image");
    auto img = vtkSmartPointer<vtkImageData>::New();
    img->SetDimensions(image.width, image.height, 1);
    vtkNew<vtkUnsignedCharArray> px;
    px->SetNumberOfComponents(3);
    px->SetNumberOfTuples(vtkIdType(image.width) * image.height);
    unsigned char* dst = px->GetPointer(0);
    const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t* s = image.bytes.data() + i * std::size_t(image.channels);
        const unsigned a = image.channels == 4 ? s[3] : 255u;
        for (int c = 0; c < 3; ++c) dst[i * 3 + std::size_t(c)] = static_cast<unsigned char>((s[c] * a + 127) / 255);
    }
    img->GetPointData()->SetScalars(px);
    return img;
}

// A name in `dir` that no file has: isoscope-<series>-<instance>.dcm.
std::string free_name(const std::string& dir, int series, int instance) {
    for (int k = 0;; ++k) {
        char name[96];
        std::snprintf(name, sizeof name, "isoscope-%d-%04d%s.dcm", series, instance,
                      k ? ("-" + std::to_string(k)).c_str() : "");
        const fs::path p = fs::path(dir) / name;
        std::error_code ec;
        if (!fs::exists(p, ec)) return p.string();
    }
}

} // namespace

DicomCaptureResult write_dicom_capture(const Image& image, const ImageMetadata& meta, const Metadata& source,
                                       const std::string& dir, const DicomCaptureOptions& opt) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir, ec)) throw Error(dir, "cannot make the folder for the DICOM figure");
    auto img = rgb_pixels(image, dir);
    DicomCaptureResult r;
    auto md = vtkSmartPointer<vtkDICOMMetaData>::New();
    md->Set(DC::SpecificCharacterSet, "ISO_IR 192"); // UTF-8: names and paths as they are
    std::string study_description;
    r.source_study = source.format == "DICOM" && !source.reference_file.empty();
    if (r.source_study) {
        copy_patient_and_study(read_header(source.reference_file), md);
        r.study_uid = trimmed(md->Get(DC::StudyInstanceUID));
    } else {
        const std::string name = fs::path(source.source).filename().string();
        study_description =
            "isoscope figures of " + (name.empty() ? std::string("a volume") : name) + " (not from a DICOM study)";
        md->Set(DC::StudyDescription, study_description.substr(0, 64));
        if (!source.patient_name.empty()) md->Set(DC::PatientName, source.patient_name);
        if (!source.patient_id.empty()) md->Set(DC::PatientID, source.patient_id);
        study_description = study_description.substr(0, 64);
    }
    const auto [date, time] = now_da_tm();
    if (!r.source_study) {
        md->Set(DC::StudyDate, date);
        md->Set(DC::StudyTime, time);
    }
    // The series: the caller's, else the folder's for this study, else new.
    const auto existing = find_series(dir, r.study_uid, study_description, opt.series_uid);
    int series_number = 1;
    for (const auto& s : source.series) series_number = std::max(series_number, s.number + 1);
    if (existing) {
        r.series_uid = existing->series_uid;
        series_number = existing->series_number;
        if (!r.source_study) md->Set(DC::StudyInstanceUID, existing->study_uid);
    } else {
        r.series_uid = opt.series_uid; // empty: the generator makes one
    }
    r.new_series = !existing;
    r.instance_number = existing ? existing->last_instance + 1 : 1;
    r.series_number = series_number;
    md->Set(DC::SeriesNumber, series_number);
    md->Set(DC::SeriesDescription, opt.series_description);
    md->Set(DC::Modality, "OT");
    md->Set(DC::ImageType, "DERIVED\\SECONDARY");
    md->Set(DC::BurnedInAnnotation, "YES");
    md->Set(DC::ConversionType, "WSD"); // a workstation made it
    const std::string version =
        text_of(meta, "isoscope:version") + " (commit " + text_of(meta, "isoscope:commit") + ")";
    md->Set(DC::SecondaryCaptureDeviceManufacturer, kManufacturer);
    md->Set(DC::SecondaryCaptureDeviceSoftwareVersions, version.substr(0, 64));
    md->Set(DC::ContentDate, date);
    md->Set(DC::ContentTime, time);
    md->Set(DC::DateOfSecondaryCapture, date);
    md->Set(DC::TimeOfSecondaryCapture, time);
    const std::string derived =
        "3D rendering by isoscope " + version + " of " +
        (r.source_study ? "series " + source.series_uid : fs::path(source.source).filename().string()) +
        "; annotations burned in; provenance in Image Comments";
    md->Set(DC::DerivationDescription, derived.substr(0, 1024));
    md->Set(DC::ImageComments, provenance_text(meta));

    vtkNew<CaptureGenerator> gen;
    gen->series_uid = r.series_uid;
    gen->instance = r.instance_number;
    vtkNew<vtkDICOMWriter> writer;
    vtkNew<VtkMessages> msgs;
    msgs->watch(writer);
    writer->SetInputData(img);
    writer->SetMetaData(md);
    writer->SetGenerator(gen);
    writer->SetMemoryRowOrderToFileNative(); // our first row is the top
    writer->SetTransferSyntaxUID("1.2.840.10008.1.2.1");
    r.file = free_name(dir, series_number, r.instance_number);
    write_atomically(r.file, [&](const std::string& tmp) {
        writer->SetFileName(tmp.c_str());
        writer->Write();
        if (writer->GetErrorCode() != 0 || msgs->has_error())
            throw Error(r.file, "cannot write the DICOM figure: " + msgs->joined_errors());
    });
    // What was written, read back (the UIDs the generator made among it).
    const auto back = read_header(r.file);
    r.study_uid = trimmed(back->Get(DC::StudyInstanceUID));
    r.series_uid = trimmed(back->Get(DC::SeriesInstanceUID));
    r.sop_uid = trimmed(back->Get(DC::SOPInstanceUID));
    return r;
}

} // namespace iso
