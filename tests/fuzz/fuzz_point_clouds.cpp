// Point clouds (.ply, .pcd, .xyz) through the stream parser read_point_cloud(path) calls after
// its file checks; the first byte picks the extension so one corpus reaches all three readers.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>

#include "scene_viewer/assets/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static const char* const kNames[] = {"cloud.ply", "cloud.pcd", "cloud.xyz"};
    const char* name = data[0] == 'p' ? kNames[0] : data[0] == '#' ? kNames[1] : kNames[2];
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    try {
        scene_viewer::read_point_cloud(in, name);
    } catch (const std::exception&) {
    }
    return 0;
}
