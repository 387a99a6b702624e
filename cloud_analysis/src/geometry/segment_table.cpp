#include <algorithm>
#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace cloud_analysis::geometry {

std::string segments_json(const SceneGeometry& g, const std::string& frame_id) {
    nlohmann::json segments = nlohmann::json::array();
    for (std::size_t k = 0; k < g.segments.size(); ++k) {
        const Segment& s = g.segments[k];
        segments.push_back(
            {{"index", k},
             {"class", s.label},
             {"pixels", s.pixels},
             {"cells", s.cells},
             {"box_px", {s.u0, s.v0, s.u1, s.v1}},
             {"top_m", s.top_m},
             {"top_q25_m", s.top_q25_m},
             {"low_m", s.low_m},
             {"width_m", s.width_m},
             {"thickness_m", s.thickness_m},
             {"depth_m", s.depth_m},
             {"near_m", s.near_m},
             {"far_m", s.far_m},
             {"green", s.green},
             {"occluded", s.occluded},
             {"horizontal_edges", s.horizontal_edges},
             {"tall", s.tall},
             {"lean", std::isfinite(s.lean) ? nlohmann::json(s.lean) : nlohmann::json()},
             {"lean_error",
              std::isfinite(s.lean_error) ? nlohmann::json(s.lean_error) : nlohmann::json()},
             {"chroma_r", s.chroma_r},
             {"chroma_g", s.chroma_g},
             {"chroma_b", s.chroma_b},
             {"fill", s.fill},
             {"luma", s.luma},
             {"luma_cv", s.luma_cv},
             {"grad", s.grad},
             {"rough_h", s.rough_h},
             {"rough_v", s.rough_v},
             {"disparity_spread", s.disparity_spread},
             {"rules_class", s.rules_label},
             {"features", s.features},
             {"vehicle_votes",
              std::isfinite(s.vehicle_votes) ? nlohmann::json(s.vehicle_votes) : nlohmann::json()},
             {"person_votes",
              std::isfinite(s.person_votes) ? nlohmann::json(s.person_votes) : nlohmann::json()}});
    }
    const nlohmann::json doc = {{"frame", frame_id},
                                {"ground",
                                 {{"found", g.ground.found},
                                  {"camera_height_m", g.ground.camera_height_m},
                                  {"pitch_deg", g.ground.pitch_deg},
                                  {"problem", g.ground.problem}}},
                                {"segments", std::move(segments)}};
    return doc.dump(1) + "\n";
}

ImageU16 segment_ids(const SceneGeometry& g, int width_px, int height_px) {
    ImageU16 out;
    out.width_px = width_px;
    out.height_px = height_px;
    out.values.assign(static_cast<std::size_t>(width_px) * height_px, 0);
    if (g.segment_of_pixel.size() != out.values.size()) return out;
    constexpr std::int32_t kMax = std::numeric_limits<std::uint16_t>::max() - 1;
    for (std::size_t p = 0; p < out.values.size(); ++p) {
        const std::int32_t s = g.segment_of_pixel[p];
        if (s >= 0) out.values[p] = static_cast<std::uint16_t>(std::min(s, kMax) + 1);
    }
    return out;
}

}  // namespace cloud_analysis::geometry
