#include "scene_viewer/assets/point_cloud.hpp"

#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>

namespace scene_viewer {

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
    throw std::runtime_error(path.string() + ": " + what);
}

/// A scalar column of PLY/PCD: its name, binary type and byte offset within a record.
struct Field {
    std::string name;
    char kind = 'f';  ///< 'f' float, 'i' signed, 'u' unsigned
    int bytes = 4;
    int offset = 0;
};

double read_binary(const char* p, const Field& f) {
    switch (f.kind) {
        case 'f':
            if (f.bytes == 4) {
                float v;
                std::memcpy(&v, p, 4);
                return v;
            } else {
                double v;
                std::memcpy(&v, p, 8);
                return v;
            }
        case 'i': {
            std::int64_t v = 0;
            if (f.bytes == 1) {
                std::int8_t t;
                std::memcpy(&t, p, 1);
                v = t;
            }
            if (f.bytes == 2) {
                std::int16_t t;
                std::memcpy(&t, p, 2);
                v = t;
            }
            if (f.bytes == 4) {
                std::int32_t t;
                std::memcpy(&t, p, 4);
                v = t;
            }
            if (f.bytes == 8) {
                std::memcpy(&v, p, 8);
            }
            return static_cast<double>(v);
        }
        default: {
            std::uint64_t v = 0;
            std::memcpy(&v, p, static_cast<std::size_t>(f.bytes));  // little-endian host
            return static_cast<double>(v);
        }
    }
}

/// Column roles: which field holds x, y, z, r, g, b, packed rgb and the class.
struct Roles {
    int x = -1, y = -1, z = -1, r = -1, g = -1, b = -1, rgb = -1, cls = -1;
};

Roles find_roles(const std::vector<std::string>& names) {
    Roles roles;
    for (int i = 0; i < static_cast<int>(names.size()); ++i) {
        const std::string n = lower(names[static_cast<std::size_t>(i)]);
        if (n == "x")
            roles.x = i;
        else if (n == "y")
            roles.y = i;
        else if (n == "z")
            roles.z = i;
        else if (n == "r" || n == "red")
            roles.r = i;
        else if (n == "g" || n == "green")
            roles.g = i;
        else if (n == "b" || n == "blue")
            roles.b = i;
        else if (n == "rgb" || n == "rgba")
            roles.rgb = i;
        else if (n == "label" || n == "class" || n == "class_id" || n == "scalar_class" ||
                 n == "scalar_label" || n == "classid")
            roles.cls = i;
    }
    return roles;
}

/// Appends one point from its column values.
/// Values a point may carry in a PLY or PCD file (the widest PCL point types carry a few hundred).
constexpr std::size_t kMaxFields = 4096;

/// A value from the file clamped into [lo, hi] before the cast (a cast of an out-of-range
/// double is undefined); NaN gives lo.
template <class T>
T clamp_cast(double v, double lo, double hi) {
    return static_cast<T>(v >= lo ? (v <= hi ? v : hi) : lo);
}

void add_point(PointCloud& cloud, const Roles& roles, const double* v, bool packed_rgb_float) {
    cloud.positions_kitti.emplace_back(v[roles.x], v[roles.y], v[roles.z]);
    if (roles.r >= 0 && roles.g >= 0 && roles.b >= 0) {
        cloud.colours.push_back({clamp_cast<std::uint8_t>(v[roles.r], 0, 255),
                                 clamp_cast<std::uint8_t>(v[roles.g], 0, 255),
                                 clamp_cast<std::uint8_t>(v[roles.b], 0, 255)});
    } else if (roles.rgb >= 0) {
        std::uint32_t packed = 0;
        if (packed_rgb_float) {
            const float f = static_cast<float>(v[roles.rgb]);
            std::memcpy(&packed, &f, 4);
        } else {
            packed = clamp_cast<std::uint32_t>(v[roles.rgb], 0, 4294967295.0);
        }
        cloud.colours.push_back({static_cast<std::uint8_t>((packed >> 16) & 0xFF),
                                 static_cast<std::uint8_t>((packed >> 8) & 0xFF),
                                 static_cast<std::uint8_t>(packed & 0xFF)});
    }
    if (roles.cls >= 0) cloud.class_ids.push_back(clamp_cast<int>(v[roles.cls], -1, 65535));
}

/// A number of an ASCII PCD record (std::stod's own exception text names neither file nor point).
double parse_number(const std::filesystem::path& path, const std::string& token,
                    std::size_t point) {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
        fail(path, "PCD point " + std::to_string(point) + ": '" + token.substr(0, 32) +
                       "' is not a number");
    }
    return v;
}

bool ply_type(const std::string& t, Field& f) {
    static const struct {
        const char* name;
        char kind;
        int bytes;
    } kTypes[] = {{"char", 'i', 1},  {"int8", 'i', 1},    {"uchar", 'u', 1},  {"uint8", 'u', 1},
                  {"short", 'i', 2}, {"int16", 'i', 2},   {"ushort", 'u', 2}, {"uint16", 'u', 2},
                  {"int", 'i', 4},   {"int32", 'i', 4},   {"uint", 'u', 4},   {"uint32", 'u', 4},
                  {"float", 'f', 4}, {"float32", 'f', 4}, {"double", 'f', 8}, {"float64", 'f', 8}};
    for (const auto& k : kTypes) {
        if (t == k.name) {
            f.kind = k.kind;
            f.bytes = k.bytes;
            return true;
        }
    }
    return false;
}

