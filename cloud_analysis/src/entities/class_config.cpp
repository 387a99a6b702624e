#include "cloud_analysis/entities/class_config.hpp"

#include <climits>
#include <cmath>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {
namespace {

void require(bool ok, const std::string& where, const std::string& rule) {
    if (!ok) throw std::invalid_argument(where + ": " + rule);
}

/// Reads the members present in `j` over `s` (missing members keep their value).
void read_settings(const nlohmann::json& j, const std::string& pointer, ClassSettings& s) {
    if (!j.is_object()) throw std::invalid_argument(pointer + ": must be an object");
    static const std::set<std::string> known = {"name",
                                                "thing",
                                                "entity",
                                                "cluster_distance_m",
                                                "cluster_growth",
                                                "cluster_distance_max_m",
                                                "min_points",
                                                "prior_L_m",
                                                "prior_W_m",
                                                "prior_H_m",
                                                "split_factor",
                                                "voxel_m",
                                                "voxel_max_m",
                                                "max_entities",
                                                "column_step",
                                                "cluster_cross_growth",
                                                "cluster_cross_distance_m",
                                                "comment"};
    for (const auto& item : j.items()) {
        if (known.count(item.key()) == 0) {
            throw std::invalid_argument(pointer + "/" + item.key() + ": unknown member");
        }
    }
    auto number = [&](const char* key, double& out) {
        if (!j.contains(key)) return;
        if (!j[key].is_number())
            throw std::invalid_argument(pointer + "/" + key + ": must be a number");
        out = j[key].get<double>();
    };
    auto integer = [&](const char* key, int& out) {
        if (!j.contains(key)) return;
        if (!j[key].is_number_integer() || j[key].get<long long>() < INT_MIN ||
            j[key].get<long long>() > INT_MAX) {
            throw std::invalid_argument(pointer + "/" + key + ": must be a 32-bit integer");
        }
        out = j[key].get<int>();
    };
    auto boolean = [&](const char* key, bool& out) {
        if (!j.contains(key)) return;
        if (!j[key].is_boolean())
            throw std::invalid_argument(pointer + "/" + key + ": must be a boolean");
        out = j[key].get<bool>();
    };
    if (j.contains("name")) {
        if (!j["name"].is_string())
            throw std::invalid_argument(pointer + "/name: must be a string");
        s.name = j["name"].get<std::string>();
    }
    boolean("thing", s.thing);
    boolean("entity", s.entity);
    number("cluster_distance_m", s.cluster_distance_m);
    number("cluster_growth", s.cluster_growth);
    number("cluster_distance_max_m", s.cluster_distance_max_m);
    if (j.contains("cluster_cross_growth")) {
        double g = 0.0;
        number("cluster_cross_growth", g);
        s.cluster_cross_growth = g;
    }
    if (j.contains("cluster_cross_distance_m")) {
        double d = 0.0;
        number("cluster_cross_distance_m", d);
        s.cluster_cross_distance_m = d;
    }
    integer("min_points", s.min_points);
    number("prior_L_m", s.prior_L_m);
    number("prior_W_m", s.prior_W_m);
    number("prior_H_m", s.prior_H_m);
    number("split_factor", s.split_factor);
    number("voxel_m", s.voxel_m);
    number("voxel_max_m", s.voxel_max_m);
    integer("max_entities", s.max_entities);
    integer("column_step", s.column_step);
}

}  // namespace

