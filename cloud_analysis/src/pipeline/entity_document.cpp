#include "cloud_analysis/pipeline/entity_document.hpp"

#include <string>

#include <nlohmann/json.hpp>

#include "cloud_analysis/geometry/scene_geometry.hpp"

namespace cloud_analysis {

scene_schema::EntityDocument entity_document(const LoadedInputs& in, const AnalyseResult& r,
                                             const ExtractOptions& extract,
                                             const RunSettings& run) {
    // Fragments and smears too faint to be a thing are dropped, whatever made the class image.
    ExtractOptions options = extract;
    options.min_face_share = run.analyse.geometry.min_face_share;
    // A car segment's top lies at least car_min_height_m above the road (the geometry's car
    // rule); a car box cut from one that stays lower is a piece of something low.
    if (r.geometry) options.family_min_height_m = run.analyse.geometry.car_min_height_m;
    options.fx_px = r.camera.fx_px;
    options.fy_px = r.camera.fy_px;
    scene_schema::EntityDocument doc =
        r.points.xyz_m.empty() ? extract_entities(r.cloud, in.palette, r.camera, options)
                               : extract_entities(r.points, in.palette, options);
    doc.frame.id = in.paths.frame_id;
    if (r.geometry) {
        // Classes from geometry are guesses the labelled path does not make: less confidence.
        for (auto& e : doc.entities) e.confidence *= geometry::kConfidenceScale;
        const auto& g = r.geometry->ground;
        doc.extra["stereo_ground"] = {{"found", g.found},
                                      {"camera_height_m", g.camera_height_m},
                                      {"pitch_deg", g.pitch_deg},
                                      {"roll_deg", g.roll_deg},
                                      {"horizon_v_px", g.horizon_v_px},
                                      {"problem", g.problem}};
    }
    scene_schema::CameraIntrinsics cam;
    // The rig of the images as read (a frame analysed at half resolution is described at its
    // own): pixel u of the analysed image is (u + 0.5) / scale - 0.5 of the image read.
    const double scale = in.resolution_scale;
    cam.width_px = in.read_width_px > 0 ? in.read_width_px : r.camera.width_px;
    cam.height_px = in.read_height_px > 0 ? in.read_height_px : r.camera.height_px;
    cam.fx_px = r.camera.fx_px / scale;
    cam.fy_px = r.camera.fy_px / scale;
    cam.cx_px = (r.camera.cx_px + 0.5) / scale - 0.5;
    cam.cy_px = (r.camera.cy_px + 0.5) / scale - 0.5;
    cam.baseline_m = r.camera.baseline_m;
    doc.frame.camera = cam;
    nlohmann::json source = describe_run(in, run.analyse, run.tool_version);
    source["extract"] = {{"method", extract.method},
                         {"class_config", run.class_config},
                         {"row_model", extract.row_model}};
    if (!run.rig.is_null()) source["rig"] = run.rig;
    if (!r.instances.empty()) {
        // Things of the instance image's objects were taken whole, the rest clustered.
        std::size_t taken = 0;
        for (const auto& e : doc.entities) taken += e.extra.contains("instance_id") ? 1 : 0;
        source["instances"] = {{"encoding", instance_encoding_name(r.instances.encoding)},
                               {"objects", r.instances.objects},
                               {"entities", taken}};
    }
    doc.source = source;
    return doc;
}

std::string entity_json(const LoadedInputs& in, const AnalyseResult& r,
                        const ExtractOptions& extract, const RunSettings& run) {
    return scene_schema::dump_checked(entity_document(in, r, extract, run));
}

}  // namespace cloud_analysis
