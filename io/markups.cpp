// 3D Slicer Markups JSON (.mrk.json) reader and writer.
//
// Written here rather than taken from a package: no Debian package reads the
// format (Slicer's own reader lives in its MRML library, which Debian does
// not ship). nlohmann_json does the JSON; this file checks every value it
// uses, since a Slicer file is hand-editable and fuzzed (tests/fuzz).
//
// What Slicer does, from vtkMRMLMarkupsJsonStorageNode.cxx (Slicer 5.0.3 and
// main, 2026), which this file follows:
//  - reads any "@schema" ending in markups-schema-v1.<n>.<n>.json (5.1 on;
//    5.0.x wants the whole "master" URL below, which is what Slicer writes);
//  - "coordinateSystem" LPS (the default) or RAS; "coordinateUnits" a UCUM
//    string or [code, scheme, meaning];
//  - a control point that is not "defined" is written with "position": "";
//  - in LPS, each control point's orientation has its first two rows
//    negated, so the identity orientation is written as
//    [-1, -0, -0, -0, -1, -0, 0, 0, 1];
//  - Line and Angle measurements are recomputed on loading, so the stored
//    values are a record for other readers.
#include "io/markups.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <new>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/finite.hpp"
#include "io/read_file.hpp"

namespace iso {
namespace fs = std::filesystem;

namespace {

using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;

// Exactly what Slicer writes (see the file comment): Slicer up to 5.0.x
// accepts only this URL, later versions any markups-schema-v1.x.y.json.
constexpr const char* kSchemaUrl =
    "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
    "markups-schema-v1.0.3.json#";

constexpr const char* kLengthFormat = "%-#4.4g%s"; // vtkMRMLMeasurementLength
constexpr const char* kAngleFormat = "%3.1f%s";    // vtkMRMLMeasurementAngle

struct TypeName {
    MarkupType type;
    const char* name;
};
constexpr TypeName kTypes[] = {{MarkupType::Fiducial, "Fiducial"},
                               {MarkupType::Line, "Line"},
                               {MarkupType::Angle, "Angle"},
                               {MarkupType::Curve, "Curve"},
                               {MarkupType::ClosedCurve, "ClosedCurve"}};

const char* status_name(PositionStatus s) {
    switch (s) {
    case PositionStatus::Defined: return "defined";
    case PositionStatus::Preview: return "preview";
    case PositionStatus::Undefined: return "undefined";
    }
    return "defined";
}

// The number of control points a type must have, or 0 when any number will do.
std::size_t required_points(MarkupType t) { return t == MarkupType::Line ? 2 : t == MarkupType::Angle ? 3 : 0; }

// Text from the file, made safe to print in a message.
std::string printable(const std::string& s, std::size_t max = 60) {
    std::string out;
    for (unsigned char c : s.substr(0, max)) out += (c >= 0x20 && c < 0x7f) ? char(c) : '?';
    if (s.size() > max) out += "...";
    return out;
}

// nlohmann's message without its "[json.exception.parse_error.101] " prefix.
std::string json_message(const json::exception& e) {
    std::string m = e.what();
    if (m.rfind("[json.exception.", 0) == 0) {
        const auto end = m.find("] ");
        if (end != std::string::npos) m.erase(0, end + 2);
    }
    return printable(m, 300);
}

// Slicer's check (ACCEPTED_MARKUPS_SCHEMA_REGEX, ".*markups-schema-v1\.[0-9]+\.[0-9]+\.json#*$",
// case-insensitive), by hand: std::regex recurses per character and a long
// hostile string would exhaust the stack.
bool accepted_schema(std::string s) {
    for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    while (!s.empty() && s.back() == '#') s.pop_back();
    const std::string ext = ".json", stem = "markups-schema-v1.";
    if (s.size() < ext.size() || s.compare(s.size() - ext.size(), ext.size(), ext) != 0) return false;
    s.erase(s.size() - ext.size());
    const auto at = s.rfind(stem);
    if (at == std::string::npos) return false;
    const std::string version = s.substr(at + stem.size());
    const auto dot = version.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == version.size()) return false;
    for (std::size_t i = 0; i < version.size(); ++i)
        if (i != dot && !std::isdigit(static_cast<unsigned char>(version[i]))) return false;
    return true;
}

// Reads one file; every failure names the file and says where in it.
class Reader {
public:
    explicit Reader(const std::string& path) : path_(path) {}

