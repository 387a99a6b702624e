// Batch frame lists (batch --list).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "cloud_analysis/pipeline/frame_list.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        cloud_analysis::parse_frame_list(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
    } catch (const std::exception&) {
    }
    return 0;
}
