#pragma once

/// Thing clusters found in image space ("image" clustering of the instances extractor).

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/entities/cluster.hpp"

namespace cloud_analysis::instances {

/// Image-space connected components refined by depth: points of neighbouring pixels (within
/// radius_px, to hop small disparity holes) are linked when their 3D distance is below the
/// depth-grown clustering distance.
std::vector<Indices> image_components(const std::vector<Eigen::Vector3f>& pts,
                                      const std::vector<std::uint32_t>& pixels,
                                      const PixelGrid& grid, const ClusterOptions& co,
                                      int radius_px);

}  // namespace cloud_analysis::instances
