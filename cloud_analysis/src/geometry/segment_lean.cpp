// Whether a car candidate stands upright below its waist: the lean of its lower body's
// surface, measured per column band (docs/stereo-only.md "Upright lower body").
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "cloud_analysis/support/select.hpp"
#include "cloud_analysis/support/task_queue.hpp"
#include "derive_semantics_internal.hpp"

namespace cloud_analysis::geometry {
namespace {

/// Per measured segment (slot), per column band: (height, depth) of its lower body's pixels.
using LowerBody = std::vector<std::vector<std::vector<std::pair<double, double>>>>;

/// The pixels 0.25-0.65 m above the road of the segments with a slot (slot[segment] >= 0) in
/// rows [v_begin, v_end) and `columns`, appended to their slot's column band in `bands`.
void lower_body_rows(const Grid& grid, const DisparityMap& disparity, const Rig& rig,
                     int column_bin_px, ColumnRange columns, const std::vector<int>& slot,
                     std::size_t v_begin, std::size_t v_end, LowerBody& bands) {
    constexpr double kLow = 0.25, kHigh = 0.65;  // metres above the road
    const auto w = static_cast<std::size_t>(disparity.width_px);
    for (auto v = v_begin; v < v_end; ++v) {
        for (int u = columns.u_begin; u < columns.u_end; ++u) {
            const std::size_t p = v * w + static_cast<std::size_t>(u);
            const std::int32_t cell = grid.pixel_cell[p];
            if (cell < 0) continue;
            const int s = grid.cells[static_cast<std::size_t>(cell)].segment;
            if (s < 0 || slot[static_cast<std::size_t>(s)] < 0) continue;
            const double height = double{grid.pixel_height[p]};
            if (height < kLow || height > kHigh) continue;
            const double d = double{disparity.disparity_px[p]} - rig.offset;
            if (!(d > 0.0)) continue;
            bands[static_cast<std::size_t>(slot[static_cast<std::size_t>(s)])]
                 [static_cast<std::size_t>(u / column_bin_px)]
                     .emplace_back(height, rig.fb / d);
        }
    }
}

/// lower_body_rows over the whole image, by bands of rows (row_bands) on the path's threads,
/// each band's pixels appended after the previous band's, as one pass would list them; `slots`
/// segments have a slot.
LowerBody lower_body_pixels(const Grid& grid, const DisparityMap& disparity, const Rig& rig,
                            const GeometryOptions& o, ColumnRange columns,
                            const std::vector<int>& slot, std::size_t slots) {
    const int w = disparity.width_px;
    const auto rows = static_cast<int>(grid.pixel_cell.size() / static_cast<std::size_t>(w));
    const auto band_count = static_cast<std::size_t>((w + o.column_bin_px - 1) / o.column_bin_px);
    const std::size_t parts = row_bands(rows, o.threads);
    std::vector<LowerBody> part_bands(parts, LowerBody(slots, LowerBody::value_type(band_count)));
    for_each_chunk(static_cast<std::size_t>(rows), parts,
                   [&](std::size_t k, std::size_t first, std::size_t last) {
                       lower_body_rows(grid, disparity, rig, o.column_bin_px, columns, slot, first,
                                       last, part_bands[k]);
                   });
    LowerBody& bands = part_bands.front();
    for (std::size_t k = 1; k < parts; ++k) {
        for (std::size_t i = 0; i < slots; ++i) {
            for (std::size_t b = 0; b < band_count; ++b) {
                auto& to = bands[i][b];
                const auto& from = part_bands[k][i][b];
                to.insert(to.end(), from.begin(), from.end());
            }
        }
    }
    return std::move(bands);
}

}  // namespace

void measure_leans(const Grid& grid, const DisparityMap& disparity, const Rig& rig,
                   const GeometryOptions& o, std::uint16_t car, const std::vector<char>& fresh,
                   ColumnRange columns, std::vector<Segment>& segments) {
    constexpr std::size_t kMinPixels = 6;     // a band's, for a slope
    constexpr double kMinHeightSpread = 0.1;  // metres: a band's, for a slope
    // Each measured segment's place among the lower-body lists (-1: not measured).
    std::vector<int> slot(segments.size(), -1);
    std::size_t slots = 0;
    for (std::size_t s = 0; s < segments.size(); ++s) {
        if (fresh[s] && segments[s].class_index == car) slot[s] = static_cast<int>(slots++);
    }
    const LowerBody bands = lower_body_pixels(grid, disparity, rig, o, columns, slot, slots);
    std::vector<double> depths, slopes, deviations;
    for (std::size_t s = 0; s < segments.size(); ++s) {
        if (slot[s] < 0) continue;
        slopes.clear();
        for (auto& px : bands[static_cast<std::size_t>(slot[s])]) {
            if (px.size() < kMinPixels) continue;
            depths.clear();
            for (const auto& hz : px) depths.push_back(hz.second);
            const double mid = quantile(depths, 0.5);
            const double reach = std::max(0.5, 2.0 * o.disparity_noise_px * mid * mid / rig.fb);
            double count = 0, h = 0, z = 0, hh = 0, hz = 0;
            for (const auto& [ph, pz] : px) {
                if (std::abs(pz - mid) > reach) continue;
                count += 1;
                h += ph;
                z += pz;
                hh += ph * ph;
                hz += ph * pz;
            }
            if (count < kMinPixels) continue;
            // A band of pixels spread evenly over kMinHeightSpread has this variance at least.
            const double shh = hh - h * h / count;
            if (!(shh > count * kMinHeightSpread * kMinHeightSpread / 12.0)) continue;
            slopes.push_back((hz - h * z / count) / shh);
        }
        if (slopes.size() < 3) continue;
        const double lean = quantile(slopes, 0.5);
        deviations.clear();
        for (double b : slopes) deviations.push_back(std::abs(b - lean));
        segments[s].lean = lean;
        segments[s].lean_error =
            1.4826 * quantile(deviations, 0.5) / std::sqrt(static_cast<double>(slopes.size()));
    }
}

}  // namespace cloud_analysis::geometry