PointCloud read_ply(const std::filesystem::path& path, std::istream& in) {
    std::string line;
    std::getline(in, line);
    if (line.rfind("ply", 0) != 0) fail(path, "not a PLY file (no 'ply' magic)");
    std::string format;
    std::size_t count = 0;
    std::vector<Field> fields;
    bool in_vertex = false;
    int stride = 0;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        if (word == "format") {
            ls >> format;
        } else if (word == "element") {
            std::string name;
            ls >> name;
            in_vertex = name == "vertex";
            if (in_vertex)
                ls >> count;
            else if (fields.empty())
                fail(path, "PLY elements before 'vertex' are not supported");
        } else if (word == "property" && in_vertex) {
            std::string type, name;
            ls >> type;
            if (type == "list") fail(path, "PLY list properties on vertices are not supported");
            ls >> name;
            Field f;
            f.name = name;
            if (!ply_type(type, f)) fail(path, "unknown PLY property type '" + type + "'");
            f.offset = stride;
            stride += f.bytes;
            fields.push_back(f);
            if (fields.size() > kMaxFields) fail(path, "PLY header: more than 4096 properties");
        } else if (word == "end_header") {
            break;
        }
    }
    std::vector<std::string> names;
    for (const auto& f : fields) names.push_back(f.name);
    const Roles roles = find_roles(names);
    if (roles.x < 0 || roles.y < 0 || roles.z < 0) fail(path, "PLY vertex lacks x, y or z");
    PointCloud cloud;
    std::vector<double> values(fields.size());
    if (format == "binary_little_endian") {
        std::vector<char> record(static_cast<std::size_t>(stride));
        for (std::size_t i = 0; i < count; ++i) {
            if (!in.read(record.data(), stride)) fail(path, "PLY data truncated");
            for (std::size_t k = 0; k < fields.size(); ++k)
                values[k] = read_binary(record.data() + fields[k].offset, fields[k]);
            add_point(cloud, roles, values.data(), false);
        }
    } else if (format == "ascii") {
        for (std::size_t i = 0; i < count; ++i) {
            for (auto& v : values) {
                if (!(in >> v)) fail(path, "PLY data truncated");
            }
            add_point(cloud, roles, values.data(), false);
        }
    } else {
        fail(path, "unsupported PLY format '" + format + "'");
    }
    return cloud;
}

namespace {

/// A PCD header: its fields as declared, the point count and the DATA kind.
struct PcdHeader {
    std::vector<std::string> names, types;
    std::vector<int> sizes, counts;
    std::size_t points = 0;
    std::string data;
};

/// Reads the header up to and including its DATA line, checked: FIELDS, SIZE, TYPE and COUNT
/// agree, each field is F 4/8 or I/U 1/2/4/8 with a COUNT of 1..1024.
PcdHeader read_pcd_header(const std::filesystem::path& path, std::istream& in) {
    PcdHeader h;
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ls(line);
        std::string key, word;
        ls >> key;
        if (key == "FIELDS") {
            while (ls >> word) h.names.push_back(word);
        } else if (key == "SIZE") {
            int s;
            while (ls >> s) h.sizes.push_back(s);
        } else if (key == "TYPE") {
            while (ls >> word) h.types.push_back(word);
        } else if (key == "COUNT") {
            int c;
            while (ls >> c) h.counts.push_back(c);
        } else if (key == "POINTS") {
            ls >> h.points;
        } else if (key == "DATA") {
            ls >> h.data;
            break;
        }
    }
    if (h.counts.empty()) h.counts.assign(h.names.size(), 1);
    if (h.sizes.size() != h.names.size() || h.types.size() != h.names.size() ||
        h.counts.size() != h.names.size()) {
        fail(path, "PCD header: FIELDS, SIZE, TYPE and COUNT disagree");
    }
    constexpr int kMaxCount = 1024;  // values per field (PCL's histograms use up to 308)
    for (std::size_t i = 0; i < h.names.size(); ++i) {
        const bool is_float = h.types[i] == "F";
        const int size = h.sizes[i];
        const bool size_ok = is_float ? (size == 4 || size == 8)
                                      : (size == 1 || size == 2 || size == 4 || size == 8);
        if (!size_ok || (!is_float && h.types[i] != "I" && h.types[i] != "U")) {
            fail(path, "PCD header: field '" + h.names[i] + "' has TYPE " + h.types[i] + " SIZE " +
                           std::to_string(size) + " (F 4/8, I or U 1/2/4/8)");
        }
        if (h.counts[i] < 1 || h.counts[i] > kMaxCount) {
            fail(path, "PCD header: field '" + h.names[i] + "' COUNT must be 1.." +
                           std::to_string(kMaxCount));
        }
    }
    return h;
}

}  // namespace