    MarkupsFile read(const json& root) {
        if (!root.is_object()) fail("", "the top level is a JSON " + std::string(root.type_name()) + ", not an object");
        const json* schema = member(root, "@schema");
        if (!schema) fail("", "no \"@schema\": not a Slicer markups file");
        if (!schema->is_string()) fail("", "\"@schema\" must be a string");
        if (!accepted_schema(schema->get<std::string>()))
            fail("", "schema '" + printable(schema->get<std::string>(), 200) +
                         "' is not a Slicer markups schema (markups-schema-v1.x.y.json)");
        const json* list = member(root, "markups");
        if (!list) fail("", "no \"markups\" array");
        if (!list->is_array()) fail("", "\"markups\" must be an array");
        if (list->empty()) fail("", "the \"markups\" array is empty");
        MarkupsFile f;
        for (std::size_t i = 0; i < list->size(); ++i) f.markups.push_back(read_markup((*list)[i], i, f.warnings));
        return f;
    }

private:
    [[noreturn]] void fail(const std::string& where, const std::string& reason) const {
        throw Error(path_, where.empty() ? reason : where + ": " + reason);
    }

    static const json* member(const json& obj, const char* key) {
        const auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }

    std::string string_or(const json& obj, const char* key, const std::string& where, std::string fallback = {}) const {
        const json* v = member(obj, key);
        if (!v) return fallback;
        if (!v->is_string()) fail(where, "\"" + std::string(key) + "\" must be a string, not a " + v->type_name());
        return v->get<std::string>();
    }

    bool bool_or(const json& obj, const char* key, const std::string& where, bool fallback) const {
        const json* v = member(obj, key);
        if (!v) return fallback;
        if (!v->is_boolean())
            fail(where, "\"" + std::string(key) + "\" must be true or false, not a " + v->type_name());
        return v->get<bool>();
    }

    double number(const json& v, const std::string& where, const std::string& what) const {
        if (!v.is_number()) fail(where, what + " must be a number, not a " + v.type_name());
        const double d = v.get<double>();
        if (!std::isfinite(d)) fail(where, what + " is NaN or infinite");
        return d;
    }

    // An array of exactly n finite numbers.
    std::vector<double> numbers(const json& v, std::size_t n, const std::string& where, const std::string& what) const {
        if (!v.is_array() || v.size() != n)
            fail(where, what + " must be an array of " + std::to_string(n) + " numbers");
        std::vector<double> out;
        for (const auto& x : v) out.push_back(number(x, where, what));
        return out;
    }

    glm::dvec3 vec3(const json& v, const std::string& where, const std::string& what) const {
        const auto n = numbers(v, 3, where, what);
        return {n[0], n[1], n[2]};
    }

    std::optional<glm::dvec3> color(const json& display, const char* key, const std::string& where) const {
        const json* v = member(display, key);
        if (!v) return std::nullopt;
        const glm::dvec3 c = vec3(*v, where, "display \"" + std::string(key) + "\"");
        for (int k = 0; k < 3; ++k)
            if (c[k] < 0.0 || c[k] > 1.0)
                fail(where, "display \"" + std::string(key) + "\" has a component outside [0, 1]");
        return c;
    }

    Markup read_markup(const json& item, std::size_t index, std::vector<std::string>& warnings) const {
        std::string where = "markup " + std::to_string(index + 1);
        if (!item.is_object()) fail(where, "must be an object, not a " + std::string(item.type_name()));
        if (!member(item, "type")) fail(where, "no \"type\"");
        const std::string type = string_or(item, "type", where);
        Markup m;
        bool known = false;
        for (const auto& t : kTypes) {
            if (type == t.name) {
                m.type = t.type;
                known = true;
            }
        }
        if (!known) {
            if (type == "Plane" || type == "ROI")
                fail(where, "markup type '" + type +
                                "' is not supported (isoscope reads Fiducial, Line, Angle, Curve and ClosedCurve)");
            fail(where, "unknown markup type '" + printable(type) + "'");
        }
        m.name = string_or(item, "name", where);
        where += " (" + type + (m.name.empty() ? "" : " '" + printable(m.name) + "'") + ")";

        const std::string system = string_or(item, "coordinateSystem", where, "LPS");
        if (system != "LPS" && system != "RAS")
            fail(where, "coordinate system '" + printable(system) + "' is neither LPS nor RAS");
        check_units(item, where);
        m.locked = bool_or(item, "locked", where, false);

        if (const json* cps = member(item, "controlPoints")) {
            if (!cps->is_array()) fail(where, "\"controlPoints\" must be an array");
            for (std::size_t i = 0; i < cps->size(); ++i)
                m.points.push_back(read_point((*cps)[i], where + ", control point " + std::to_string(i + 1)));
        }
        if (const std::size_t need = required_points(m.type); need && m.points.size() != need)
            fail(where, (m.type == MarkupType::Angle ? "an " : "a ") + type + " needs " + std::to_string(need) +
                            " control points, the file has " + std::to_string(m.points.size()));
        if (system == "RAS") {
            for (auto& p : m.points) p.position = {-p.position.x, -p.position.y, p.position.z};
            warnings.push_back(where + ": positions converted from RAS to LPS");
        }

        if (const json* ms = member(item, "measurements")) {
            if (!ms->is_array()) fail(where, "\"measurements\" must be an array");
            for (std::size_t i = 0; i < ms->size(); ++i)
                m.measurements.push_back(read_measurement((*ms)[i], where + ", measurement " + std::to_string(i + 1)));
        }
        if (const json* d = member(item, "display")) {
            if (!d->is_object()) fail(where, "\"display\" must be an object");
            m.color = color(*d, "color", where);
            m.selected_color = color(*d, "selectedColor", where);
        }
        return m;
    }

