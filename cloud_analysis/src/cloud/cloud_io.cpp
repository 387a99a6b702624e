#include "cloud_analysis/cloud/cloud_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <future>
#include <memory>
#include <stdexcept>

namespace cloud_analysis {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the binary PCD and PLY writers assume a little-endian host");

std::int32_t class_id(const Palette& palette, std::uint16_t index) {
    return index == kVoidClass || index >= palette.classes.size()
               ? kVoidClassId
               : static_cast<std::int32_t>(palette.classes[index].id);
}

/// Decimal text of 0..255, built once: colour channels are most of an .xyz line.
struct ByteText {
    char text[256][4];
    std::uint8_t length[256];
    ByteText() {
        for (int i = 0; i < 256; ++i) {
            const auto end = std::to_chars(text[i], text[i] + 4, i).ptr;
            length[i] = static_cast<std::uint8_t>(end - text[i]);
        }
    }
};
const ByteText kByteText;

char* put_byte(char* p, std::uint8_t v) {
    std::memcpy(p, kByteText.text[v], 4);  // copies padding too; the cursor moves by length
    return p + kByteText.length[v];
}

/// Unsigned decimal, most significant digit first.
char* put_unsigned(char* p, std::uint64_t v) {
    char digits[20];
    int n = 0;
    do {
        digits[n++] = static_cast<char>('0' + v % 10);
        v /= 10;
    } while (v != 0);
    while (n > 0) *p++ = digits[--n];
    return p;
}

/// ".000" to ".999", built once: the decimals of every coordinate.
struct MilliText {
    char text[1000][4];
    MilliText() {
        for (int i = 0; i < 1000; ++i) {
            text[i][0] = '.';
            text[i][1] = static_cast<char>('0' + i / 100);
            text[i][2] = static_cast<char>('0' + (i / 10) % 10);
            text[i][3] = static_cast<char>('0' + i % 10);
        }
    }
};
const MilliText kMilliText;

/// Writes v with 3 decimals (millimetres) at p; returns the end. Fixed point: no locale, no
/// exponent. Non-finite values never reach here (reprojection drops them).
char* put_fixed3(char* p, float value) {
    // A float times 1000 is exact in a double, so ties are exact: round them to even as
    // printf("%.3f") does.
    const double scaled = static_cast<double>(value) * 1000.0;
    auto milli = static_cast<std::int64_t>(scaled);  // toward zero; the rest is exact
    const double rest = std::abs(scaled - static_cast<double>(milli));
    if (rest > 0.5 || (rest == 0.5 && (milli & 1) != 0)) milli += scaled < 0.0 ? -1 : 1;
    if (milli < 0) {
        *p++ = '-';
        milli = -milli;
    }
    const auto m = static_cast<std::uint64_t>(milli);
    const std::uint64_t whole = m / 1000;
    if (whole < 100) {  // metres in front of a car: one or two digits from the byte table
        p = put_byte(p, static_cast<std::uint8_t>(whole));
    } else {
        p = put_unsigned(p, whole);
    }
    std::memcpy(p, kMilliText.text[m - whole * 1000], 4);
    return p + 4;
}

char* put_int(char* p, long long value) {
    if (value < 0) {
        *p++ = '-';
        return put_unsigned(p, static_cast<std::uint64_t>(-value));
    }
    return put_unsigned(p, static_cast<std::uint64_t>(value));
}

template <typename T>
char* put_raw(char* p, T value) {
    std::memcpy(p, &value, sizeof(T));
    return p + sizeof(T);
}

}  // namespace

CloudFormat cloud_format_from_path(const std::filesystem::path& path) {
    const std::string ext = path.extension().string();
    if (ext == ".xyz" || ext == ".txt") return CloudFormat::kXyz;
    if (ext == ".pcd") return CloudFormat::kPcd;
    if (ext == ".ply") return CloudFormat::kPly;
    throw std::invalid_argument("unknown cloud extension '" + ext + "' (want .xyz, .pcd, .ply)");
}

namespace {

/// Text in a buffer sized for the worst case, left uninitialised (unlike std::string::resize):
/// the pages of the unused tail are never touched.
struct Text {
    std::unique_ptr<char[]> data;
    std::size_t size = 0;
};

/// The .xyz lines of points [begin, end) (no header).
Text xyz_lines(const LabeledCloud& cloud, const Palette& palette, std::size_t begin,
               std::size_t end) {
    // Worst case per line: 3 coordinates of 24 chars, 3 colours, class, luma, separators;
    // a cloud costs its real size (~35 bytes a point), not 120.
    Text text{std::unique_ptr<char[]>(new char[(end - begin) * 120 + 1]), 0};
    char* const start = text.data.get();
    char* p = start;
    for (std::size_t i = begin; i < end; ++i) {
        const auto& xyz = cloud.xyz_m[i];
        const auto& c = cloud.colour[i];
        p = put_fixed3(p, xyz.x());
        *p++ = ' ';
        p = put_fixed3(p, xyz.y());
        *p++ = ' ';
        p = put_fixed3(p, xyz.z());
        for (int k = 0; k < 3; ++k) {
            *p++ = ' ';
            p = put_byte(p, c[static_cast<std::size_t>(k)]);
        }
        *p++ = ' ';
        p = put_int(p, class_id(palette, cloud.class_index[i]));
        *p++ = ' ';
        // Rec. 601 luma, the grey value the thesis wrote.
        p = put_byte(
            p, static_cast<std::uint8_t>((299 * c[0] + 587 * c[1] + 114 * c[2] + 500) / 1000));
        *p++ = '\n';
    }
    text.size = static_cast<std::size_t>(p - start);
    return text;
}

}  // namespace

