#include "cloud_analysis/cloud/instances.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace cloud_analysis {
namespace {

/// The 16-bit encodings agree with the semantic image of the same view on this share of its
/// classed pixels at least: both images describe the same pixels, and what differs is label
/// bleed along borders. Less means another frame, another palette or another encoding.
constexpr std::size_t kMinAgreementPermille = 900;

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

/// The label id and the instance number of a 16-bit value.
struct Decoded {
    std::uint32_t label = 0;
    std::uint32_t instance = 0;
};

Decoded decode_value(std::uint16_t v, InstanceEncoding e) {
    if (e == InstanceEncoding::kKitti) return {std::uint32_t{v} >> 8, std::uint32_t{v} & 0xffu};
    if (v < 1000) return {v, 0};
    return {std::uint32_t{v} / 1000, std::uint32_t{v} % 1000};
}

/// Palette class index of each label id (kVoidClass where none has it).
std::vector<std::uint16_t> classes_by_label(const Palette& palette) {
    std::vector<std::uint16_t> out(65536, kVoidClass);
    for (std::size_t k = 0; k < palette.classes.size(); ++k) {
        const int id = palette.classes[k].id;
        if (id >= 0 && id < 65536 && out[static_cast<std::size_t>(id)] == kVoidClass) {
            out[static_cast<std::size_t>(id)] = static_cast<std::uint16_t>(k);
        }
    }
    return out;
}

/// Pixels whose class in the 16-bit file is the semantic image's, per mille of the pixels both
/// images class.
std::size_t agreement_permille(const ImageU16& ids, InstanceEncoding e, const ClassImage& classes,
                               const std::vector<std::uint16_t>& by_label) {
    std::size_t classed = 0, agree = 0;
    for (std::size_t p = 0; p < ids.values.size(); ++p) {
        const std::uint16_t k = classes.class_index[p];
        // 0 (labelId 0, "unlabeled") says nothing: renderers leave stuff pixels at 0.
        if (k == kVoidClass || ids.values[p] == 0) continue;
        ++classed;
        agree += by_label[decode_value(ids.values[p], e).label] == k ? 1 : 0;
    }
    return classed == 0 ? 0 : agree * 1000 / classed;
}

InstanceMap decode_ids(const ImageU16& ids, InstanceEncoding encoding, const ClassImage& classes,
                       const Palette& palette) {
    const std::vector<std::uint16_t> by_label = classes_by_label(palette);
    InstanceMap out;
    if (encoding == InstanceEncoding::kAuto) {
        const std::size_t kitti =
            agreement_permille(ids, InstanceEncoding::kKitti, classes, by_label);
        const std::size_t cityscapes =
            agreement_permille(ids, InstanceEncoding::kCityscapes, classes, by_label);
        encoding = kitti >= cityscapes ? InstanceEncoding::kKitti : InstanceEncoding::kCityscapes;
    }
    out.encoding = encoding;
    out.class_agreement_permille = agreement_permille(ids, encoding, classes, by_label);
    if (out.class_agreement_permille < kMinAgreementPermille) {
        throw std::invalid_argument(
            "its classes (" + instance_encoding_name(encoding) +
            " encoding) match the semantic "
            "image on " +
            std::to_string(out.class_agreement_permille / 10) +
            " % of the pixels, not the same view or not this encoding or palette");
    }
    out.id.assign(ids.values.size(), 0);
    std::unordered_set<std::uint32_t> seen;
    std::size_t on_stuff = 0;
    std::uint16_t stuff_class = kVoidClass;
    for (std::size_t p = 0; p < ids.values.size(); ++p) {
        const Decoded d = decode_value(ids.values[p], encoding);
        if (d.instance == 0) continue;
        const std::uint16_t k = by_label[d.label];
        if (k == kVoidClass) continue;  // a class the palette does not know: no object of ours
        if (!palette.classes[k].thing) {
            ++on_stuff;
            stuff_class = k;
            continue;
        }
        if (classes.class_index[p] != k) continue;
        out.id[p] = ids.values[p];
        seen.insert(ids.values[p]);
    }
    if (on_stuff > 0) {
        throw std::invalid_argument("object ids on stuff class '" +
                                    palette.classes[stuff_class].name + "' (" +
                                    std::to_string(on_stuff) + " pixels)");
    }
    out.objects = seen.size();
    return out;
}

InstanceMap decode_colours(const ImageU8& colour, const ClassImage& classes,
                           const Palette& palette) {
    if (colour.channels != 3) {
        throw std::invalid_argument(
            "8-bit single-channel: neither 16-bit ids nor RGB colours (convert it to one)");
    }
    const std::size_t n = classes.class_index.size();
    const std::size_t class_count = palette.classes.size();
    // Pixels of each class under each colour.
    std::unordered_map<std::uint32_t, std::vector<std::size_t>> count;
    std::vector<std::uint32_t> packed(n, 0);
    for (std::size_t p = 0; p < n; ++p) {
        const std::uint8_t* c = colour.data.data() + 3 * p;
        packed[p] = (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | c[2];
        if (packed[p] == 0) continue;
        auto& per_class = count[packed[p]];
        if (per_class.empty()) per_class.assign(class_count + 1, 0);
        const std::uint16_t k = classes.class_index[p];
        ++per_class[k == kVoidClass ? class_count : k];
    }
    // Each colour is an object of the class most of its pixels have.
    std::unordered_map<std::uint32_t, std::uint16_t> class_of;
    for (const auto& [id, per_class] : count) {
        const auto most = static_cast<std::size_t>(
            std::max_element(per_class.begin(), per_class.end()) - per_class.begin());
        if (most == class_count) continue;  // mostly unclassed pixels: nothing to say of it
        if (!palette.classes[most].thing) {
            throw std::invalid_argument("object colour " + std::to_string(id >> 16) + "," +
                                        std::to_string((id >> 8) & 0xffu) + "," +
                                        std::to_string(id & 0xffu) + " lies on stuff class '" +
                                        palette.classes[most].name + "' (" +
                                        std::to_string(per_class[most]) + " pixels)");
        }
        class_of[id] = static_cast<std::uint16_t>(most);
    }
    InstanceMap out;
    out.encoding = InstanceEncoding::kColour;
    out.id.assign(n, 0);
    for (std::size_t p = 0; p < n; ++p) {
        const auto it = packed[p] == 0 ? class_of.end() : class_of.find(packed[p]);
        if (it != class_of.end() && it->second == classes.class_index[p]) out.id[p] = packed[p];
    }
    out.objects = class_of.size();
    return out;
}

}  // namespace

InstanceEncoding parse_instance_encoding(std::string_view name) {
    if (name == "auto") return InstanceEncoding::kAuto;
    if (name == "kitti") return InstanceEncoding::kKitti;
    if (name == "cityscapes") return InstanceEncoding::kCityscapes;
    if (name == "colour") return InstanceEncoding::kColour;
    throw std::invalid_argument("instance encoding: must be auto, kitti, cityscapes or colour");
}

std::string instance_encoding_name(InstanceEncoding encoding) {
    switch (encoding) {
        case InstanceEncoding::kKitti:
            return "kitti";
        case InstanceEncoding::kCityscapes:
            return "cityscapes";
        case InstanceEncoding::kColour:
            return "colour";
        case InstanceEncoding::kAuto:
            break;
    }
    return "auto";
}

InstanceMap decode_instances(const IdImage& image, InstanceEncoding encoding,
                             const ClassImage& classes, const Palette& palette) {
    if (classes.class_index.empty()) {
        throw std::invalid_argument("instances need the semantic image's classes (--semantic)");
    }
    if (image.width_px() != classes.width_px || image.height_px() != classes.height_px) {
        throw std::invalid_argument("inputs do not match: instance image is " +
                                    size_text(image.width_px(), image.height_px()) +
                                    ", semantic image is " +
                                    size_text(classes.width_px, classes.height_px));
    }
    InstanceMap out;
    if (image.has_ids()) {
        if (encoding == InstanceEncoding::kColour) {
            throw std::invalid_argument(
                "16-bit ids where 8-bit RGB colours are expected (instance encoding colour)");
        }
        out = decode_ids(image.ids, encoding, classes, palette);
    } else {
        if (encoding == InstanceEncoding::kKitti || encoding == InstanceEncoding::kCityscapes) {
            throw std::invalid_argument(
                "8-bit samples where 16-bit " + instance_encoding_name(encoding) +
                " ids are expected (instance encoding " + instance_encoding_name(encoding) + ")");
        }
        out = decode_colours(image.colour, classes, palette);
    }
    out.width_px = classes.width_px;
    out.height_px = classes.height_px;
    return out;
}

void mark_object_outlines(std::vector<std::uint8_t>& depth_edge, const InstanceMap& instances,
                          const DisparityMap& disparity, const MatchBorder& border, double step_m,
                          int columns) {
    const int w = instances.width_px, h = instances.height_px;
    const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    if (!(step_m > 0.0) || columns <= 0 || !(border.fb_px_m > 0.0) || instances.id.size() != n ||
        disparity.disparity_px.size() != n || disparity.width_px != w) {
        return;
    }
    // Each object's median depth.
    std::unordered_map<std::uint32_t, std::vector<float>> disparities;
    for (std::size_t p = 0; p < n; ++p) {
        if (instances.id[p] != 0 && disparity.disparity_px[p] > 0.0f) {
            disparities[instances.id[p]].push_back(disparity.disparity_px[p]);
        }
    }
    std::unordered_map<std::uint32_t, double> depth_m;
    for (auto& [id, d] : disparities) {
        auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
        std::nth_element(d.begin(), mid, d.end());
        if (const double z = border.depth_m(double{*mid}); z > 0.0) depth_m[id] = z;
    }
    if (depth_m.empty()) return;
    if (depth_edge.size() != n) depth_edge.assign(n, 0);
    for (int v = 0; v < h; ++v) {
        const std::uint32_t* row = instances.id.data() + static_cast<std::size_t>(v) * w;
        std::uint8_t* edge = depth_edge.data() + static_cast<std::size_t>(v) * w;
        const float* disp = disparity.disparity_px.data() + static_cast<std::size_t>(v) * w;
        for (int u = 0; u < w; ++u) {
            const auto own = depth_m.find(row[u]);
            if (own == depth_m.end() || edge[u] != 0) continue;
            for (int k = std::max(0, u - columns); k <= std::min(w - 1, u + columns); ++k) {
                if (row[k] == row[u]) continue;
                const auto other = depth_m.find(row[k]);
                const double z = row[k] == 0              ? border.depth_m(double{disp[k]})
                                 : other != depth_m.end() ? other->second
                                                          : 0.0;
                if (z > 0.0 && z <= own->second - step_m) {
                    edge[u] = 1;
                    break;
                }
            }
        }
    }
}

std::vector<float> depth_of(const DisparityMap& disparity, const MatchBorder& border) {
    std::vector<float> out(disparity.disparity_px.size(), 0.0f);
    if (!(border.fb_px_m > 0.0)) return out;
    for (std::size_t p = 0; p < out.size(); ++p) {
        out[p] = static_cast<float>(border.depth_m(double{disparity.disparity_px[p]}));
    }
    return out;
}

}  // namespace cloud_analysis
