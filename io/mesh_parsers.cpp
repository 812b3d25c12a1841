#include "io/mesh_parsers.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "io/error.hpp"

namespace iso::detail {

namespace {

std::string slurp(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open");
    std::string s;
    f.seekg(0, std::ios::end);
    s.resize(std::size_t(f.tellg()));
    f.seekg(0);
    f.read(s.data(), std::streamsize(s.size()));
    return s;
}

std::string tag_in(const std::string& text) {
    const auto p = text.find("SPACE=");
    return p == std::string::npos ? "" : text.substr(p + 6, 3);
}

void require_finite(const std::string& path, const glm::vec3& p, const char* what) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw Error(path, std::string(what) + " with NaN or infinite coordinates");
}

// Welds identical positions (STL stores every corner of every triangle).
struct Welder {
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> buckets;
    Mesh& m;
    explicit Welder(Mesh& mesh) : m(mesh) {}
    std::uint32_t add(const glm::vec3& p) {
        std::uint32_t bits[3];
        std::memcpy(bits, &p, sizeof bits);
        const std::uint64_t h = (std::uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^
                                (std::uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^ bits[2];
        auto& b = buckets[h];
        for (auto i : b)
            if (m.positions[i] == p) return i;
        b.push_back(std::uint32_t(m.positions.size()));
        m.positions.push_back(p);
        return b.back();
    }
};

} // namespace

Mesh parse_stl(const std::string& path, std::string& space) {
    const std::string s = slurp(path);
    Mesh m;
    Welder w(m);
    std::uint32_t n = 0;
    if (s.size() >= 84) std::memcpy(&n, s.data() + 80, 4);
    if (s.size() >= 84 && 84 + 50 * std::uint64_t(n) == s.size()) {
        space = tag_in(s.substr(0, 80));
        m.triangles.reserve(n);
        for (std::uint32_t t = 0; t < n; ++t) {
            const char* rec = s.data() + 84 + 50 * std::size_t(t) + 12; // skip the facet normal
            std::array<std::uint32_t, 3> tri;
            for (int k = 0; k < 3; ++k) {
                float xyz[3];
                std::memcpy(xyz, rec + 12 * k, 12);
                const glm::vec3 p(xyz[0], xyz[1], xyz[2]);
                require_finite(path, p, "a triangle");
                tri[std::size_t(k)] = w.add(p);
            }
            m.triangles.push_back(tri);
        }
        return m;
    }
    // ASCII: "vertex x y z" three at a time.
    const auto start = s.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || s.compare(start, 5, "solid") != 0)
        throw Error(path, "truncated or malformed binary STL: the header announces " + std::to_string(n) +
                              " triangles (" + std::to_string(84 + 50 * std::uint64_t(n)) + " bytes), the file has " +
                              std::to_string(s.size()) + " bytes");
    space = tag_in(s.substr(start, s.find('\n', start) - start));
    std::istringstream in(s);
    std::string word;
    std::array<std::uint32_t, 3> tri{};
    int corner = 0;
    bool any = false;
    while (in >> word) {
        if (word != "vertex") continue;
        glm::vec3 p;
        if (!(in >> p.x >> p.y >> p.z)) throw Error(path, "malformed ASCII STL: a vertex line without three numbers");
        require_finite(path, p, "a vertex");
        tri[std::size_t(corner++)] = w.add(p);
        if (corner == 3) {
            m.triangles.push_back(tri);
            corner = 0;
            any = true;
        }
    }
    if (corner != 0) throw Error(path, "malformed ASCII STL: a facet with fewer than three vertices");
    if (!any) throw Error(path, "ASCII STL without any facet");
    return m;
}

namespace {

// PLY scalar types.
enum class PT { I8, U8, I16, U16, I32, U32, F32, F64 };
bool ply_type(const std::string& t, PT& out) {
    static const std::pair<const char*, PT> table[] = {
        {"char", PT::I8},   {"int8", PT::I8},     {"uchar", PT::U8},   {"uint8", PT::U8},
        {"short", PT::I16}, {"int16", PT::I16},   {"ushort", PT::U16}, {"uint16", PT::U16},
        {"int", PT::I32},   {"int32", PT::I32},   {"uint", PT::U32},   {"uint32", PT::U32},
        {"float", PT::F32}, {"float32", PT::F32}, {"double", PT::F64}, {"float64", PT::F64}};
    for (auto& [name, t2] : table)
        if (t == name) {
            out = t2;
            return true;
        }
    return false;
}
std::size_t ply_size(PT t) {
    switch (t) {
    case PT::I8:
    case PT::U8: return 1;
    case PT::I16:
    case PT::U16: return 2;
    case PT::I32:
    case PT::U32:
    case PT::F32: return 4;
    case PT::F64: return 8;
    }
    return 1;
}

struct PlyProp {
    std::string name;
    PT type = PT::F32;
    bool list = false;
    PT count_type = PT::U8;
};
struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProp> props;
};

// Reads values from the body, ASCII or binary, bounds-checked.
class PlyReader {
public:
    PlyReader(const std::string& path, const std::string& data, std::size_t pos, int format)
        : path_(path), d_(data), pos_(pos), format_(format) {}
    double read(PT t) {
        if (format_ == 0) return read_ascii();
        const std::size_t n = ply_size(t);
        if (pos_ + n > d_.size()) throw Error(path_, "truncated PLY data");
        unsigned char b[8];
        std::memcpy(b, d_.data() + pos_, n);
        pos_ += n;
        if (format_ == 2) std::reverse(b, b + n); // big endian
        switch (t) {
        case PT::I8: return double(std::int8_t(b[0]));
        case PT::U8: return double(b[0]);
        case PT::I16: {
            std::int16_t v;
            std::memcpy(&v, b, 2);
            return v;
        }
        case PT::U16: {
            std::uint16_t v;
            std::memcpy(&v, b, 2);
            return v;
        }
        case PT::I32: {
            std::int32_t v;
            std::memcpy(&v, b, 4);
            return v;
        }
        case PT::U32: {
            std::uint32_t v;
            std::memcpy(&v, b, 4);
            return v;
        }
        case PT::F32: {
            float v;
            std::memcpy(&v, b, 4);
            return v;
        }
        case PT::F64: {
            double v;
            std::memcpy(&v, b, 8);
            return v;
        }
        }
        return 0;
    }

private:
    double read_ascii() {
        while (pos_ < d_.size() && std::isspace(static_cast<unsigned char>(d_[pos_]))) ++pos_;
        if (pos_ >= d_.size()) throw Error(path_, "truncated PLY data");
        const char* b = d_.data() + pos_;
        char* e = nullptr;
        const double v = std::strtod(b, &e);
        if (e == b)
            throw Error(path_,
                        "malformed PLY data: '" + std::string(b, std::min<std::size_t>(12, d_.size() - pos_)) + "'");
        pos_ += std::size_t(e - b);
        return v;
    }
    const std::string& path_;
    const std::string& d_;
    std::size_t pos_;
    int format_; // 0 ascii, 1 binary little endian, 2 binary big endian
};

} // namespace

