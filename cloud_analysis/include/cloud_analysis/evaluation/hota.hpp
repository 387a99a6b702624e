#pragma once

/// HOTA, Higher Order Tracking Accuracy (Luiten et al., IJCV 2020), as TrackEval computes it:
/// for every localisation threshold alpha in 0.05, 0.10, ..., 0.95, truth and tracks are
/// matched per frame by the Hungarian method on similarity weighted by the pair's alignment over
/// the whole drive; HOTA_alpha = sqrt(DetA_alpha * AssA_alpha); HOTA is their mean.

#include <cstdint>
#include <vector>

namespace cloud_analysis {

/// One frame as HOTA sees it: the scored truth and track ids and their similarity in [0, 1]
/// (truth-major: similarity[t * tracks.size() + k]).
struct HotaFrame {
    std::vector<std::int64_t> truth;
    std::vector<std::int64_t> tracks;
    std::vector<double> similarity;
};

/// HOTA and its parts, each the mean over the 19 thresholds.
struct HotaScore {
    double hota = 0.0;  ///< sqrt(DetA * AssA), averaged over alpha
    double deta = 0.0;  ///< detection accuracy TP / (TP + FN + FP)
    double assa = 0.0;  ///< association accuracy over the true positives
    double loca = 0.0;  ///< mean similarity of the true positives
};

/// HOTA of a drive; an empty drive (no truth, no tracks) scores 1. Throws
/// std::invalid_argument for a frame whose similarity matrix has the wrong size.
HotaScore hota(const std::vector<HotaFrame>& frames);

}  // namespace cloud_analysis
