// Slicer Markups JSON: round trips through our writer and reader, the
// hand-written Slicer 5.x fixtures (datasets/markups/, one in RAS), the file
// our writer produces read back as plain JSON against Slicer's writer, and
// each kind of bad input named with its file and reason. Expected lengths and
// angles come from hand geometry or Python (datasets/markups/README.md).
#include <cmath>
#include <filesystem>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "io/error.hpp"
#include "io/markups.hpp"
#include "tests/support/test_util.hpp"

using namespace iso;
using iso::test::read_file;
using iso::test::TempDir;
using iso::test::write_file;
namespace fs = std::filesystem;

namespace {

MarkupControlPoint point(const std::string& label, glm::dvec3 p) {
    MarkupControlPoint c;
    c.label = label;
    c.position = p;
    return c;
}

// A point list, a 3-4-5 line and a 45-degree angle, in LPS mm.
MarkupsFile sample() {
    MarkupsFile f;
    Markup pts;
    pts.type = MarkupType::Fiducial;
    pts.name = "F";
    pts.points = {point("F-1", {1.5, -2.25, 3.125}), point("F-2", {-100.1, 0.3, 1e-7}), point("F-3", {})};
    pts.points[0].description = "tip of the nose";
    pts.points[1].locked = true;
    pts.points[1].visible = false;
    pts.points[1].selected = false;
    pts.points[2].status = PositionStatus::Undefined;
    pts.selected_color = glm::dvec3(0.25, 0.5, 1.0);
    Markup line;
    line.type = MarkupType::Line;
    line.name = "L";
    line.points = {point("L-1", {1, 2, 3}), point("L-2", {4, 6, 3})}; // 3-4-5
    line.color = glm::dvec3(1.0, 0.0, 0.0);
    Markup angle;
    angle.type = MarkupType::Angle;
    angle.name = "A";
    angle.points = {point("A-1", {11, 20, 30}), point("A-2", {10, 20, 30}), point("A-3", {11, 21, 30})}; // 45 degrees
    angle.measurements.push_back({"HU mean", 42.5, "[hnsf'U]", true, "", ""});
    f.markups = {pts, line, angle};
    return f;
}

const MarkupMeasurement* find(const Markup& m, const std::string& name) {
    for (const auto& x : m.measurements)
        if (x.name == name) return &x;
    return nullptr;
}

// Expects load_markups(path) to throw an Error naming the file and containing `reason`.
void expect_error(const std::string& path, const std::string& reason) {
    try {
        load_markups(path);
        ADD_FAILURE() << path << " loaded; expected an error containing '" << reason << "'";
    } catch (const Error& e) {
        EXPECT_EQ(e.where(), path);
        EXPECT_NE(std::string(e.what()).find(fs::path(path).filename().string()), std::string::npos) << e.what();
        EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    }
}

// One markup wrapped into a file with Slicer's schema.
std::string file_with(const std::string& markup) {
    return R"({"@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#", "markups": [)" +
           markup + "]}";
}

const std::string kLine = R"({"type": "Line", "controlPoints": [{"position": [0, 0, 0]}, {"position": [3, 4, 0]}]})";

} // namespace

TEST(Markups, LengthAndAngleFromHandGeometry) {
    EXPECT_DOUBLE_EQ(line_length_mm({1, 2, 3}, {4, 6, 3}), 5.0);
    EXPECT_DOUBLE_EQ(line_length_mm({-1, -1, -1}, {-1, -1, -1}), 0.0);
    EXPECT_NEAR(*angle_degrees({1, 0, 0}, {0, 0, 0}, {0, 1, 0}), 90.0, 1e-12);
    EXPECT_NEAR(*angle_degrees({1, 0, 0}, {0, 0, 0}, {1, 1, 0}), 45.0, 1e-12);
    EXPECT_NEAR(*angle_degrees({1, 0, 0}, {0, 0, 0}, {-1, 0, 0}), 180.0, 1e-12);
    EXPECT_NEAR(*angle_degrees({2, 0, 0}, {0, 0, 0}, {5, 0, 0}), 0.0, 1e-12);
    // Equilateral triangle, away from the origin: 60 degrees at every corner.
    const glm::dvec3 a(10, 10, 10), b(12, 10, 10), c(11, 10 + std::sqrt(3.0), 10);
    EXPECT_NEAR(*angle_degrees(a, b, c), 60.0, 1e-12);
    EXPECT_NEAR(*angle_degrees(b, c, a), 60.0, 1e-12);
    // Nearly straight: acos of the cosine would lose this.
    EXPECT_NEAR(*angle_degrees({-1, 0, 0}, {0, 0, 0}, {1, 1e-9, 0}), 180.0 - 1e-9 * 180.0 / M_PI, 1e-12);
    EXPECT_FALSE(angle_degrees({0, 0, 0}, {0, 0, 0}, {1, 0, 0}).has_value());
}