Mesh parse_ply(const std::string& path, std::string& space) {
    const std::string s = slurp(path);
    if (s.compare(0, 3, "ply") != 0) throw Error(path, "not a PLY file (no 'ply' magic)");
    const auto end = s.find("end_header");
    if (end == std::string::npos) throw Error(path, "PLY header is incomplete (no end_header)");
    std::size_t body = s.find('\n', end);
    if (body == std::string::npos) throw Error(path, "PLY header is incomplete");
    ++body;
    std::istringstream in(s.substr(0, end));
    std::string line;
    int format = -1;
    std::vector<PlyElement> elements;
    std::string comments;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string w;
        ls >> w;
        if (w == "format") {
            std::string f;
            ls >> f;
            format = f == "ascii" ? 0 : f == "binary_little_endian" ? 1 : f == "binary_big_endian" ? 2 : -1;
            if (format < 0) throw Error(path, "unknown PLY format '" + f + "'");
        } else if (w == "comment" || w == "obj_info") {
            comments += line + "\n";
        } else if (w == "element") {
            PlyElement e;
            if (!(ls >> e.name >> e.count)) throw Error(path, "malformed PLY element line: " + line);
            elements.push_back(e);
        } else if (w == "property") {
            if (elements.empty()) throw Error(path, "PLY property before any element");
            PlyProp p;
            std::string t;
            ls >> t;
            if (t == "list") {
                std::string ct, it;
                ls >> ct >> it >> p.name;
                if (!ply_type(ct, p.count_type) || !ply_type(it, p.type))
                    throw Error(path, "malformed PLY list property: " + line);
                p.list = true;
            } else {
                if (!ply_type(t, p.type)) throw Error(path, "unknown PLY property type '" + t + "'");
                ls >> p.name;
            }
            elements.back().props.push_back(p);
        }
    }
    if (format < 0) throw Error(path, "PLY header without a format line");
    space = tag_in(comments);
    // Plausibility: every element instance takes at least one byte (two in ASCII).
    std::uint64_t instances = 0;
    for (const auto& e : elements) instances += e.count;
    if (instances > s.size() - body)
        throw Error(path, "PLY header announces more elements than the file can hold (truncated?)");

    Mesh m;
    PlyReader r(path, s, body, format);
    for (const auto& e : elements) {
        const bool vertex = e.name == "vertex", face = e.name == "face";
        int ix[10];
        std::fill(std::begin(ix), std::end(ix), -1);
        const char* names[10] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha"};
        for (std::size_t p = 0; p < e.props.size(); ++p)
            for (int k = 0; k < 10; ++k)
                if (e.props[p].name == names[k] && !e.props[p].list) ix[k] = int(p);
        if (vertex && (ix[0] < 0 || ix[1] < 0 || ix[2] < 0)) throw Error(path, "PLY vertices without x, y, z");
        const bool normals = vertex && ix[3] >= 0 && ix[4] >= 0 && ix[5] >= 0;
        const bool colors = vertex && ix[6] >= 0 && ix[7] >= 0 && ix[8] >= 0;
        std::vector<double> vals(e.props.size());
        for (std::uint64_t i = 0; i < e.count; ++i) {
            for (std::size_t p = 0; p < e.props.size(); ++p) {
                const auto& pr = e.props[p];
                if (!pr.list) {
                    vals[p] = r.read(pr.type);
                    continue;
                }
                const double cnt = r.read(pr.count_type);
                if (!(cnt >= 0) || cnt > 1e6) throw Error(path, "PLY list with an invalid length");
                std::vector<std::uint32_t> idx(static_cast<std::size_t>(cnt));
                for (auto& x : idx) {
                    const double v = r.read(pr.type);
                    if (!(v >= 0 && v < 4294967295.0))
                        throw Error(path, "PLY face with a negative or invalid vertex index");
                    x = std::uint32_t(v);
                }
                if (face && (pr.name == "vertex_indices" || pr.name == "vertex_index"))
                    for (std::size_t k = 2; k < idx.size(); ++k) m.triangles.push_back({idx[0], idx[k - 1], idx[k]});
            }
            if (vertex) {
                const glm::vec3 p(static_cast<float>(vals[std::size_t(ix[0])]),
                                  static_cast<float>(vals[std::size_t(ix[1])]),
                                  static_cast<float>(vals[std::size_t(ix[2])]));
                require_finite(path, p, "a vertex");
                m.positions.push_back(p);
                if (normals)
                    m.normals.emplace_back(float(vals[std::size_t(ix[3])]), float(vals[std::size_t(ix[4])]),
                                           float(vals[std::size_t(ix[5])]));
                if (colors) {
                    auto c = [&](int k) { return std::uint8_t(std::clamp(vals[std::size_t(ix[k])], 0.0, 255.0)); };
                    m.colors.emplace_back(c(6), c(7), c(8), ix[9] >= 0 ? c(9) : std::uint8_t(255));
                }
            }
        }
    }
    if (m.positions.empty()) throw Error(path, "PLY file has no vertices");
    return m;
}

