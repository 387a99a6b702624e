#include <algorithm>
#include <cmath>
#include <vector>

#include "scene_viewer/sensors/stereo_sensors.hpp"
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {

namespace {

/// SplitMix64 (Steele, Lea, Flood: Fast splittable pseudorandom number generators, OOPSLA 2014):
/// a counter-based stream, so every pixel's noise depends only on (seed, camera, index).
std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

/// A uniform number in (0, 1) from 53 random bits.
double unit_open(std::uint64_t bits) {
    return (static_cast<double>(bits >> 11) + 0.5) / 9007199254740992.0;
}

/// Standard normal sample number `index` of stream `stream` (Box-Muller).
double gaussian(std::uint64_t stream, std::uint64_t index) {
    const std::uint64_t a = splitmix64(stream ^ splitmix64(2 * index));
    const std::uint64_t b = splitmix64(stream ^ splitmix64(2 * index + 1));
    return std::sqrt(-2.0 * std::log(unit_open(a))) * std::cos(2.0 * kPi * unit_open(b));
}

/// Normalised 1D Gaussian kernel of radius ceil(3 sigma).
std::vector<float> gaussian_kernel(double sigma) {
    const int radius = static_cast<int>(std::ceil(3.0 * sigma));
    std::vector<float> k(2 * radius + 1);
    double sum = 0.0;
    for (int i = -radius; i <= radius; ++i) {
        const double v = std::exp(-0.5 * i * i / (sigma * sigma));
        k[i + radius] = static_cast<float>(v);
        sum += v;
    }
    for (float& v : k) v = static_cast<float>(static_cast<double>(v) / sum);
    return k;
}

/// Separable blur of an interleaved 3-channel float image, edges clamped.
void blur(std::vector<float>& img, int w, int h, double sigma) {
    const std::vector<float> k = gaussian_kernel(sigma);
    const int r = static_cast<int>(k.size() / 2);
    std::vector<float> tmp(img.size());
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                float s = 0.0f;
                for (int i = -r; i <= r; ++i) {
                    const int xx = std::clamp(x + i, 0, w - 1);
                    s += k[i + r] * img[(static_cast<std::size_t>(y) * w + xx) * 3 + c];
                }
                tmp[(static_cast<std::size_t>(y) * w + x) * 3 + c] = s;
            }
        }
    }
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                float s = 0.0f;
                for (int i = -r; i <= r; ++i) {
                    const int yy = std::clamp(y + i, 0, h - 1);
                    s += k[i + r] * tmp[(static_cast<std::size_t>(yy) * w + x) * 3 + c];
                }
                img[(static_cast<std::size_t>(y) * w + x) * 3 + c] = s;
            }
        }
    }
}

}  // namespace

ImageRgb8 apply_sensor_model(const ImageRgb8& image, int camera,
                             const SensorModelOptions& options) {
    options.validate();
    const int w = image.width, h = image.height;
    if (w <= 0 || h <= 0 || image.pixels.size() != static_cast<std::size_t>(w) * h * 3)
        throw std::invalid_argument("sensor model: image size does not match its pixel data");
    std::vector<float> v(image.pixels.begin(), image.pixels.end());
    if (options.blur_sigma_px > 0.0) blur(v, w, h, options.blur_sigma_px);
    const double gain = camera == 1 ? options.right_gain : 1.0;
    const std::uint64_t stream =
        splitmix64(options.seed ^ splitmix64(0x5e5e0000ULL + static_cast<std::uint64_t>(camera)));
    const double half_w = 0.5 * w, half_h = 0.5 * h;
    const double corner2 = half_w * half_w + half_h * half_h;
    ImageRgb8 out{w, h, std::vector<std::uint8_t>(image.pixels.size())};
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            double factor = gain;
            if (options.vignetting) {
                const double dx = x + 0.5 - half_w, dy = y + 0.5 - half_h;
                factor *= 1.0 - options.vignetting_strength * (dx * dx + dy * dy) / corner2;
            }
            const std::size_t p = static_cast<std::size_t>(y) * w + x;
            for (int c = 0; c < 3; ++c) {
                double value = static_cast<double>(v[p * 3 + c]) * factor;
                if (options.noise_sigma > 0.0)
                    value += options.noise_sigma * gaussian(stream, p * 3 + c);
                out.pixels[p * 3 + c] =
                    static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0, 255.0)));
            }
        }
    }
    return out;
}

