#pragma once

/// `cloud-analysis analyse` (the default command): one frame from files to written outputs.
/// `bench` times the same run.

#include <optional>
#include <vector>

#include <CLI/CLI.hpp>

#include "analysis_flags.hpp"
#include "cloud_analysis/io/io.hpp"
#include "cloud_analysis/pipeline/rig_fit.hpp"
#include "cloud_analysis/stereo/disparity.hpp"

namespace cloud_analysis::app {

/// Registers `analyse` on app and binds its flags to args (which must outlive parsing).
CLI::App* add_analyse_command(CLI::App& app, AnalyseArgs& args);

/// What one run measured.
struct RunReport {
    std::vector<cloud_analysis::StageTiming> timings;  ///< load, disparity, ..., write per output
    std::size_t points = 0;                            ///< points in the cloud
};

/// What a run reads before its expensive stages: the decoded frame, the extraction settings
/// and the optional GT disparity.
struct LoadedRun {
    cloud_analysis::LoadedInputs inputs;     ///< decoded images, calibration
    cloud_analysis::ExtractOptions extract;  ///< with the class config read
    cloud_analysis::RigFit fit;  ///< the analyse and extract options fitted to the frame's rig
    std::optional<cloud_analysis::DisparityMap> gt_disparity;  ///< --gt-disparity, when given
};

/// Checks the output flags and folders, reads the class config and the GT disparity, decodes
/// and checks the inputs and fits the settings to their rig. Throws before anything expensive
/// or written.
LoadedRun load_run(const AnalyseArgs& a);

/// The stages after decoding (disparity ... entity file and clouds written), with a matcher
/// made with run.fit's disparity options kept across frames: a frame already in memory, as from a
/// camera. Throws on failure, leaving no output behind.
RunReport analyse_loaded_and_write(const LoadedRun& run, const AnalyseArgs& a,
                                   cloud_analysis::DisparityMatcher& matcher);

/// One analysis from files to written outputs (load_run, then analyse_loaded_and_write); the
/// first timing is "load". Throws on failure, leaving no output behind.
RunReport analyse_and_write(const AnalyseArgs& a, cloud_analysis::DisparityMatcher& matcher);

/// As above with a matcher of the run's own.
RunReport analyse_and_write(const AnalyseArgs& a);

/// `analyse`: analyse_and_write, then --timings to stderr. Returns the exit code.
int run_analyse(const AnalyseArgs& a);

}  // namespace cloud_analysis::app