void ClassSettings::validate() const {
    const std::string where = "class '" + name + "'";
    require(cluster_distance_m > 0.0, where + " cluster_distance_m", "must be > 0");
    require(cluster_growth >= 0.0, where + " cluster_growth", "must be >= 0");
    require(!cluster_cross_growth ||
                (*cluster_cross_growth >= 0.0 && *cluster_cross_growth <= cluster_growth),
            where + " cluster_cross_growth", "must be >= 0 and <= cluster_growth");
    require(!cluster_cross_distance_m || (*cluster_cross_distance_m > 0.0 &&
                                          *cluster_cross_distance_m <= cluster_distance_m),
            where + " cluster_cross_distance_m", "must be > 0 and <= cluster_distance_m");
    require(cluster_distance_max_m >= cluster_distance_m, where + " cluster_distance_max_m",
            "must be >= cluster_distance_m");
    require(min_points >= 1, where + " min_points", "must be >= 1");
    require(prior_L_m >= 0.0, where + " prior_L_m", "must be >= 0");
    require(prior_W_m >= 0.0, where + " prior_W_m", "must be >= 0");
    require(prior_H_m >= 0.0, where + " prior_H_m", "must be >= 0");
    require(split_factor > 1.0, where + " split_factor", "must be > 1");
    require(voxel_m >= 0.0, where + " voxel_m", "must be >= 0");
    require(voxel_max_m == 0.0 || voxel_max_m >= voxel_m, where + " voxel_max_m",
            "must be 0 or >= voxel_m");
    require(max_entities >= 1, where + " max_entities", "must be >= 1");
    require(column_step == 1 || column_step == 2 || column_step == 4 || column_step == 8,
            where + " column_step", "must be 1, 2, 4 or 8");
    require(!thing || column_step == 1, where + " column_step",
            "must be 1 for a thing (its boxes need every point)");
}

std::vector<double> ClassSettings::voxel_doubling_depths() const {
    std::vector<double> depths;
    if (!(voxel_m > 0.0) || !(cluster_growth > 0.0)) return depths;
    for (int k = 1; k <= 7; ++k) {
        const double factor = static_cast<double>(1 << k);
        if (voxel_m * factor > voxel_max_m ||
            cluster_distance_m * factor > cluster_distance_max_m) {
            break;
        }
        // distance_at(z) = d10 * (z / 10 m)^growth = d10 * 2^k
        depths.push_back(10.0 * std::pow(factor, 1.0 / cluster_growth));
    }
    return depths;
}

ClassSettings ClassConfig::find(std::string_view name) const {
    for (const auto& c : classes) {
        if (c.name == name) return c;
    }
    ClassSettings s = fallback;
    s.name = std::string(name);
    return s;
}

void ClassConfig::validate() const {
    fallback.validate();
    std::set<std::string> names;
    for (const auto& c : classes) {
        require(!c.name.empty(), "classes", "every class needs a name");
        require(names.insert(c.name).second, "class '" + c.name + "'", "listed twice");
        c.validate();
    }
}

ClassConfig parse_class_config(std::string_view text, std::string_view origin) {
    const std::string where(origin);
    nlohmann::json j;
    try {
        j = scene_schema::parse_json(text);
    } catch (const scene_schema::SchemaError& e) {
        throw std::runtime_error(
            where + ": not JSON: " + (e.pointer().empty() ? "" : e.pointer() + ": ") + e.rule());
    }
    try {
        if (!j.is_object()) throw std::invalid_argument(": must be an object");
        for (const auto& item : j.items()) {
            if (item.key() != "comment" && item.key() != "defaults" && item.key() != "classes") {
                throw std::invalid_argument("/" + item.key() + ": unknown member");
            }
        }
        ClassConfig config;
        if (j.contains("defaults")) read_settings(j["defaults"], "/defaults", config.fallback);
        if (!j.contains("classes") || !j["classes"].is_array()) {
            throw std::invalid_argument("/classes: must be an array");
        }
        for (std::size_t i = 0; i < j["classes"].size(); ++i) {
            ClassSettings s = config.fallback;
            s.name.clear();
            const std::string pointer = "/classes/" + std::to_string(i);
            read_settings(j["classes"][i], pointer, s);
            if (s.name.empty()) throw std::invalid_argument(pointer + "/name: required");
            config.classes.push_back(s);
        }
        config.validate();
        return config;
    } catch (const std::invalid_argument& e) {
        throw std::runtime_error(where + ": " + e.what());
    }
}

ClassConfig load_class_config(const std::filesystem::path& path) {
    return parse_class_config(read_text_file(path), path.string());
}

std::filesystem::path default_class_config_path() {
    return bundled_palette_dir().parent_path() / "classes" / "entity_config.json";
}

}  // namespace cloud_analysis
