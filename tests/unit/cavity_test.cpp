// A closed surface or component whose signed volume is negative is the wall
// of a cavity (iso::encloses_cavity; issue 39: the 512^3 phantom's largest
// component was printed as "volume -11426.8 mm^3"). Every front end reports
// it as the cavity it encloses and never as a negative volume: `isoscope
// mesh` in memory and streamed (its line and --json: volume_ml the cavity's,
// cavity true, for the surface and its largest component), `isoscope
// measure` (per surface, per component, --component-at).
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "io/volume_io.hpp"
#include "renderer/surface/analysis.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::TempDir;

namespace {

// An int16 volume, 1 mm voxels, whose value is 500 + 100 * field(p) (clamped
// to 0..1000) at each voxel's index p.
template <class F> void save_field(const std::string& path, F field) {
    const std::array<std::int64_t, 3> d{40, 40, 40};
    Volume v = Volume::dense(d, VoxelType::I16, make_affine(glm::dvec3(1.0), glm::dvec3(0.0), glm::dmat3(1.0)));
    auto s = v.as<std::int16_t>();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i)
                s[v.linear_index(i, j, k)] =
                    std::int16_t(std::clamp(500.0 + 100.0 * field(glm::dvec3(i, j, k)), 0.0, 1000.0));
    save_volume(v, path, false);
}

double ball_ml(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r / 1000.0; }

nlohmann::json run_json(const std::string& args) {
    const auto r = test::run_command(test::cli() + " " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return nlohmann::json::parse(r.out);
}

} // namespace

TEST(Cavity, TheRuleIsTheSignOfTheVolume) {
    EXPECT_TRUE(encloses_cavity(-1e-9));
    EXPECT_FALSE(encloses_cavity(0.0));
    EXPECT_FALSE(encloses_cavity(2.0));
    EXPECT_FALSE(encloses_cavity(std::nan(""))); // undefined: no cavity either
}

// A hole of radius 9.5 mm in material that fills the grid: the only surface
// is the hole's wall, closed, facing into the hole. `mesh` reports the hole,
// in memory and streamed alike, in its line and its JSON.
TEST(Cavity, AHoleInTheMaterialIsReportedAsTheCavityItEncloses) {
    TempDir dir;
    const std::string in = dir / "hole.nhdr";
    save_field(in, [](const glm::dvec3& p) { return glm::length(p - glm::dvec3(19.5, 20.0, 19.0)) - 9.5; });
    const double hole = ball_ml(9.5);
    for (const char* route : {"", " --stream --memory 0.3 --chunk 8"}) {
        SCOPED_TRACE(std::string("route:") + route);
        const auto j = run_json("mesh " + in + " --iso 500" + route + " -o " + (dir / "h.ply"));
        const auto& s = j["surfaces"][0];
        EXPECT_EQ(s["closed"], true);
        EXPECT_EQ(s["volume_kind"], "enclosed");
        EXPECT_EQ(s["cavity"], true);
        EXPECT_NEAR(s["volume_ml"].get<double>(), hole, 0.02 * hole) << "the hole's volume, positive";
        EXPECT_NEAR(s["volume_mm3"].get<double>(), 1000.0 * s["volume_ml"].get<double>(), 1e-9 * hole * 1000.0);
        EXPECT_EQ(s["components"]["count"], 1);
        EXPECT_EQ(s["components"]["largest"]["cavity"], true);
        EXPECT_NEAR(s["components"]["largest"]["volume_ml"].get<double>(), s["volume_ml"].get<double>(), 1e-9 * hole);
        const auto t = test::run_command(test::cli() + " mesh " + in + " --iso 500" + route + " -o " + (dir / "h.stl"));
        ASSERT_EQ(t.exit_code, 0) << t.out;
        EXPECT_NE(t.out.find("closed, encloses a cavity of "), std::string::npos) << t.out;
        EXPECT_NE(t.out.find("(largest: "), std::string::npos) << t.out;
        EXPECT_EQ(t.out.find("volume -"), std::string::npos) << "never a negative volume: " << t.out;
    }
}

// A hollow ball (material between radii 5.5 and 12.5): two closed
// components, the outer wall a solid of +V_out, the inner wall a cavity of
// V_in. The surface's volume is the material's (V_out - V_in, no cavity);
// `measure` lists the inner wall as a cavity, and --component-at on it says so.
TEST(Cavity, AHollowBallsInnerWallIsACavityAndItsMaterialIsTheSurfacesVolume) {
    TempDir dir;
    const std::string in = dir / "hollow.nhdr";
    const glm::dvec3 c(19.5, 20.0, 19.0);
    save_field(in, [&](const glm::dvec3& p) {
        const double r = glm::length(p - c);
        return std::min(12.5 - r, r - 5.5);
    });
    const double outer = ball_ml(12.5), inner = ball_ml(5.5);
    const auto m = run_json("mesh " + in + " --iso 500 -o " + (dir / "b.stl"));
    const auto& s = m["surfaces"][0];
    EXPECT_EQ(s["cavity"], false);
    EXPECT_NEAR(s["volume_ml"].get<double>(), outer - inner, 0.03 * (outer - inner));
    EXPECT_EQ(s["components"]["count"], 2);
    EXPECT_EQ(s["components"]["largest"]["cavity"], false) << "the outer wall has the most triangles";

    const auto q = run_json("measure " + in + " --iso 500 --component-at " + std::to_string(c.x + 5.5) + "," +
                            std::to_string(c.y) + "," + std::to_string(c.z));
    const auto& qs = q["surfaces"][0];
    EXPECT_EQ(qs["cavity"], false);
    ASSERT_EQ(qs["components"].size(), 2u);
    EXPECT_EQ(qs["components"][0]["cavity"], false);
    EXPECT_NEAR(qs["components"][0]["volume_ml"].get<double>(), outer, 0.02 * outer);
    EXPECT_EQ(qs["components"][1]["cavity"], true) << "the inner wall, listed after the structures";
    EXPECT_NEAR(qs["components"][1]["volume_ml"].get<double>(), inner, 0.05 * inner);
    ASSERT_EQ(q["components"].size(), 1u);
    EXPECT_EQ(q["components"][0]["cavity"], true);
    EXPECT_GT(q["components"][0]["volume_ml"].get<double>(), 0.0);
    const auto t = test::run_command(test::cli() + " measure " + in + " --iso 500 --component-at " +
                                     std::to_string(c.x + 5.5) + "," + std::to_string(c.y) + "," + std::to_string(c.z));
    ASSERT_EQ(t.exit_code, 0) << t.out;
    EXPECT_NE(t.out.find("encloses a cavity of "), std::string::npos) << t.out;
    EXPECT_EQ(t.out.find("volume -"), std::string::npos) << t.out;
}
