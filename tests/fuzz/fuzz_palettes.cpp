// Palettes and per-class extractor settings (cloud-analysis), class tables (scene-render).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/entities/class_config.hpp"
#include "scene_viewer/assets/class_table.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        cloud_analysis::parse_palette(text, "fuzz");
    } catch (const std::exception&) {
    }
    try {
        cloud_analysis::parse_class_config(text, "fuzz");
    } catch (const std::exception&) {
    }
    try {
        scene_viewer::parse_class_table(text, "/nonexistent-fuzz/classes.json");
    } catch (const std::exception&) {
    }
    return 0;
}
