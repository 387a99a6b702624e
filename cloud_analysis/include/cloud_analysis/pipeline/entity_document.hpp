#pragma once

/// The entity document of one analysed frame: the entities extracted from the analysis's cloud
/// (or its per-class points), the frame's id and camera, and the `source` block that says how
/// the file was made.

#include <string>
#include <vector>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/entities/extract.hpp"
#include "cloud_analysis/pipeline/pipeline.hpp"

namespace cloud_analysis {

/// How a run was configured, as the `source` block records it.
struct RunSettings {
    AnalyseOptions analyse;                ///< the analysis's settings (as given, before outputs
                                           ///< decide whether a cloud is built)
    std::string class_config = "default";  ///< class config file, "default" for the bundled one
    std::string tool_version;              ///< version of the tool that made the file
    nlohmann::json rig;                    ///< source.rig: how the analysis fitted the rig
                                           ///< (RigFit::describe), null = not written
};

/// The entities of analysis `r` of frame `in` (extract_entities on its per-class points when
/// the analysis made no cloud, else on the cloud; things seen over less than
/// geometry::GeometryOptions::min_face_share of their prior face dropped on both paths), with
/// frame.id, frame.camera and source (describe_run plus extract.method and the class config)
/// filled in.
scene_schema::EntityDocument entity_document(const LoadedInputs& in, const AnalyseResult& r,
                                             const ExtractOptions& extract, const RunSettings& run);

/// The same as the file's text, checked against the schema (scene_schema::dump_checked).
std::string entity_json(const LoadedInputs& in, const AnalyseResult& r,
                        const ExtractOptions& extract, const RunSettings& run);

}  // namespace cloud_analysis
