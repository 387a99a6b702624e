#pragma once

/// Per-class settings of the entity extractors (thing/stuff, clustering distance, minimum
/// points, size prior), loaded from assets/classes/entity_config.json (documented in
/// docs/entities.md).

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cloud_analysis {

/// Default location of the class config, relative to the source (or install) root.
inline constexpr const char* kDefaultClassConfigPath = "assets/classes/entity_config.json";

/// Settings of one class, keyed by its palette name.
struct ClassSettings {
    std::string name;                     ///< palette class name, e.g. "car"
    bool thing = false;                   ///< countable object (instances, prior-completed boxes)
    bool entity = true;                   ///< false: never becomes an entity (sky, void)
    double cluster_distance_m = 0.5;      ///< clustering distance at 10 m depth, metres, > 0
    double cluster_growth = 2.0;          ///< distance grows as (z / 10 m)^growth beyond 10 m, >= 0
    double cluster_distance_max_m = 3.0;  ///< cap of the grown clustering distance, metres
    /// Exponent of the growth of the distance across the viewing ray, horizontally (empty:
    /// cluster_growth, the same distance in every direction), in [0, cluster_growth].
    std::optional<double> cluster_cross_growth;
    /// Distance across the viewing ray at 10 m, horizontally, metres (empty:
    /// cluster_distance_m); in (0, cluster_distance_m].
    std::optional<double> cluster_cross_distance_m;
    int min_points = 50;        ///< clusters with fewer points are dropped, >= 1
    double prior_L_m = 0.0;     ///< typical length along the heading, metres (0 = none)
    double prior_W_m = 0.0;     ///< typical width across the heading, metres (0 = none)
    double prior_H_m = 0.0;     ///< typical height, metres (0 = none)
    double split_factor = 1.6;  ///< split a cluster longer than split_factor * prior_L_m
    double voxel_m = 0.0;       ///< voxel size used before clustering, metres (0 = none)
    /// Largest voxel edge, metres (0 = voxel_m): the edge doubles with depth as the clustering
    /// distance doubles (voxel_doubling_depths), up to this.
    double voxel_max_m = 0.0;
    int max_entities = 50;  ///< keep at most this many entities (largest first), >= 1
    /// Stuff only: the extractor takes every column_step-th pixel column of the class (1, 2, 4
    /// or 8), each point standing for column_step; 1 for things.
    int column_step = 1;
    bool has_prior() const { return prior_L_m > 0.0 && prior_W_m > 0.0 && prior_H_m > 0.0; }
    /// Depths (ascending, metres) at which the voxel edge doubles: where the clustering
    /// distance reaches 2, 4, ... times its value at 10 m, while the doubled edge stays within
    /// voxel_max_m and the doubled distance within cluster_distance_max_m. Sparse far points
    /// then share voxels (stereo depth error grows as z^2 anyway); empty without growth.
    std::vector<double> voxel_doubling_depths() const;
    /// Throws std::invalid_argument naming the bad field.
    void validate() const;
};

/// The whole table plus the settings used for classes it does not list.
struct ClassConfig {
    ClassSettings fallback;              ///< used for palette classes not listed
    std::vector<ClassSettings> classes;  ///< explicit settings, unique names
    /// Settings for `name` (the fallback, renamed, when not listed).
    ClassSettings find(std::string_view name) const;
    /// Throws std::invalid_argument naming the bad class and field.
    void validate() const;
};

/// Reads and validates a class config JSON file; throws std::runtime_error naming the file
/// and the bad member.
ClassConfig load_class_config(const std::filesystem::path& path);

/// The bundled config (assets/classes/entity_config.json of the source tree).
std::filesystem::path default_class_config_path();

/// Parses class config JSON text (same rules as load_class_config, `origin` names the source
/// in error messages).
ClassConfig parse_class_config(std::string_view text, std::string_view origin = "<text>");

}  // namespace cloud_analysis