Mesh parse_obj(const std::string& path, std::string& space) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path, "cannot open");
    Mesh m;
    std::vector<glm::vec3> vn;
    std::string line;
    std::size_t lineno = 0;
    bool normals_match = true, any_vn_ref = false;
    std::vector<std::int64_t> fv, fn;
    while (std::getline(f, line)) {
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        if (line[0] == '#') {
            if (space.empty()) space = tag_in(line);
            continue;
        }
        const char* p = line.c_str();
        auto number = [&](double& out) {
            while (*p == ' ' || *p == '\t') ++p;
            char* e = nullptr;
            out = std::strtod(p, &e);
            if (e == p || !std::isfinite(out))
                throw Error(path, "line " + std::to_string(lineno) + ": NaN, infinite or unreadable coordinate");
            p = e;
        };
        if (line.rfind("v ", 0) == 0 || line.rfind("v\t", 0) == 0) {
            p += 2;
            double x, y, z;
            number(x), number(y), number(z);
            m.positions.emplace_back(float(x), float(y), float(z));
        } else if (line.rfind("vn ", 0) == 0) {
            p += 3;
            double x, y, z;
            number(x), number(y), number(z);
            vn.emplace_back(float(x), float(y), float(z));
        } else if (line.rfind("f ", 0) == 0 || line.rfind("f\t", 0) == 0) {
            std::istringstream ls(line.substr(2));
            std::string tok;
            fv.clear();
            fn.clear();
            while (ls >> tok) {
                // v, v/vt, v//vn, v/vt/vn; negative indices count from the end.
                std::int64_t idx[3] = {0, 0, 0};
                int field = 0;
                std::size_t start = 0;
                for (std::size_t i = 0; i <= tok.size() && field < 3; ++i) {
                    if (i == tok.size() || tok[i] == '/') {
                        if (i > start) {
                            std::int64_t v = 0;
                            auto [ptr, ec] = std::from_chars(tok.data() + start, tok.data() + i, v);
                            if (ec != std::errc() || ptr != tok.data() + i)
                                throw Error(path,
                                            "line " + std::to_string(lineno) + ": malformed face index '" + tok + "'");
                            idx[field] = v;
                        }
                        ++field;
                        start = i + 1;
                    }
                }
                auto resolve = [&](std::int64_t i, std::size_t n) -> std::int64_t {
                    if (i > 0 && std::uint64_t(i) <= n) return i - 1;
                    if (i < 0 && std::uint64_t(-i) <= n) return std::int64_t(n) + i;
                    throw Error(path,
                                "line " + std::to_string(lineno) + ": face refers to a vertex that does not exist");
                };
                fv.push_back(resolve(idx[0], m.positions.size()));
                if (idx[2] != 0) {
                    any_vn_ref = true;
                    fn.push_back(resolve(idx[2], vn.size()));
                } else {
                    fn.push_back(-1);
                }
            }
            if (fv.size() < 3)
                throw Error(path, "line " + std::to_string(lineno) + ": a face needs at least three vertices");
            for (std::size_t k = 0; k < fv.size(); ++k)
                if (fn[k] != fv[k]) normals_match = false;
            for (std::size_t k = 2; k < fv.size(); ++k)
                m.triangles.push_back({std::uint32_t(fv[0]), std::uint32_t(fv[k - 1]), std::uint32_t(fv[k])});
        }
    }
    if (m.positions.empty()) throw Error(path, "OBJ file has no vertices");
    // Per-vertex normals only when every face uses vertex i's normal i (as we write them).
    if (any_vn_ref && normals_match && vn.size() >= m.positions.size())
        m.normals.assign(vn.begin(), vn.begin() + std::ptrdiff_t(m.positions.size()));
    return m;
}

} // namespace iso::detail
