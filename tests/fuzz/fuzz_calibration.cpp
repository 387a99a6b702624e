// Calibration files in every format cloud-analysis reads (KITTI cam_to_cam, KITTI raw, the
// simple key/value text, JSON).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "cloud_analysis/stereo/calibration.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        cloud_analysis::parse_calibration(text, "fuzz", cloud_analysis::CalibrationOptions{});
    } catch (const std::exception&) {
    }
    return 0;
}
