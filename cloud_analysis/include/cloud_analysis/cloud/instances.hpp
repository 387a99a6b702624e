#pragma once

/// Instance images as input: which object each pixel of the left view belongs to, where a
/// dataset (KITTI, Cityscapes, CARLA) or a panoptic segmentation network already separates
/// them. Decoded against the semantic image's classes, so that every pixel with an object id
/// carries that object's class (docs/clouds.md, "Instance images").

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/cloud/types.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {

/// How an instance image stores its objects.
enum class InstanceEncoding {
    kAuto,        ///< 16-bit: KITTI or Cityscapes, whichever agrees with the semantic image;
                  ///< 8-bit RGB: colours
    kKitti,       ///< 16-bit, labelId = v >> 8, instance = v & 0xff (0 = none; KITTI 2015)
    kCityscapes,  ///< 16-bit, v = labelId * 1000 + instance for objects, v = labelId for
                  ///< the rest (Cityscapes *_instanceIds.png)
    kColour,      ///< 8-bit RGB, one colour per object, black = none (CARLA-style renders)
};

/// "auto", "kitti", "cityscapes" or "colour"; throws std::invalid_argument for another name.
InstanceEncoding parse_instance_encoding(std::string_view name);

/// The encoding's name as parse_instance_encoding reads it.
std::string instance_encoding_name(InstanceEncoding encoding);

/// The object of every pixel of the left view.
struct InstanceMap {
    int width_px = 0;   ///< columns
    int height_px = 0;  ///< rows
    /// Per pixel (v * width_px + u): the object's id as the file stores it (KITTI and
    /// Cityscapes: the 16-bit value; colours: 0xRRGGBB), 0 for no object. A pixel keeps its id
    /// only when its class (ClassImage) is the object's class.
    std::vector<std::uint32_t> id;
    InstanceEncoding encoding = InstanceEncoding::kAuto;  ///< the encoding decoded (never kAuto)
    std::size_t objects = 0;                              ///< distinct ids
    std::size_t class_agreement_permille = 0;  ///< 16-bit: pixels whose class in the file is the
                                               ///< semantic image's, per mille of classed pixels
    bool empty() const { return id.empty(); }
};

/// Decodes `image` against the pixel classes of the same view (classify_pixels). Throws
/// std::invalid_argument with a one-line reason when the sizes differ, the depth does not fit
/// the encoding (8-bit where 16-bit ids are asked for, or the reverse), the 16-bit classes
/// disagree with the semantic image on more than a tenth of the pixels both class (0 classes
/// nothing), or an object
/// lies on a stuff class (its id's class for KITTI and Cityscapes, the class of most of its
/// pixels for colours).
InstanceMap decode_instances(const IdImage& image, InstanceEncoding encoding,
                             const ClassImage& classes, const Palette& palette);

/// Marks in `depth_edge` (per pixel, 1 on the far side of a depth step; see depth_edge_band
/// in reproject.hpp, sized like the map or empty, then filled with 0 first) the pixels of an
/// object within `columns` columns of a pixel nearer than the object by at least `step_m`: a
/// pixel of another object (its median depth) or of no object (its own depth: a trunk, a pole
/// or a sign in front of a car), depths fb / (d - offset) of `border` and the object's median.
/// There the matcher's window straddles the nearer surface's outline and the disparity is that
/// surface's (foreground fattening). Across rows depth_edge_band marks such pixels for every
/// surface; across columns only the instance image tells an outline from a surface seen along the
/// viewing ray. Does nothing when the sizes differ, step_m <= 0 or columns <= 0.
void mark_object_outlines(std::vector<std::uint8_t>& depth_edge, const InstanceMap& instances,
                          const DisparityMap& disparity, const MatchBorder& border, double step_m,
                          int columns);

/// Per pixel of `disparity`, its depth fb / (d - offset) of `border`, metres; 0 where the
/// disparity is missing or at most the offset, or the border is unknown.
std::vector<float> depth_of(const DisparityMap& disparity, const MatchBorder& border);

}  // namespace cloud_analysis
