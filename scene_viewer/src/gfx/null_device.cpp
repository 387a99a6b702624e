#include "scene_viewer/gfx/null_device.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace scene_viewer {

MeshHandle NullDevice::create_mesh(const MeshData& mesh) {
    meshes.push_back(mesh);
    return MeshHandle{static_cast<std::uint32_t>(meshes.size())};
}

TextureHandle NullDevice::create_texture(const ImageRgba8& /*image*/) {
    return TextureHandle{static_cast<std::uint32_t>(++textures_created)};
}

void NullDevice::destroy_mesh(MeshHandle /*mesh*/) { ++meshes_destroyed; }

void NullDevice::destroy_texture(TextureHandle /*texture*/) { ++textures_destroyed; }

void NullDevice::begin_frame(const FrameSetup& setup) {
    if (setup.fxaa && setup.msaa_samples > 1)
        throw std::invalid_argument("frame setup asks for both MSAA and FXAA");
    ++frames_begun;
    last_setup = setup;
    draws.clear();
}

void NullDevice::draw(const DrawCall& call) { draws.push_back(call); }

void NullDevice::end_frame() {
    ++frames_ended;
    if (last_setup.fxaa) ++fxaa_passes;
}

ImageRgba8 NullDevice::read_pixels() {
    ImageRgba8 image;
    image.width = last_setup.width_px;
    image.height = last_setup.height_px;
    image.pixels.resize(static_cast<std::size_t>(image.width) * image.height * 4);
    std::uint8_t rgba[4];
    for (int c = 0; c < 4; ++c) {
        rgba[c] = static_cast<std::uint8_t>(
            std::lround(std::clamp(last_setup.clear_colour[c], 0.0f, 1.0f) * 255.0f));
    }
    for (std::size_t i = 0; i < image.pixels.size(); i += 4)
        std::copy(rgba, rgba + 4, &image.pixels[i]);
    return image;
}

std::vector<float> NullDevice::read_depth() {
    return std::vector<float>(static_cast<std::size_t>(last_setup.width_px) * last_setup.height_px,
                              1.0f);
}

}  // namespace scene_viewer