TEST(Markups, RoundTripPointsLineAndAngle) {
    TempDir dir;
    const MarkupsFile in = sample();
    save_markups(in, dir / "m.mrk.json");
    const MarkupsFile out = load_markups(dir / "m.mrk.json");
    ASSERT_EQ(out.markups.size(), 3u);
    EXPECT_TRUE(out.warnings.empty());
    for (std::size_t i = 0; i < in.markups.size(); ++i) {
        const Markup &a = in.markups[i], &b = out.markups[i];
        EXPECT_EQ(b.type, a.type);
        EXPECT_EQ(b.name, a.name);
        EXPECT_EQ(b.color, a.color);
        EXPECT_EQ(b.selected_color, a.selected_color);
        ASSERT_EQ(b.points.size(), a.points.size());
        for (std::size_t k = 0; k < a.points.size(); ++k) {
            EXPECT_EQ(b.points[k].label, a.points[k].label);
            EXPECT_EQ(b.points[k].id, std::to_string(k + 1)); // numbered by the writer
            EXPECT_EQ(b.points[k].description, a.points[k].description);
            EXPECT_EQ(b.points[k].status, a.points[k].status);
            EXPECT_EQ(b.points[k].locked, a.points[k].locked);
            EXPECT_EQ(b.points[k].visible, a.points[k].visible);
            EXPECT_EQ(b.points[k].selected, a.points[k].selected);
            if (a.points[k].status == PositionStatus::Defined) {
                EXPECT_EQ(b.points[k].position, a.points[k].position); // exact
            }
        }
    }
    EXPECT_TRUE(out.markups[0].measurements.empty());
    const auto* length = find(out.markups[1], "length");
    ASSERT_NE(length, nullptr);
    ASSERT_TRUE(length->value.has_value());
    EXPECT_DOUBLE_EQ(*length->value, 5.0);
    EXPECT_EQ(length->units, "mm");
    EXPECT_TRUE(length->enabled);
    const auto* angle = find(out.markups[2], "angle");
    ASSERT_NE(angle, nullptr);
    ASSERT_TRUE(angle->value.has_value());
    EXPECT_NEAR(*angle->value, 45.0, 1e-12);
    EXPECT_EQ(angle->units, "deg");
    const auto* hu = find(out.markups[2], "HU mean"); // an extra measurement is kept as given
    ASSERT_NE(hu, nullptr);
    EXPECT_EQ(hu->value, 42.5);
    EXPECT_EQ(hu->units, "[hnsf'U]");
}

