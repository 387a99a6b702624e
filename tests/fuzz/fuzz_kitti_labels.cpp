// KITTI object label files (evaluate --labels, export-kitti's reference).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "cloud_analysis/evaluation/kitti_labels.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        cloud_analysis::parse_kitti_labels(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
    } catch (const std::exception&) {
    }
    return 0;
}
