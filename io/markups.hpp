// Measurements as 3D Slicer Markups JSON (.mrk.json, schema v1.0.3): point
// lists, lines and angles (read and written), open and closed curves (read
// only, as their control points). Positions are LPS millimetres in memory;
// files in RAS are converted on reading. docs/markups.md describes what is
// read, what is written and how Slicer treats it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace iso {

// Slicer's markup types that isoscope understands ("Fiducial" is Slicer's
// name for a point list). Plane and ROI are refused when reading.
enum class MarkupType { Fiducial, Line, Angle, Curve, ClosedCurve };

// Slicer's control point states: a point being placed ("preview") or not
// placed yet ("undefined") has no meaningful position.
enum class PositionStatus { Defined, Preview, Undefined };

struct MarkupControlPoint {
    std::string id;    // unique within its markup ("1", "2", ...); the writer numbers empty ones
    std::string label; // shown next to the point in Slicer
    std::string description;
    glm::dvec3 position{0.0}; // LPS mm; meaningful only when status is Defined
    PositionStatus status = PositionStatus::Defined;
    bool selected = true; // Slicer draws selected points in the display's selected colour
    bool locked = false;
    bool visible = true;
    bool operator==(const MarkupControlPoint&) const = default;
};

struct MarkupMeasurement {
    std::string name;            // Slicer's built-in ones: "length" (Line, Curve), "angle" (Angle)
    std::optional<double> value; // absent when Slicer could not compute it
    std::string units;           // "mm", "deg", ... (a coded entry's code value when the file has one)
    bool enabled = true;
    std::string description;
    std::string print_format; // printf-style, as Slicer shows it ("%-#4.4g%s"); may be empty
    bool operator==(const MarkupMeasurement&) const = default;
};

struct Markup {
    MarkupType type = MarkupType::Fiducial;
    std::string name; // Slicer does not write it (it names the node after the file); empty when absent
    std::vector<MarkupControlPoint> points;
    std::vector<MarkupMeasurement> measurements;
    bool locked = false;
    // Slicer's display colours, RGB components in [0, 1] as Slicer stores them, when the file has them.
    // Points are selected by default, so `selected_color` is what Slicer shows.
    std::optional<glm::dvec3> color;
    std::optional<glm::dvec3> selected_color;
    bool operator==(const Markup&) const = default;
};

struct MarkupsFile {
    std::vector<Markup> markups;
    std::vector<std::string> warnings; // non-fatal findings while reading (e.g. converted from RAS)
};

// "Fiducial", "Line", "Angle", "Curve", "ClosedCurve": the names in the file.
const char* markup_type_name(MarkupType t);

// Distance between two points, mm (a Line's "length").
double line_length_mm(const glm::dvec3& a, const glm::dvec3& b);
// The angle at `vertex` between the arms to `a` and `b`, in degrees within
// [0, 180] (an Angle's "angle": its points are arm, vertex, arm, in that
// order). nullopt when an arm has zero length, where Slicer reports none.
std::optional<double> angle_degrees(const glm::dvec3& a, const glm::dvec3& vertex, const glm::dvec3& b);
// The built-in measurement the writer stores for `m`, computed from its
// points as Slicer names it: a Line's "length" (units "mm"), an Angle's
// "angle" ("deg"). Without a value when a point is not Defined or the angle
// has a zero-length arm; nullopt for the other types.
std::optional<MarkupMeasurement> computed_measurement(const Markup& m);

// Reads every markup of a .mrk.json file (Slicer's "markups" array) and
// converts RAS positions to LPS. Throws iso::Error naming the file and the
// reason for anything it cannot read completely: a missing or non-JSON file,
// a schema other than markups-schema-v1.x.y, a markup type other than the
// ones above, coordinate units other than mm, a Line without exactly 2 or an
// Angle without exactly 3 control points, a value of the wrong type, a
// non-finite number. Properties isoscope does not model (orientations,
// display settings, Slicer's codes) are accepted and ignored.
MarkupsFile load_markups(const std::string& path);

// Writes Fiducial, Line and Angle markups in LPS mm under the v1.0.3 schema,
// the built-in length/angle measurement computed from the points (replacing
// a stored one of the same name; other measurements are written as they
// are). Writes to a temporary file and renames it into place, so the user's
// file is replaced whole or not at all. Throws iso::Error for curves, a Line
// or Angle with the wrong number of points, non-finite positions or colours
// outside [0, 1], and an empty list (Slicer cannot open a file without
// markups).
void save_markups(const MarkupsFile& f, const std::string& path);

// The same JSON text save_markups writes, in memory (sessions embed it), and
// reading such text (checked as load_markups checks a file). `where` is the
// file or field named in errors.
std::string markups_json_text(const MarkupsFile& f, const std::string& where);
MarkupsFile parse_markups(const std::string& text, const std::string& where);

} // namespace iso