TEST(Markups, WrittenFileHasSlicersFields) {
    TempDir dir;
    MarkupsFile in = sample();
    // A stale stored length is replaced by the one computed from the points.
    in.markups[1].measurements.push_back({"length", 99.0, "cm", false, "", ""});
    save_markups(in, dir / "m.mrk.json");
    const auto j = nlohmann::json::parse(read_file(dir / "m.mrk.json"));
    // Slicer up to 5.0.x accepts only this exact URL.
    EXPECT_EQ(j["@schema"], "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/"
                            "Schema/markups-schema-v1.0.3.json#");
    ASSERT_EQ(j["markups"].size(), 3u);
    const auto& line = j["markups"][1];
    EXPECT_EQ(line["type"], "Line");
    EXPECT_EQ(line["coordinateSystem"], "LPS");
    EXPECT_EQ(line["coordinateUnits"], "mm");
    ASSERT_EQ(line["controlPoints"].size(), 2u);
    const auto& cp = line["controlPoints"][1];
    EXPECT_EQ(cp["id"], "2");
    EXPECT_EQ(cp["label"], "L-2");
    EXPECT_EQ(cp["position"], nlohmann::json::array({4.0, 6.0, 3.0}));
    EXPECT_EQ(cp["positionStatus"], "defined");
    // Identity orientation as Slicer writes it in LPS: first two rows negated.
    EXPECT_EQ(cp["orientation"], nlohmann::json::array({-1.0, -0.0, -0.0, -0.0, -1.0, -0.0, 0.0, 0.0, 1.0}));
    ASSERT_EQ(line["measurements"].size(), 1u);
    const auto& m = line["measurements"][0];
    EXPECT_EQ(m["name"], "length");
    EXPECT_EQ(m["enabled"], true);
    EXPECT_EQ(m["value"], 5.0);
    EXPECT_EQ(m["units"], "mm");
    EXPECT_EQ(m["printFormat"], "%-#4.4g%s");
    const auto& angle = j["markups"][2]["measurements"][0];
    EXPECT_EQ(angle["name"], "angle");
    EXPECT_EQ(angle["units"], "deg");
    EXPECT_EQ(angle["printFormat"], "%3.1f%s");
    EXPECT_EQ(line["display"]["color"], nlohmann::json::array({1.0, 0.0, 0.0}));
    // A point not placed: Slicer writes an empty string for its position.
    const auto& undefined = j["markups"][0]["controlPoints"][2];
    EXPECT_EQ(undefined["position"], "");
    EXPECT_EQ(undefined["positionStatus"], "undefined");
    // Slicer's layout: a position on one line.
    EXPECT_NE(read_file(dir / "m.mrk.json").find("\"position\": [4.0, 6.0, 3.0]"), std::string::npos);
}

TEST(Markups, AngleWithoutArmHasNoValue) {
    TempDir dir;
    MarkupsFile f;
    Markup a;
    a.type = MarkupType::Angle;
    a.points = {point("", {1, 1, 1}), point("", {1, 1, 1}), point("", {2, 1, 1})};
    f.markups = {a};
    save_markups(f, dir / "a.mrk.json");
    const auto j = nlohmann::json::parse(read_file(dir / "a.mrk.json"));
    EXPECT_FALSE(j["markups"][0]["measurements"][0].contains("value"));
    const MarkupsFile back = load_markups(dir / "a.mrk.json");
    const auto* m = find(back.markups[0], "angle");
    ASSERT_NE(m, nullptr);
    EXPECT_FALSE(m->value.has_value());
}

TEST(Markups, SlicerLineInRasComesOutInLps) {
    const MarkupsFile f = load_markups(test::data("markups/slicer-line-ras.mrk.json"));
    ASSERT_EQ(f.markups.size(), 1u);
    const Markup& m = f.markups[0];
    EXPECT_EQ(m.type, MarkupType::Line);
    EXPECT_EQ(m.name, ""); // Slicer does not write one
    ASSERT_EQ(m.points.size(), 2u);
    // The file's RAS positions with x and y negated.
    EXPECT_EQ(m.points[0].position, glm::dvec3(38.42101287841797, -52.13835525512695, 27.600000381469727));
    EXPECT_EQ(m.points[1].position, glm::dvec3(-41.93075942993164, -48.77734375, 30.0));
    EXPECT_EQ(m.points[0].label, "L-1");
    EXPECT_EQ(m.points[1].id, "2");
    const auto* length = find(m, "length");
    ASSERT_NE(length, nullptr);
    EXPECT_EQ(length->value, 80.45783808678556);
    EXPECT_EQ(length->units, "mm");
    EXPECT_EQ(length->print_format, "%-#4.4g%s");
    // The stored value (Python's math.dist) and ours from the LPS points agree.
    EXPECT_NEAR(line_length_mm(m.points[0].position, m.points[1].position), 80.45783808678556, 1e-12);
    EXPECT_EQ(m.color, glm::dvec3(0.4, 1.0, 1.0));
    EXPECT_EQ(m.selected_color, glm::dvec3(1.0, 0.5000076295109484, 0.5000076295109484));
    ASSERT_EQ(f.warnings.size(), 1u);
    EXPECT_NE(f.warnings[0].find("RAS"), std::string::npos);
}