std::string format_xyz(const LabeledCloud& cloud, const Palette& palette) {
    // ASCII formatting is the costliest writer: the second half of a large cloud is formatted
    // on a helper thread (2 cores), then the halves are joined.
    constexpr std::size_t kParallelFrom = 100000;
    const std::size_t n = cloud.size();
    const std::size_t split = n < kParallelFrom ? n : n / 2;
    auto second = std::async(split < n ? std::launch::async : std::launch::deferred,
                             [&] { return xyz_lines(cloud, palette, split, n); });
    const Text first = xyz_lines(cloud, palette, 0, split);
    const Text last = second.get();
    // One copy of each half into the file's bytes.
    std::string out;
    out.reserve(kXyzHeader.size() + first.size + last.size);
    out.append(kXyzHeader);
    out.append(first.data.get(), first.size);
    out.append(last.data.get(), last.size);
    return out;
}

std::string format_pcd(const LabeledCloud& cloud, const Palette& palette) {
    const std::string n = std::to_string(cloud.size());
    std::string out =
        "# .PCD v0.7 - Point Cloud Data file format\n"
        "VERSION 0.7\n"
        "FIELDS x y z rgb label\n"
        "SIZE 4 4 4 4 4\n"
        "TYPE F F F F U\n"
        "COUNT 1 1 1 1 1\n"
        "WIDTH " +
        n +
        "\n"
        "HEIGHT 1\n"
        "VIEWPOINT 0 0 0 1 0 0 0\n"
        "POINTS " +
        n +
        "\n"
        "DATA binary\n";
    const std::size_t header = out.size();
    out.resize(header + cloud.size() * 20);
    char* p = out.data() + header;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& xyz = cloud.xyz_m[i];
        const auto& c = cloud.colour[i];
        p = put_raw(p, xyz.x());
        p = put_raw(p, xyz.y());
        p = put_raw(p, xyz.z());
        // PCL's PointXYZRGB layout: 0x00RRGGBB stored in the bytes of a float field.
        p = put_raw(p, (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | c[2]);
        p = put_raw(p, static_cast<std::uint32_t>(class_id(palette, cloud.class_index[i])));
    }
    return out;
}

std::string format_ply(const LabeledCloud& cloud, const Palette& palette) {
    std::string out =
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment stereoscene cloud-analysis: rectified left camera, x right, y down, z forward, "
        "metres\n"
        "comment palette " +
        palette.name +
        "\n"
        "element vertex " +
        std::to_string(cloud.size()) +
        "\n"
        "property float x\n"
        "property float y\n"
        "property float z\n"
        "property uchar red\n"
        "property uchar green\n"
        "property uchar blue\n"
        "property int scalar_class\n"
        "end_header\n";
    const std::size_t header = out.size();
    out.resize(header + cloud.size() * 19);
    char* p = out.data() + header;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& xyz = cloud.xyz_m[i];
        const auto& c = cloud.colour[i];
        p = put_raw(p, xyz.x());
        p = put_raw(p, xyz.y());
        p = put_raw(p, xyz.z());
        p = put_raw(p, c[0]);
        p = put_raw(p, c[1]);
        p = put_raw(p, c[2]);
        p = put_raw(p, class_id(palette, cloud.class_index[i]));
    }
    return out;
}

std::vector<std::uint16_t> class_indices(const Palette& palette,
                                         const std::vector<std::string>& names) {
    std::vector<std::uint16_t> out;
    for (const auto& name : names) {
        if (name == "void") {
            out.push_back(kVoidClass);
            continue;
        }
        const auto it = std::find_if(palette.classes.begin(), palette.classes.end(),
                                     [&](const ClassInfo& c) { return c.name == name; });
        if (it == palette.classes.end()) {
            throw std::invalid_argument("no class '" + name + "' in palette '" + palette.name +
                                        "'");
        }
        out.push_back(static_cast<std::uint16_t>(it - palette.classes.begin()));
    }
    return out;
}

LabeledCloud without_classes(const LabeledCloud& cloud, const std::vector<std::uint16_t>& dropped) {
    if (dropped.empty()) return cloud;
    LabeledCloud out;
    out.width_px = cloud.width_px;
    out.height_px = cloud.height_px;
    out.border = cloud.border;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (std::find(dropped.begin(), dropped.end(), cloud.class_index[i]) != dropped.end()) {
            continue;
        }
        out.xyz_m.push_back(cloud.xyz_m[i]);
        out.colour.push_back(cloud.colour[i]);
        out.class_index.push_back(cloud.class_index[i]);
        if (i < cloud.pixel.size()) out.pixel.push_back(cloud.pixel[i]);
    }
    return out;
}

std::string format_cloud(const LabeledCloud& cloud, const Palette& palette, CloudFormat format) {
    switch (format) {
        case CloudFormat::kXyz:
            return format_xyz(cloud, palette);
        case CloudFormat::kPcd:
            return format_pcd(cloud, palette);
        case CloudFormat::kPly:
            return format_ply(cloud, palette);
    }
    throw std::invalid_argument("unknown cloud format");
}

}  // namespace cloud_analysis