    void check_units(const json& item, const std::string& where) const {
        const json* u = member(item, "coordinateUnits");
        if (!u) return; // Slicer's default: mm
        std::string code;
        if (u->is_string()) {
            code = u->get<std::string>();
        } else if (u->is_array() && !u->empty() && u->size() <= 3) {
            for (const auto& s : *u)
                if (!s.is_string()) fail(where, "\"coordinateUnits\" must be a string or an array of strings");
            code = (*u)[0].get<std::string>();
            if (u->size() > 1 && !(*u)[1].get<std::string>().empty() && (*u)[1].get<std::string>() != "UCUM")
                fail(where, "coordinate units coded in '" + printable((*u)[1].get<std::string>()) + "', not UCUM");
        } else {
            fail(where, "\"coordinateUnits\" must be a string or [code, scheme, meaning]");
        }
        if (code != "mm")
            fail(where,
                 "coordinate units '" + printable(code) + "' are not supported (isoscope reads millimetres, \"mm\")");
    }

    MarkupControlPoint read_point(const json& item, const std::string& where) const {
        if (!item.is_object()) fail(where, "must be an object, not a " + std::string(item.type_name()));
        MarkupControlPoint p;
        p.id = string_or(item, "id", where);
        p.label = string_or(item, "label", where);
        p.description = string_or(item, "description", where);
        const std::string status = string_or(item, "positionStatus", where, "defined");
        if (status == "defined")
            p.status = PositionStatus::Defined;
        else if (status == "preview")
            p.status = PositionStatus::Preview;
        else if (status == "undefined")
            p.status = PositionStatus::Undefined;
        else
            fail(where, "position status '" + printable(status) + "' is not defined, preview or undefined");
        const json* pos = member(item, "position");
        if (p.status == PositionStatus::Defined) {
            if (!pos) fail(where, "no \"position\" for a defined point");
            p.position = vec3(*pos, where, "\"position\"");
        } else if (pos && !(pos->is_string() && pos->get<std::string>().empty())) {
            // Slicer writes "" for a point without a position; anything else must be a position.
            p.position = vec3(*pos, where, "\"position\"");
        }
        if (const json* o = member(item, "orientation")) numbers(*o, 9, where, "\"orientation\"");
        p.selected = bool_or(item, "selected", where, true);
        p.locked = bool_or(item, "locked", where, false);
        p.visible = bool_or(item, "visibility", where, true);
        return p;
    }

    MarkupMeasurement read_measurement(const json& item, const std::string& where) const {
        if (!item.is_object()) fail(where, "must be an object, not a " + std::string(item.type_name()));
        MarkupMeasurement m;
        if (!member(item, "name")) fail(where, "no \"name\"");
        m.name = string_or(item, "name", where);
        m.enabled = bool_or(item, "enabled", where, true);
        if (const json* v = member(item, "value")) m.value = number(*v, where, "\"value\"");
        if (const json* u = member(item, "units")) {
            if (u->is_string()) {
                m.units = u->get<std::string>();
            } else if (u->is_array() && !u->empty() && u->size() <= 3 && (*u)[0].is_string()) {
                m.units = (*u)[0].get<std::string>(); // a coded entry: Slicer shows its code value
            } else {
                fail(where, "\"units\" must be a string or [code, scheme, meaning]");
            }
        }
        m.description = string_or(item, "description", where);
        m.print_format = string_or(item, "printFormat", where);
        return m;
    }