namespace {

/// A thing pixel of the instance image (labelIds 24-33 have instances).
bool is_thing(std::uint16_t instance) {
    const int label = instance >> 8;
    return label >= 24 && label <= 33;
}

/// The bleed offset field: seeded values in [-1, 1] on a grid of `cell` px, bilinear between.
std::vector<float> offset_field(int w, int h, int cell, std::uint64_t seed) {
    const int gw = w / cell + 2, gh = h / cell + 2;
    const std::uint64_t stream = splitmix64(seed ^ 0x6c61626c65ULL);
    std::vector<float> grid(static_cast<std::size_t>(gw) * gh);
    for (std::size_t i = 0; i < grid.size(); ++i)
        grid[i] = static_cast<float>(2.0 * unit_open(splitmix64(stream ^ splitmix64(i))) - 1.0);
    std::vector<float> field(static_cast<std::size_t>(w) * h);
    for (int y = 0; y < h; ++y) {
        const int gy = y / cell;
        const float fy = static_cast<float>(y % cell) / cell;
        for (int x = 0; x < w; ++x) {
            const int gx = x / cell;
            const float fx = static_cast<float>(x % cell) / cell;
            const auto g = [&](int i, int j) { return grid[static_cast<std::size_t>(j) * gw + i]; };
            const float top = g(gx, gy) + fx * (g(gx + 1, gy) - g(gx, gy));
            const float bottom = g(gx, gy + 1) + fx * (g(gx + 1, gy + 1) - g(gx, gy + 1));
            field[static_cast<std::size_t>(y) * w + x] = top + fy * (bottom - top);
        }
    }
    return field;
}

}  // namespace

ImageRgb8 apply_label_bleed(const ImageRgb8& semantic, const ImageU16& instance, int max_px,
                            std::uint64_t seed) {
    const int w = semantic.width, h = semantic.height;
    const std::size_t count = static_cast<std::size_t>(w) * h;
    if (semantic.pixels.size() != count * 3 || instance.width != w || instance.height != h ||
        instance.values.size() != count)
        throw std::invalid_argument("label bleed: semantic and instance images differ in size");
    if (max_px <= 0) return semantic;
    constexpr int kCellPx = 16;
    const std::vector<float> field = offset_field(w, h, kCellPx, seed);
    ImageRgb8 out = semantic;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t p = static_cast<std::size_t>(y) * w + x;
            const int offset = static_cast<int>(std::lround(field[p] * max_px));
            const std::uint16_t self = instance.values[p];
            if (offset == 0 || (offset > 0) == is_thing(self)) continue;
            // The nearest pixel (chessboard rings) that grows into p or that p shrinks to.
            const auto donor = [&](std::uint16_t v) {
                return offset > 0 ? is_thing(v) : v != self;
            };
            bool found = false;
            for (int d = 1; d <= std::abs(offset) && !found; ++d) {
                for (int dy = -d; dy <= d && !found; ++dy) {
                    const int yy = y + dy;
                    if (yy < 0 || yy >= h) continue;
                    const int step = (dy == -d || dy == d) ? 1 : 2 * d;
                    for (int dx = -d; dx <= d && !found; dx += step) {
                        const int xx = x + dx;
                        if (xx < 0 || xx >= w) continue;
                        const std::size_t q = static_cast<std::size_t>(yy) * w + xx;
                        if (!donor(instance.values[q])) continue;
                        for (int c = 0; c < 3; ++c)
                            out.pixels[p * 3 + c] = semantic.pixels[q * 3 + c];
                        found = true;
                    }
                }
            }
        }
    }
    return out;
}

}  // namespace scene_viewer
