// The unit of a volume's values and the readout of a value at a point
// (renderer/core/value_unit.hpp), on volumes read from files: HU for CT
// only (DICOM and MetaImage files that say CT), no unit for MR and for
// formats that do not say (NRRD, NIfTI, a MetaImage file without a
// modality); the readout's text; the unit in `isoscope measure`'s JSON.
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "io/volume_io.hpp"
#include "renderer/core/measure.hpp"
#include "renderer/core/scene.hpp"
#include "renderer/core/value_unit.hpp"
#include "tests/support/dicom_fixtures.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::SeriesSpec;
using iso::test::TempDir;
using iso::test::write_series;
namespace fs = std::filesystem;

namespace {

// headsq's samples under a MetaImage header that names `modality` ("" for
// no Modality line), in `dir`.
std::string headsq_metaimage(const TempDir& dir, const std::string& name, const std::string& modality) {
    fs::copy_file(test::data("headsq.raw"), dir / "headsq.raw", fs::copy_options::skip_existing);
    std::string header = test::read_file(test::data("headsq.mhd"));
    if (!modality.empty()) header = "Modality = " + modality + "\n" + header;
    test::write_file(dir / name, header);
    return dir / name;
}

} // namespace

TEST(ValueUnit, HounsfieldForCtOnly) {
    TempDir dir;
    SeriesSpec ct; // vtkDICOMCTGenerator: Modality CT, rescaled to HU
    write_series(dir / "ct", ct);
    SeriesSpec mr;
    mr.ct = false;
    write_series(dir / "mr", mr);
    const Volume ct_dicom = load_volume(dir / "ct");
    ASSERT_EQ(ct_dicom.meta.modality, "CT");
    EXPECT_EQ(core::value_unit(ct_dicom), "HU");
    const Volume mr_dicom = load_volume(dir / "mr");
    ASSERT_EQ(mr_dicom.meta.modality, "MR");
    EXPECT_EQ(core::value_unit(mr_dicom), "");
    const Volume forearm = load_volume(test::data("dicom-mr-forearm"));
    ASSERT_EQ(forearm.meta.modality, "MR");
    EXPECT_EQ(core::value_unit(forearm), "");

    // The bundled head CT says nothing about its modality (and is not in HU):
    // neither its NRRD nor its MetaImage header.
    EXPECT_EQ(core::value_unit(load_volume(test::data("headsq.nhdr"))), "");
    EXPECT_EQ(core::value_unit(load_volume(test::data("headsq.mhd"))), "");
    EXPECT_EQ(core::value_unit(load_volume(test::data("HeadMRVolume.mhd"))), "");
    // The same samples under a MetaImage header that says CT, or MR.
    const Volume said_ct = load_volume(headsq_metaimage(dir, "ct.mhd", "MET_MOD_CT"));
    ASSERT_EQ(said_ct.meta.modality, "CT");
    EXPECT_EQ(core::value_unit(said_ct), "HU");
    EXPECT_EQ(core::value_unit(load_volume(headsq_metaimage(dir, "mr.mhd", "MET_MOD_MR"))), "");

    // NIfTI does not carry a modality: the CT written as NIfTI has no unit.
    save_volume(ct_dicom, dir / "ct.nii.gz");
    const Volume nifti = load_volume(dir / "ct.nii.gz");
    EXPECT_EQ(nifti.meta.modality, "");
    EXPECT_EQ(core::value_unit(nifti), "");

    // A scene: its volume's unit; none without a volume.
    core::Scene scene;
    EXPECT_EQ(core::value_unit(scene), "");
    scene.open(dir / "ct");
    EXPECT_EQ(core::value_unit(scene), "HU");
    scene.open(test::data("headsq.nhdr"));
    EXPECT_EQ(core::value_unit(scene), "");
}

TEST(ValueUnit, ReadoutText) {
    EXPECT_EQ(core::value_readout(1234.5, "HU"), "1234.50 HU");
    EXPECT_EQ(core::value_readout(1234.5, ""), "value 1234.50");
    EXPECT_EQ(core::value_readout(-1000.004, "HU"), "-1000.00 HU");
    EXPECT_EQ(core::value_readout(0.125, "", 1), "value 0.1");
    EXPECT_EQ(core::value_readout(7, "HU", 0), "7 HU");
    EXPECT_EQ(core::value_readout(std::nan(""), "HU"), "value undefined");
    EXPECT_EQ(core::value_readout(std::numeric_limits<double>::infinity(), ""), "value undefined");
}

// `isoscope measure --json`'s values: "value" and "unit" ("HU" for CT, null
// otherwise and outside the volume), never a "hu" key.
TEST(ValueUnit, MeasureJsonNamesTheUnit) {
    TempDir dir;
    write_series(dir / "ct", SeriesSpec{});
    core::PointMeasurements points;
    core::Scene scene;
    scene.open(dir / "ct");
    const glm::dvec3 inside = glm::dvec3(scene.volume().index_to_lps * glm::dvec4(5, 4, 3, 1));
    points.values = {inside, glm::dvec3(1e4, 1e4, 1e4)};
    auto j = core::measure_json(scene, {}, points);
    ASSERT_EQ(j["values"].size(), 2u);
    EXPECT_NEAR(j["values"][0]["value"].get<double>(), test::pattern(5, 4, 3) - 1024.0, 1e-9);
    EXPECT_EQ(j["values"][0]["unit"], "HU");
    EXPECT_FALSE(j["values"][0].contains("hu"));
    EXPECT_TRUE(j["values"][1]["value"].is_null()) << "outside the volume";
    EXPECT_TRUE(j["values"][1]["unit"].is_null());

    scene.open(test::data("headsq.nhdr"));
    points.values = {glm::dvec3(-98.9, 20, -12)};
    j = core::measure_json(scene, {}, points);
    EXPECT_TRUE(j["values"][0]["value"].is_number());
    EXPECT_TRUE(j["values"][0]["unit"].is_null());
    EXPECT_FALSE(j["values"][0].contains("hu"));
}
