// glTF models: .glb containers and .gltf JSON (with data: URIs) through load_model_memory(), the
// parser load_model() calls after its bounded read. External URIs are looked up in a folder that
// does not exist, so they fail to read (the URI rules are still checked).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <vector>

#include "scene_viewer/assets/gltf_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const bool binary = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T';
    const std::vector<unsigned char> bytes(data, data + size);
    try {
        scene_viewer::load_model_memory(
            bytes, binary ? "/nonexistent-fuzz/model.glb" : "/nonexistent-fuzz/model.gltf");
    } catch (const std::exception&) {
    }
    return 0;
}