    const std::string& path_;
};

// Slicer's layout: objects one member per line, arrays of numbers on one line.
void write_value(std::string& out, const ordered_json& v, int indent) {
    const std::string pad(std::size_t(indent + 4), ' ');
    if (v.is_object() && !v.empty()) {
        out += "{\n";
        std::size_t i = 0;
        for (const auto& [key, value] : v.items()) {
            out += pad + ordered_json(key).dump() + ": ";
            write_value(out, value, indent + 4);
            out += ++i < v.size() ? ",\n" : "\n";
        }
        out += std::string(std::size_t(indent), ' ') + "}";
        return;
    }
    if (v.is_array() && !v.empty()) {
        bool flat = true;
        for (const auto& x : v) flat = flat && !x.is_structured();
        out += flat ? "[" : "[\n";
        for (std::size_t i = 0; i < v.size(); ++i) {
            if (!flat) out += pad;
            write_value(out, v[i], indent + 4);
            if (i + 1 < v.size()) out += flat ? ", " : ",\n";
        }
        out += flat ? "]" : "\n" + std::string(std::size_t(indent), ' ') + "]";
        return;
    }
    out += v.dump(); // throws type_error 316 on a string that is not UTF-8
}

ordered_json vec_json(const glm::dvec3& v) { return ordered_json::array({v.x, v.y, v.z}); }

ordered_json measurement_json(const MarkupMeasurement& m) {
    ordered_json j;
    j["name"] = m.name;
    j["enabled"] = m.enabled;
    if (m.value) j["value"] = *m.value;
    if (!m.units.empty()) j["units"] = m.units;
    if (!m.description.empty()) j["description"] = m.description;
    if (!m.print_format.empty()) j["printFormat"] = m.print_format;
    return j;
}

void check_for_writing(const Markup& m, std::size_t index, const std::string& path) {
    const std::string where = "markup " + std::to_string(index + 1) + " (" + markup_type_name(m.type) + ")";
    if (m.type == MarkupType::Curve || m.type == MarkupType::ClosedCurve)
        throw Error(path, where + ": curves are read, not written (their length is measured along Slicer's spline)");
    if (const std::size_t need = required_points(m.type); need && m.points.size() != need)
        throw Error(path, where + ": needs " + std::to_string(need) + " control points, has " +
                              std::to_string(m.points.size()));
    for (std::size_t i = 0; i < m.points.size(); ++i)
        if (m.points[i].status == PositionStatus::Defined && !finite(m.points[i].position))
            throw Error(path, where + ": control point " + std::to_string(i + 1) + " has a NaN or infinite position");
    for (const auto& c : {m.color, m.selected_color}) {
        if (!c) continue;
        for (int k = 0; k < 3; ++k)
            if (!((*c)[k] >= 0.0 && (*c)[k] <= 1.0)) throw Error(path, where + ": a display colour outside [0, 1]");
    }
    for (const auto& meas : m.measurements)
        if (meas.value && !std::isfinite(*meas.value))
            throw Error(path, where + ": measurement '" + meas.name + "' is NaN or infinite");
}

ordered_json markup_json(const Markup& m) {
    ordered_json j;
    j["type"] = markup_type_name(m.type);
    if (!m.name.empty()) j["name"] = m.name; // Slicer reads it but names its nodes after the file
    j["coordinateSystem"] = "LPS";
    j["coordinateUnits"] = "mm";
    j["locked"] = m.locked;
    j["fixedNumberOfControlPoints"] = false;
    j["labelFormat"] = "%N-%d";
    j["lastUsedControlPointNumber"] = m.points.size();
    ordered_json points = ordered_json::array();
    for (std::size_t i = 0; i < m.points.size(); ++i) {
        const auto& p = m.points[i];
        ordered_json cp;
        cp["id"] = p.id.empty() ? std::to_string(i + 1) : p.id;
        cp["label"] = p.label;
        cp["description"] = p.description;
        cp["associatedNodeID"] = "";
        if (p.status == PositionStatus::Defined)
            cp["position"] = vec_json(p.position);
        else
            cp["position"] = "";
        // Slicer's identity orientation as it writes it in LPS (file comment).
        cp["orientation"] = ordered_json::array({-1.0, -0.0, -0.0, -0.0, -1.0, -0.0, 0.0, 0.0, 1.0});
        cp["selected"] = p.selected;
        cp["locked"] = p.locked;
        cp["visibility"] = p.visible;
        cp["positionStatus"] = status_name(p.status);
        points.push_back(std::move(cp));
    }
    j["controlPoints"] = std::move(points);

    ordered_json measurements = ordered_json::array();
    const auto built_in = computed_measurement(m);
    bool placed = false;
    for (const auto& meas : m.measurements) {
        if (built_in && meas.name == built_in->name) {
            if (!placed) measurements.push_back(measurement_json(*built_in));
            placed = true;
        } else {
            measurements.push_back(measurement_json(meas));
        }
    }
    if (built_in && !placed) measurements.insert(measurements.begin(), measurement_json(*built_in));
    j["measurements"] = std::move(measurements);

    ordered_json display;
    display["visibility"] = true;
    display["opacity"] = 1.0;
    if (m.color) display["color"] = vec_json(*m.color);
    if (m.selected_color) display["selectedColor"] = vec_json(*m.selected_color);
    j["display"] = std::move(display);
    return j;
}

} // namespace

