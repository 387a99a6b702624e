#pragma once

/// Plain data shared by the cloud_analysis stages. No OpenCV or PCL types here: foreign types
/// stay behind .cpp files.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cloud_analysis {

using Rgb = std::array<std::uint8_t, 3>;

/// Rectified pinhole stereo rig: the left camera's intrinsics and the baseline.
struct StereoCamera {
    int width_px = 0;          ///< rectified image width in pixels
    int height_px = 0;         ///< rectified image height in pixels
    double fx_px = 0.0;        ///< focal length along x in pixels
    double fy_px = 0.0;        ///< focal length along y in pixels
    double cx_px = 0.0;        ///< left principal point x in pixels
    double cy_px = 0.0;        ///< principal point y in pixels
    double cx_right_px = 0.0;  ///< right principal point x in pixels (equals cx_px when unknown)
    double baseline_m = 0.0;   ///< distance between the optical centres in metres, > 0
};

/// One semantic class of a palette.
struct ClassInfo {
    std::string name;    ///< e.g. "car"
    int id = 0;          ///< numeric id written to entities (Cityscapes labelId by default)
    bool thing = false;  ///< countable object (split into instances) vs stuff (extents)
    Rgb colour{};        ///< colour of the class in the semantic image
};

/// Colour -> class table, loaded from assets/palettes/*.json.
struct Palette {
    std::string name;                ///< e.g. "cityscapes"
    std::vector<ClassInfo> classes;  ///< in file order; colours are unique
};

/// Class index value for pixels whose colour is not in the palette.
inline constexpr std::uint16_t kVoidClass = 0xFFFF;

/// Where the matcher's view ends on the left: a left-image pixel at column u and disparity d
/// has its match at column u - d of the right image, so at depth z nothing left of column
/// offset_px + fb_px_m / z can be matched. Unknown (no depth-dependent border) when fb_px_m is 0.
struct MatchBorder {
    double fb_px_m = 0.0;    ///< focal length x baseline: the disparity of depth z is fb / z
    double offset_px = 0.0;  ///< left minus right principal point x
    /// The leftmost column that can be matched at depth z; 0 when unknown.
    double left_column(double z_m) const {
        return fb_px_m > 0.0 && z_m > 0.0 ? offset_px + fb_px_m / z_m : 0.0;
    }
    /// The depth of disparity d: fb_px_m / (d - offset_px), metres; 0 when d is at most the
    /// offset or the rig is unknown.
    double depth_m(double disparity_px) const {
        const double d = disparity_px - offset_px;
        return fb_px_m > 0.0 && d > 0.0 ? fb_px_m / d : 0.0;
    }
};

/// The matching border of a rig.
inline MatchBorder match_border(const StereoCamera& c) {
    return {c.fx_px * c.baseline_m, c.cx_px - c.cx_right_px};
}

/// The point of pixel (u, v) at depth z_m in the rectified left camera's frame (x right, y
/// down, z forward, metres).
inline Eigen::Vector3d camera_point(const StereoCamera& c, double u_px, double v_px, double z_m) {
    return {(u_px - c.cx_px) * z_m / c.fx_px, (v_px - c.cy_px) * z_m / c.fy_px, z_m};
}

/// A metric point cloud in the rectified left camera frame (x right, y down, z forward,
/// metres), one entry per valid pixel, structure of arrays.
struct LabeledCloud {
    int width_px = 0;                        ///< source image width (for pixel indices)
    int height_px = 0;                       ///< source image height
    std::vector<Eigen::Vector3f> xyz_m;      ///< positions in metres
    std::vector<Rgb> colour;                 ///< left image colour at the pixel
    std::vector<std::uint16_t> class_index;  ///< index into Palette::classes, or kVoidClass
    std::vector<std::uint32_t> pixel;        ///< v * width_px + u of the source pixel
    MatchBorder border;                      ///< the rig's left matching border
    /// Per pixel (v * width_px + u): 1 on the far side of a depth step, where the disparity
    /// mixes two surfaces (depth_edge_band in reproject.hpp); empty when not computed.
    std::vector<std::uint8_t> depth_edge;
    /// Per pixel (v * width_px + u): the object the pixel belongs to in an instance image
    /// (InstanceMap::id, 0 = none); empty without an instance image.
    std::vector<std::uint32_t> instance_id;
    /// Per pixel, with an instance image: the depth of its disparity, metres (0 = none;
    /// depth_of in instances.hpp): what stands in front of an object where its outline ends.
    std::vector<float> depth_m;
    std::size_t size() const { return xyz_m.size(); }
};

/// The entity extractor's input: a labelled cloud's points split by palette class, each class in
/// pixel order (see ClassSelection for which points are kept).
struct ClassPoints {
    std::vector<std::vector<Eigen::Vector3f>> xyz_m;  ///< per palette class, metres
    std::vector<std::vector<std::uint32_t>> pixel;    ///< per class, v * width_px + u of each
                                                      ///< point; filled for classes that keep
                                                      ///< pixels (things), else empty
    std::vector<std::size_t> weight;  ///< per class: cloud points each point stands for (>= 1)
    int width_px = 0;                 ///< pixel grid of `pixel`; 0 when the pixels are unknown
    int height_px = 0;                ///< pixel grid height; 0 when the pixels are unknown
    /// The leftmost and rightmost image columns holding any point of the cloud: the edges of
    /// what stereo sees (the image's, or the border the matcher leaves without disparity).
    int first_column = 0;
    int last_column = 0;
    MatchBorder border;            ///< the rig's left matching border (depth-dependent)
    std::size_t cloud_points = 0;  ///< points of the whole cloud (every class and void)
    /// Per pixel of the grid: 1 on the far side of a depth step (LabeledCloud::depth_edge);
    /// empty when not computed.
    std::vector<std::uint8_t> depth_edge;
    /// Per pixel of the grid: the object the pixel belongs to (LabeledCloud::instance_id, 0 =
    /// none); empty without an instance image.
    std::vector<std::uint32_t> instance_id;
    /// Per pixel of the grid, with an instance image: the depth of its disparity, metres
    /// (LabeledCloud::depth_m); empty otherwise.
    std::vector<float> depth_m;
};

}  // namespace cloud_analysis