TEST(Markups, SlicerPointListWithUnplacedPoint) {
    const MarkupsFile f = load_markups(test::data("markups/slicer-points-lps.mrk.json"));
    ASSERT_EQ(f.markups.size(), 1u);
    const Markup& m = f.markups[0];
    EXPECT_EQ(m.type, MarkupType::Fiducial);
    ASSERT_EQ(m.points.size(), 3u);
    EXPECT_EQ(m.points[0].position, glm::dvec3(1.6000003814697266, -88.92708587646484, 41.25)); // LPS as written
    EXPECT_EQ(m.points[0].description, "nasion");
    EXPECT_TRUE(m.points[0].locked);
    EXPECT_FALSE(m.points[1].visible);
    EXPECT_FALSE(m.points[1].selected);
    EXPECT_EQ(m.points[2].status, PositionStatus::Undefined);
    EXPECT_TRUE(m.measurements.empty());
    EXPECT_EQ(m.selected_color, glm::dvec3(0.9372549019607843, 0.34901960784313726, 0.3843137254901961));
    EXPECT_TRUE(f.warnings.empty());
}

TEST(Markups, SlicerFilesSurviveOurWriter) {
    TempDir dir;
    for (const char* name : {"slicer-line-ras.mrk.json", "slicer-points-lps.mrk.json"}) {
        const MarkupsFile a = load_markups(test::data(std::string("markups/") + name));
        save_markups(a, dir / name);
        const MarkupsFile b = load_markups(dir / name);
        ASSERT_EQ(b.markups.size(), 1u) << name;
        ASSERT_EQ(b.markups[0].points.size(), a.markups[0].points.size()) << name;
        for (std::size_t k = 0; k < a.markups[0].points.size(); ++k) {
            EXPECT_EQ(b.markups[0].points[k].status, a.markups[0].points[k].status) << name;
            if (a.markups[0].points[k].status == PositionStatus::Defined) {
                EXPECT_EQ(b.markups[0].points[k].position, a.markups[0].points[k].position) << name;
            }
        }
        EXPECT_TRUE(b.warnings.empty()) << name; // written in LPS
    }
}

TEST(Markups, AcceptsWhatSlicerAccepts) {
    TempDir dir;
    // Any markups-schema-v1.x.y.json, any case, with or without '#'; the
    // coordinate system defaults to LPS; units may be a UCUM coded entry.
    for (const char* schema :
         {"https://raw.githubusercontent.com/slicer/slicer/main/modules/loadable/markups/resources/"
          "schema/markups-schema-v1.0.3.json#",
          "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/"
          "Resources/Schema/markups-schema-v1.0.0.json#",
          "MARKUPS-SCHEMA-V1.12.7.JSON"}) {
        write_file(dir / "s.mrk.json",
                   std::string(R"({"@schema": ")") + schema +
                       R"(", "markups": [{"type": "Line", "coordinateUnits": ["mm", "UCUM", "millimeter"],
                                         "controlPoints": [{"position": [0, 0, 0]}, {"position": [3, 4, 0]}]}]})");
        const MarkupsFile f = load_markups(dir / "s.mrk.json");
        ASSERT_EQ(f.markups.size(), 1u) << schema;
        EXPECT_EQ(f.markups[0].points[1].position, glm::dvec3(3, 4, 0)) << schema;
        EXPECT_EQ(f.markups[0].points[1].status, PositionStatus::Defined) << schema;
    }
    // Curves are read as their control points; every markup of a file is read.
    write_file(
        dir / "c.mrk.json",
        file_with(
            R"({"type": "Curve", "coordinateSystem": "RAS", "controlPoints": [{"position": [1, 2, 3]}, {"position": [4, 5, 6]},
                        {"position": [7, 8, 9]}]}, {"type": "ClosedCurve", "controlPoints": []}, )" +
            kLine));
    const MarkupsFile c = load_markups(dir / "c.mrk.json");
    ASSERT_EQ(c.markups.size(), 3u);
    EXPECT_EQ(c.markups[0].type, MarkupType::Curve);
    EXPECT_EQ(c.markups[0].points[2].position, glm::dvec3(-7, -8, 9));
    EXPECT_EQ(c.markups[1].type, MarkupType::ClosedCurve);
    EXPECT_EQ(c.markups[2].type, MarkupType::Line);
}

