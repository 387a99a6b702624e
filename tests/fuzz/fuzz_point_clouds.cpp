// Point clouds (.ply, .pcd, .xyz) as scene-render --cloud reads them; the first byte picks the
// extension so one corpus reaches all three readers.
#include <cstddef>
#include <cstdint>
#include <exception>

#include "fuzz_file.hpp"
#include "scene_viewer/render/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static const char* const kNames[] = {"cloud.ply", "cloud.pcd", "cloud.xyz"};
    const char* name = data[0] == 'p' ? kNames[0] : data[0] == '#' ? kNames[1] : kNames[2];
    try {
        scene_viewer::read_point_cloud(stereoscene_fuzz::input_file(data, size, name));
    } catch (const std::exception&) {
    }
    return 0;
}
