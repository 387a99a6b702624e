#pragma once

/// The 2D-label mode of `cloud-analysis evaluate` (--labels-2d): entity files, one or a batch
/// folder of them, scored against boxes drawn on the images (cloud_analysis/evaluation/
/// labels_2d.hpp).

#include <CLI/CLI.hpp>

#include "cloud_analysis/evaluation/report.hpp"
#include "evaluate.hpp"

namespace cloud_analysis::app {

/// Registers --labels-2d and its matching flags on `evaluate`.
void add_labels_2d_flags(CLI::App* sub, EvaluateArgs& args);

/// Throws CLI::ValidationError when flags of another mode are given with --labels-2d.
void check_labels_2d_flags(const EvaluateArgs& args);

/// Scores --entities (a file, or a folder holding <frame>.json for every labelled frame)
/// against --labels-2d into the report. Throws std::runtime_error naming the file at fault.
void evaluate_labels_2d(const EvaluateArgs& args, EvaluationReport& report);

}  // namespace cloud_analysis::app