TEST(Markups, BadInputNamesFileAndReason) {
    TempDir dir;
    expect_error(dir / "missing.mrk.json", "no such file");
    fs::create_directories(dir / "folder.mrk.json");
    expect_error(dir / "folder.mrk.json", "not a regular file");
    auto bad = [&](const std::string& name, const std::string& text, const std::string& reason) {
        write_file(dir / name, text);
        expect_error(dir / name, reason);
    };
    bad("empty.mrk.json", "", "empty");
    bad("text.mrk.json", "this is not JSON", "not valid JSON");
    const std::string fixture = read_file(test::data("markups/slicer-line-ras.mrk.json"));
    ASSERT_GT(fixture.size(), 100u);
    bad("truncated.mrk.json", fixture.substr(0, fixture.size() / 2), "unexpected end of input");
    bad("toplevel.mrk.json", "[1, 2]", "not an object");
    bad("noschema.mrk.json", R"({"markups": []})", "no \"@schema\"");
    bad("schema.mrk.json", R"({"@schema": "https://example.org/other-schema-v1.0.3.json", "markups": []})",
        "not a Slicer markups schema");
    bad("schema2.mrk.json", R"({"@schema": "markups-schema-v2.0.0.json#", "markups": []})",
        "not a Slicer markups schema");
    bad("schema3.mrk.json", R"({"@schema": 103, "markups": []})", "\"@schema\" must be a string");
    bad("nomarkups.mrk.json", R"({"@schema": "markups-schema-v1.0.3.json"})", "no \"markups\"");
    bad("nolist.mrk.json", R"({"@schema": "markups-schema-v1.0.3.json", "markups": {}})", "must be an array");
    bad("nothing.mrk.json", file_with(""), "empty");
    // Markup types.
    bad("notype.mrk.json", file_with(R"({"controlPoints": []})"), "no \"type\"");
    bad("unknown.mrk.json", file_with(R"({"type": "Banana"})"), "unknown markup type 'Banana'");
    bad("roi.mrk.json", file_with(R"({"type": "ROI", "controlPoints": []})"), "'ROI' is not supported");
    bad("typenum.mrk.json", file_with(R"({"type": 3})"), "\"type\" must be a string");
    // Point counts.
    bad("line3.mrk.json",
        file_with(
            R"({"type": "Line", "controlPoints": [{"position": [0,0,0]}, {"position": [1,0,0]}, {"position": [2,0,0]}]})"),
        "a Line needs 2 control points, the file has 3");
    bad("line0.mrk.json", file_with(R"({"type": "Line"})"), "a Line needs 2 control points, the file has 0");
    bad("angle2.mrk.json",
        file_with(R"({"type": "Angle", "controlPoints": [{"position": [0,0,0]}, {"position": [1,0,0]}]})"),
        "an Angle needs 3 control points, the file has 2");
    // Coordinates: units, system, non-finite, wrong shapes and types.
    bad("um.mrk.json", file_with(R"({"type": "Fiducial", "coordinateUnits": "um"})"),
        "coordinate units 'um' are not supported");
    bad("dcm.mrk.json", file_with(R"({"type": "Fiducial", "coordinateUnits": ["mm", "DCM", "millimeter"]})"),
        "not UCUM");
    bad("xyz.mrk.json", file_with(R"({"type": "Fiducial", "coordinateSystem": "XYZ"})"), "neither LPS nor RAS");
    bad("overflow.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1e999, 0, 0]}]})"),
        "overflow");
    bad("nan.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [NaN, 0, 0]}]})"),
        "not valid JSON");
    bad("short.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1, 2]}]})"),
        "control point 1: \"position\" must be an array of 3 numbers");
    bad("strpos.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": "1 2 3"}]})"),
        "must be an array of 3");
    bad("nopos.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"label": "F-1"}]})"), "no \"position\"");
    bad("strnum.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1, "2", 3]}]})"),
        "must be a number");
    bad("status.mrk.json",
        file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1, 2, 3], "positionStatus": "maybe"}]})"),
        "position status 'maybe'");
    bad("orient.mrk.json",
        file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1, 2, 3], "orientation": [1, 0]}]})"),
        "\"orientation\" must be an array of 9 numbers");
    bad("locked.mrk.json", file_with(R"({"type": "Fiducial", "locked": "yes"})"), "\"locked\" must be true or false");
    bad("label.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [{"position": [1, 2, 3], "label": 7}]})"),
        "\"label\" must be a string");
    bad("points.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": {"position": [1, 2, 3]}})"),
        "\"controlPoints\" must be an array");
    bad("pointnum.mrk.json", file_with(R"({"type": "Fiducial", "controlPoints": [5]})"),
        "control point 1: must be an object");
    // Measurements and display.
    bad("measname.mrk.json", file_with(R"({"type": "Fiducial", "measurements": [{"value": 1}]})"),
        "measurement 1: no \"name\"");
    bad("measval.mrk.json", file_with(R"({"type": "Fiducial", "measurements": [{"name": "x", "value": "1"}]})"),
        "\"value\" must be a number");
    bad("color.mrk.json", file_with(R"({"type": "Fiducial", "display": {"color": [0.5, 1.5, 0]}})"), "outside [0, 1]");
    bad("display.mrk.json", file_with(R"({"type": "Fiducial", "display": []})"), "\"display\" must be an object");
    // The second markup is bad: nothing is returned (no half-loaded list), and the message says which.
    bad("second.mrk.json", file_with(kLine + R"(, {"type": "Angle"})"), "markup 2 (Angle)");
}

