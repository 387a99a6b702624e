#pragma once

/// The thing classes of the "instances" extractor: a class's points clustered, each cluster
/// cleaned of smear, fitted, split when oversized and refitted, the candidates suppressed
/// (shadows, nested fragments) and the largest kept as entities.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <scene_schema/entities.hpp>

#include "cloud_analysis/entities/candidate.hpp"
#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/support/task_queue.hpp"

namespace cloud_analysis::instances {

/// Entities of thing class `info` made on `queue`: clustered by this task, then one task per
/// cluster of at least min_points (largest first, at the front of the queue); the last of
/// them to finish makes the class's entities, from the candidates in cluster order, into `out`.
void queue_things_of_class(TaskQueue& queue, const ClassInfo& info,
                           const std::vector<Eigen::Vector3f>& pts,
                           const std::vector<std::uint32_t>& pixels, const PixelGrid& grid,
                           const ClassSettings& settings, const PendingGround& pending_ground,
                           const ExtractOptions& options, std::vector<scene_schema::Entity>& out);

}  // namespace cloud_analysis::instances