PointCloud read_pcd(const std::filesystem::path& path, std::istream& in) {
    const PcdHeader h = read_pcd_header(path, in);
    const std::size_t points = h.points;
    const std::string& data = h.data;
    std::vector<Field> fields;
    std::vector<std::string> scalar_names;
    int stride = 0;
    for (std::size_t i = 0; i < h.names.size(); ++i) {
        for (int c = 0; c < h.counts[i]; ++c) {
            Field f;
            f.name = c == 0 ? h.names[i] : h.names[i] + "_" + std::to_string(c);
            f.kind = h.types[i] == "F" ? 'f' : h.types[i] == "I" ? 'i' : 'u';
            f.bytes = h.sizes[i];
            f.offset = stride;
            stride += f.bytes;
            fields.push_back(f);
            scalar_names.push_back(f.name);
            if (fields.size() > kMaxFields) fail(path, "PCD header: more than 4096 values a point");
        }
    }
    const Roles roles = find_roles(scalar_names);
    if (roles.x < 0 || roles.y < 0 || roles.z < 0) fail(path, "PCD lacks x, y or z");
    const bool packed_float =
        roles.rgb >= 0 && fields[static_cast<std::size_t>(roles.rgb)].kind == 'f';
    PointCloud cloud;
    std::vector<double> values(fields.size());
    if (data == "binary") {
        std::vector<char> record(static_cast<std::size_t>(stride));
        for (std::size_t i = 0; i < points; ++i) {
            if (!in.read(record.data(), stride)) fail(path, "PCD data truncated");
            for (std::size_t k = 0; k < fields.size(); ++k)
                values[k] = read_binary(record.data() + fields[k].offset, fields[k]);
            if (std::isfinite(values[static_cast<std::size_t>(roles.x)]))
                add_point(cloud, roles, values.data(), packed_float);
        }
    } else if (data == "ascii") {
        for (std::size_t i = 0; i < points; ++i) {
            for (std::size_t k = 0; k < fields.size(); ++k) {
                std::string token;
                if (!(in >> token)) fail(path, "PCD data truncated");
                values[k] = parse_number(path, token, i);
            }
            if (std::isfinite(values[static_cast<std::size_t>(roles.x)]))
                add_point(cloud, roles, values.data(), packed_float);
        }
    } else {
        fail(path, "unsupported PCD DATA '" + data + "' (ascii or binary)");
    }
    return cloud;
}

PointCloud read_xyz(const std::filesystem::path& path, std::istream& in) {
    std::vector<std::string> names;
    std::string line;
    PointCloud cloud;
    Roles roles;
    bool roles_set = false;
    std::vector<double> values;
    std::size_t line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.rfind("//", 0) == 0) {
            std::string header = line.substr(2);
            std::replace(header.begin(), header.end(), ',', ' ');
            std::istringstream hs(header);
            std::string name;
            names.clear();
            while (hs >> name) names.push_back(name);
            roles = find_roles(names);
            roles_set = true;
            continue;
        }
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream ls(line);
        values.clear();
        double v;
        while (ls >> v) values.push_back(v);
        if (values.empty()) continue;
        if (!roles_set) {
            // No header: x y z [r g b [class]].
            roles = Roles{};
            roles.x = 0, roles.y = 1, roles.z = 2;
            if (values.size() >= 6) roles.r = 3, roles.g = 4, roles.b = 5;
            if (values.size() >= 7) roles.cls = 6;
            roles_set = true;
        }
        if (roles.x < 0 || roles.y < 0 || roles.z < 0) fail(path, "XYZ header lacks x, y or z");
        const int needed =
            std::max({roles.x, roles.y, roles.z, roles.r, roles.g, roles.b, roles.cls}) + 1;
        if (static_cast<int>(values.size()) < needed)
            fail(path, "line " + std::to_string(line_no) + " has too few columns");
        add_point(cloud, roles, values.data(), false);
    }
    return cloud;
}

}  // namespace

PointCloud read_point_cloud(const std::filesystem::path& path) {
    stereoscene::support::check_input_file(path, stereoscene::support::limits().max_file_bytes);
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
    try {
        return read_point_cloud(in, path);
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory reading the cloud");
    }
}

PointCloud read_point_cloud(std::istream& in, const std::filesystem::path& path) {
    const std::string ext = lower(path.extension().string());
    PointCloud cloud;
    if (ext == ".ply") {
        cloud = read_ply(path, in);
    } else if (ext == ".pcd") {
        cloud = read_pcd(path, in);
    } else if (ext == ".xyz" || ext == ".txt" || ext == ".asc") {
        cloud = read_xyz(path, in);
    } else {
        fail(path, "unsupported point cloud extension '" + ext + "' (.ply, .pcd, .xyz)");
    }
    if (!cloud.colours.empty() && cloud.colours.size() != cloud.size()) cloud.colours.clear();
    if (!cloud.class_ids.empty() && cloud.class_ids.size() != cloud.size()) cloud.class_ids.clear();
    return cloud;
}

}  // namespace scene_viewer