TEST(Markups, WriterRefusesWhatSlicerCannotRead) {
    TempDir dir;
    auto refused = [&](const MarkupsFile& f, const std::string& reason) {
        write_file(dir / "keep.mrk.json", "user data");
        try {
            save_markups(f, dir / "keep.mrk.json");
            ADD_FAILURE() << "written; expected '" << reason << "'";
        } catch (const Error& e) {
            EXPECT_EQ(e.where(), dir / "keep.mrk.json");
            EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
        }
        EXPECT_EQ(read_file(dir / "keep.mrk.json"), "user data"); // untouched
    };
    refused(MarkupsFile{}, "no markups");
    MarkupsFile f = sample();
    f.markups[1].points.pop_back();
    refused(f, "needs 2 control points, has 1");
    f = sample();
    f.markups[2].points.push_back(point("", {}));
    refused(f, "needs 3 control points, has 4");
    f = sample();
    f.markups[1].points[0].position.y = std::nan("");
    refused(f, "NaN or infinite position");
    f = sample();
    f.markups[0].color = glm::dvec3(0, 2, 0);
    refused(f, "outside [0, 1]");
    f = sample();
    f.markups[0].type = MarkupType::Curve;
    refused(f, "curves are read, not written");
    f = sample();
    f.markups[0].points[0].label = "\xff\xfe";
    refused(f, "not valid UTF-8");
    EXPECT_THROW(save_markups(sample(), dir / "no/such/folder/m.mrk.json"), Error);
    // Overwriting a file the user named is fine: atomically, whole.
    save_markups(sample(), dir / "keep.mrk.json");
    EXPECT_EQ(load_markups(dir / "keep.mrk.json").markups.size(), 3u);
    for (const auto& e : fs::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename().string().rfind(".isoscope-tmp", 0), std::string::npos)
            << e.path(); // no temporary left
}