const char* markup_type_name(MarkupType t) {
    for (const auto& n : kTypes)
        if (n.type == t) return n.name;
    return "Fiducial";
}

double line_length_mm(const glm::dvec3& a, const glm::dvec3& b) { return glm::length(b - a); }

std::optional<double> angle_degrees(const glm::dvec3& a, const glm::dvec3& vertex, const glm::dvec3& b) {
    const glm::dvec3 u = a - vertex, v = b - vertex;
    if (glm::dot(u, u) == 0.0 || glm::dot(v, v) == 0.0) return std::nullopt;
    // atan2 of |u x v| and u.v keeps full precision near 0 and 180 degrees, where acos of the cosine does not.
    return std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v)) * (180.0 / 3.14159265358979323846);
}

std::optional<MarkupMeasurement> computed_measurement(const Markup& m) {
    MarkupMeasurement meas;
    meas.enabled = true;
    if (m.type == MarkupType::Line) {
        meas.name = "length";
        meas.units = "mm";
        meas.print_format = kLengthFormat;
    } else if (m.type == MarkupType::Angle) {
        meas.name = "angle";
        meas.units = "deg";
        meas.print_format = kAngleFormat;
    } else {
        return std::nullopt;
    }
    if (m.points.size() != required_points(m.type)) return meas;
    for (const auto& p : m.points)
        if (p.status != PositionStatus::Defined || !finite(p.position)) return meas;
    const auto& p = m.points;
    if (m.type == MarkupType::Line)
        meas.value = line_length_mm(p[0].position, p[1].position);
    else
        meas.value = angle_degrees(p[0].position, p[1].position, p[2].position);
    return meas;
}

MarkupsFile load_markups(const std::string& path) {
    try {
        const std::string text = read_file(path);
        if (text.empty()) throw Error(path, "file is empty");
        json root;
        try {
            root = json::parse(text);
        } catch (const json::exception& e) {
            throw Error(path, "not valid JSON: " + json_message(e));
        }
        return Reader(path).read(root);
    } catch (const std::bad_alloc&) {
        throw Error(path, "not enough memory to read this file");
    }
}

std::string markups_json_text(const MarkupsFile& f, const std::string& where) {
    if (f.markups.empty()) throw Error(where, "no markups to write (Slicer cannot open a file without any)");
    ordered_json root;
    root["@schema"] = kSchemaUrl;
    root["markups"] = ordered_json::array();
    for (std::size_t i = 0; i < f.markups.size(); ++i) {
        check_for_writing(f.markups[i], i, where);
        root["markups"].push_back(markup_json(f.markups[i]));
    }
    std::string text;
    try {
        write_value(text, root, 0);
    } catch (const ordered_json::exception& e) {
        throw Error(where, "a name, label or text is not valid UTF-8 (" + json_message(e) + ")");
    }
    return text;
}

MarkupsFile parse_markups(const std::string& text, const std::string& where) {
    try {
        if (text.empty()) throw Error(where, "no markups text");
        json root;
        try {
            root = json::parse(text);
        } catch (const json::exception& e) {
            throw Error(where, "not valid JSON: " + json_message(e));
        }
        return Reader(where).read(root);
    } catch (const std::bad_alloc&) {
        throw Error(where, "not enough memory to read these markups");
    }
}

void save_markups(const MarkupsFile& f, const std::string& path) {
    check_writable_destination(path);
    std::string text = markups_json_text(f, path);
    text += "\n";
    write_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(path, "cannot create the file");
        out.write(text.data(), std::streamsize(text.size()));
        out.flush();
        if (!out) throw Error(path, "write failed (disk full?)");
    });
}

} // namespace iso
