#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "cloud_analysis/support/select.hpp"
#include "derive_semantics_internal.hpp"

namespace cloud_analysis::geometry {

bool split_into_vehicle_pieces(Grid& g, std::vector<int>& parent, const Rig& rig,
                               const GeometryOptions& o, const std::vector<char>& split) {
    struct SegmentCells {
        std::vector<int> cells;
        std::vector<Eigen::Vector3d> footprint;  ///< (x, z, pixels) of each cell
    };
    std::unordered_map<int, SegmentCells> by_segment;
    for (int i = 0; i < static_cast<int>(g.cells.size()); ++i) {
        const Cell& c = g.cells[static_cast<std::size_t>(i)];
        if (c.segment < 0 || parent[static_cast<std::size_t>(i)] < 0 ||
            !split[static_cast<std::size_t>(c.segment)]) {
            continue;
        }
        const int column_bin = i / kLayers;
        const double z = rig.fb / g.bin_centre[static_cast<std::size_t>(column_bin % g.bins_d)];
        const double u = ((column_bin / g.bins_d) + 0.5) * o.column_bin_px;
        SegmentCells& s = by_segment[c.segment];
        s.cells.push_back(i);
        s.footprint.emplace_back((u - rig.cx) * z / rig.fx, z, c.count);
    }
    bool changed = false;
    for (auto& [segment, s] : by_segment) {
        const auto frame = footprint_axis(s.footprint);
        if (!frame) continue;
        const auto& [mean, axis] = *frame;
        std::vector<double> along;
        along.reserve(s.footprint.size());
        for (const auto& p : s.footprint) along.push_back(axis.dot(p.head<2>() - mean));
        std::vector<double> sorted = along;
        const auto [lo, hi] = quantiles(sorted, 0.02, 0.98);  // as Segment::width_m
        const int pieces = static_cast<int>(std::lround((hi - lo) / o.vehicle_piece_m));
        if (pieces < 2) continue;
        const double step = (hi - lo) / pieces;
        std::vector<int> root(static_cast<std::size_t>(pieces), -1);
        for (std::size_t k = 0; k < s.cells.size(); ++k) {
            const int piece =
                std::clamp(static_cast<int>(std::floor((along[k] - lo) / step)), 0, pieces - 1);
            int& r = root[static_cast<std::size_t>(piece)];
            if (r < 0) r = s.cells[k];
            parent[static_cast<std::size_t>(s.cells[k])] = r;
        }
        changed = true;
    }
    return changed;
}

}  // namespace cloud_analysis::geometry
