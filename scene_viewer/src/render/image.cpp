#include "scene_viewer/render/image.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "scene_viewer/assets/image_io.hpp"
#include "stereoscene/support/atomic_file.hpp"

namespace scene_viewer {

ImageRgba8 make_image(int width, int height, Rgb8 colour, std::uint8_t alpha) {
    ImageRgba8 image;
    image.width = width;
    image.height = height;
    image.pixels.resize(static_cast<std::size_t>(width) * height * 4);
    for (std::size_t i = 0; i < image.pixels.size(); i += 4) {
        image.pixels[i] = colour[0];
        image.pixels[i + 1] = colour[1];
        image.pixels[i + 2] = colour[2];
        image.pixels[i + 3] = alpha;
    }
    return image;
}

void write_png(const std::filesystem::path& path, const ImageRgba8& image, int zlib_level) {
    const std::vector<unsigned char> bytes = encode_png(image, zlib_level);
    if (path == "-") {
        if (std::fwrite(bytes.data(), 1, bytes.size(), stdout) != bytes.size() ||
            std::fflush(stdout) != 0) {
            throw std::runtime_error("cannot write the PNG to stdout");
        }
        return;
    }
    stereoscene::support::write_file_atomic(
        path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

ImageRgba8 resize_nearest(const ImageRgba8& image, int width, int height) {
    ImageRgba8 out;
    out.width = width;
    out.height = height;
    out.pixels.resize(static_cast<std::size_t>(width) * height * 4);
    for (int y = 0; y < height; ++y) {
        const int sy = static_cast<int>((static_cast<long long>(y) * image.height) / height);
        for (int x = 0; x < width; ++x) {
            const int sx = static_cast<int>((static_cast<long long>(x) * image.width) / width);
            std::memcpy(&out.pixels[(static_cast<std::size_t>(y) * width + x) * 4],
                        pixel_at(image, sx, sy), 4);
        }
    }
    return out;
}

void composite_over(ImageRgba8& render, const ImageRgba8& background, float opacity, Rgb8 clear) {
    if (render.width != background.width || render.height != background.height) {
        throw std::invalid_argument("composite: background size differs from the render");
    }
    for (std::size_t i = 0; i < render.pixels.size(); i += 4) {
        const float alpha = render.pixels[i + 3] / 255.0f;
        for (int c = 0; c < 3; ++c) {
            const float b = background.pixels[i + c];
            // The model's premultiplied share: the pixel minus its uncovered share of `clear`.
            const float model = render.pixels[i + c] - (1.0f - alpha) * clear[c];
            const float v = alpha > 0.0f ? b + opacity * (model - alpha * b) : b;
            render.pixels[i + c] = static_cast<std::uint8_t>(std::clamp(v, 0.0f, 255.0f) + 0.5f);
        }
        render.pixels[i + 3] = 255;
    }
}

}  // namespace scene_viewer
