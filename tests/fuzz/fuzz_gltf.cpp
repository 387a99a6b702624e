// glTF models: .glb containers and .gltf JSON (with data: URIs) through load_model().
#include <cstddef>
#include <cstdint>
#include <exception>

#include "fuzz_file.hpp"
#include "scene_viewer/assets/gltf_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const bool binary = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T';
    try {
        scene_viewer::load_model(
            stereoscene_fuzz::input_file(data, size, binary ? "model.glb" : "model.gltf"));
    } catch (const std::exception&) {
    }
    return 0;
}
