#pragma once

/// The bundled synthetic sample (samples/synthetic) as the inputs of one analysis, for the
/// tests that run the pipeline on it.

#include <filesystem>

#include "cloud_analysis/pipeline/pipeline.hpp"

namespace test_samples {

inline const std::filesystem::path kSynthetic =
    std::filesystem::path(STEREOSCENE_SAMPLES_DIR) / "synthetic";

/// left.png, right.png, semantic.png and calib.yaml of the sample, frame "synthetic-street".
inline cloud_analysis::InputPaths synthetic_paths() {
    cloud_analysis::InputPaths p;
    p.left = kSynthetic / "left.png";
    p.right = kSynthetic / "right.png";
    p.semantic = kSynthetic / "semantic.png";
    p.calibration = kSynthetic / "calib.yaml";
    p.frame_id = "synthetic-street";
    return p;
}

}  // namespace test_samples
