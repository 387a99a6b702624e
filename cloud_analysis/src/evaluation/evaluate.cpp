#include "cloud_analysis/evaluation/evaluate.hpp"
#include "cloud_analysis/support/box_axes.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "cloud_analysis/cloud/semantic.hpp"
#include "cloud_analysis/io/io.hpp"

namespace cloud_analysis {
namespace {

/// Pixel (u, v) with disparity d to the camera frame (rectified pinhole, Q of Hartley &
/// Zisserman / OpenCV stereoRectify).
Eigen::Vector3f reproject_pixel(const StereoCamera& cam, int u, int v, double d) {
    const double doffs = cam.cx_right_px != 0.0 ? cam.cx_px - cam.cx_right_px : 0.0;
    return camera_point(cam, u, v, cam.fx_px * cam.baseline_m / (d - doffs)).cast<float>();
}

void check_camera(const StereoCamera& cam) {
    if (!(cam.fx_px > 0.0 && cam.fy_px > 0.0))
        throw std::invalid_argument("camera: fx/fy must be > 0");
    if (!(cam.baseline_m > 0.0)) throw std::invalid_argument("camera: baseline_m must be > 0");
}

}  // namespace

double GtCar::range_m() const { return std::hypot(centroid_m.x(), centroid_m.z()); }

void GtCarOptions::validate() const {
    if (car_label_id < 0 || car_label_id > 255)
        throw std::invalid_argument("car_label_id: must be in 0..255");
    if (!(occluder_gap_m >= 0.0)) throw std::invalid_argument("occluder_gap_m: must be >= 0");
    if (min_interior_px < 1) throw std::invalid_argument("min_interior_px: must be >= 1");
}

void CarMatchOptions::validate() const {
    if (car_class.empty()) throw std::invalid_argument("car_class: must not be empty");
    if (!(footprint_margin_m >= 0.0))
        throw std::invalid_argument("footprint_margin_m: must be >= 0");
    if (!(min_inside_fraction > 0.0 && min_inside_fraction <= 1.0)) {
        throw std::invalid_argument("min_inside_fraction: must be in (0, 1]");
    }
    if (!(max_footprint_area_m2 > 0.0))
        throw std::invalid_argument("max_footprint_area_m2: must be > 0");
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m: must be > 0");
    if (!(fallback_min_iou > 0.0 && fallback_min_iou <= 1.0))
        throw std::invalid_argument("fallback_min_iou: must be in (0, 1]");
}

double CarEvaluation::recall() const {
    return gt_owed == 0 ? 1.0 : static_cast<double>(gt_owed_matched) / static_cast<double>(gt_owed);
}

double CarEvaluation::precision() const {
    return entities_in_range == 0
               ? 1.0
               : static_cast<double>(entities_matched) / static_cast<double>(entities_in_range);
}

double CarEvaluation::precision_scorable() const {
    const std::size_t scorable = entities_in_range - entities_unscorable;
    return scorable == 0 ? 1.0
                         : static_cast<double>(entities_matched) / static_cast<double>(scorable);
}

double CarEvaluation::mean_centre_distance_m() const {
    if (matches.empty()) return 0.0;
    double sum = 0.0;
    for (const auto& m : matches) sum += m.centre_distance_m;
    return sum / static_cast<double>(matches.size());
}

double footprint_inside_fraction(const scene_schema::Entity& entity,
                                 const std::vector<Eigen::Vector3f>& points_m, double margin_m) {
    if (points_m.empty()) return 0.0;
    const BoxAxes axes(entity.theta);
    const double half_l = entity.L / 2.0 + margin_m, half_w = entity.W / 2.0 + margin_m;
    std::size_t inside = 0;
    for (const auto& p : points_m) {
        const double dx = double{p.x()} - entity.x, dz = double{p.z()} - entity.z;
        if (std::abs(axes.along(dx, dz)) <= half_l && std::abs(axes.across(dx, dz)) <= half_w) {
            ++inside;
        }
    }
    return static_cast<double>(inside) / static_cast<double>(points_m.size());
}

std::optional<Eigen::Vector4d> projected_box_px(const scene_schema::Entity& entity,
                                                const StereoCamera& camera, int width_px,
                                                int height_px) {
    const double c = std::cos(entity.theta), s = std::sin(entity.theta);
    // Length along the heading (cos t, 0, -sin t), width along (sin t, 0, cos t).
    const Eigen::Vector3d along(c, 0.0, -s), across(s, 0.0, c),
        centre(entity.x, entity.y, entity.z);
    double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
    for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p =
            centre + ((corner & 1) ? 0.5 : -0.5) * entity.L * along +
            ((corner & 2) ? 0.5 : -0.5) * entity.W * across +
            Eigen::Vector3d(0.0, (corner & 4) ? 0.5 * entity.H : -0.5 * entity.H, 0.0);
        if (p.z() < 0.1) return std::nullopt;
        // Pixel centres at integer u, v: the pixel-edge coordinate is u + 0.5.
        const double u = camera.fx_px * p.x() / p.z() + camera.cx_px + 0.5;
        const double v = camera.fy_px * p.y() / p.z() + camera.cy_px + 0.5;
        u0 = std::min(u0, u);
        u1 = std::max(u1, u);
        v0 = std::min(v0, v);
        v1 = std::max(v1, v);
    }
    u0 = std::clamp(u0, 0.0, double(width_px));
    u1 = std::clamp(u1, 0.0, double(width_px));
    v0 = std::clamp(v0, 0.0, double(height_px));
    v1 = std::clamp(v1, 0.0, double(height_px));
    if (!(u1 > u0 && v1 > v0)) return std::nullopt;
    return Eigen::Vector4d(u0, v0, u1, v1);
}

double rect_iou(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
    const auto area = [](const Eigen::Vector4d& r) {
        return std::max(0.0, r[2] - r[0]) * std::max(0.0, r[3] - r[1]);
    };
    const Eigen::Vector4d inter(std::max(a[0], b[0]), std::max(a[1], b[1]), std::min(a[2], b[2]),
                                std::min(a[3], b[3]));
    const double i = area(inter), u = area(a) + area(b) - i;
    return u > 0.0 ? i / u : 0.0;
}

float own_surface_min_depth_m(std::vector<GtDepth> points, const GtCarOptions& options) {
    options.validate();
    if (points.empty() || options.occluder_gap_m == 0.0) return 0.0f;
    std::sort(points.begin(), points.end(),
              [](const GtDepth& a, const GtDepth& b) { return a.z_m < b.z_m; });
    float best_z = points.front().z_m;
    std::size_t best_interior = 0, best_size = 0;
    for (std::size_t begin = 0; begin < points.size();) {
        std::size_t end = begin + 1, interior = points[begin].interior ? 1 : 0;
        while (end < points.size() &&
               double{points[end].z_m - points[end - 1].z_m} <= options.occluder_gap_m) {
            interior += points[end].interior ? 1 : 0;
            ++end;
        }
        const std::size_t size = end - begin;
        if (interior > best_interior || (interior == best_interior && size > best_size)) {
            best_interior = interior;
            best_size = size;
            best_z = points[begin].z_m;
        }
        begin = end;
    }
    return best_z;
}

std::vector<int> label_border_distance_px(const std::vector<std::uint16_t>& labels, int width_px,
                                          int height_px) {
    const int far = width_px + height_px;
    std::vector<int> d(labels.size(), far);
    const auto relax = [&](int u, int v, int nu, int nv) {
        if (nu < 0 || nv < 0 || nu >= width_px || nv >= height_px) return;
        const std::size_t i = static_cast<std::size_t>(v) * width_px + u;
        const std::size_t n = static_cast<std::size_t>(nv) * width_px + nu;
        d[i] = std::min(d[i], labels[n] != labels[i] ? 1 : d[n] + 1);
    };
    for (int v = 0; v < height_px; ++v) {
        for (int u = 0; u < width_px; ++u) {
            relax(u, v, u - 1, v - 1);
            relax(u, v, u, v - 1);
            relax(u, v, u + 1, v - 1);
            relax(u, v, u - 1, v);
        }
    }
    for (int v = height_px - 1; v >= 0; --v) {
        for (int u = width_px - 1; u >= 0; --u) {
            relax(u, v, u + 1, v + 1);
            relax(u, v, u, v + 1);
            relax(u, v, u - 1, v + 1);
            relax(u, v, u + 1, v);
        }
    }
    return d;
}

namespace {

/// A box over a whole parked row is not a car: its grown footprint must stay small.
bool small_enough(const scene_schema::Entity& e, const CarMatchOptions& options) {
    const double grow = 2.0 * options.footprint_margin_m;
    return (e.L + grow) * (e.W + grow) <= options.max_footprint_area_m2;
}

/// Pairs of a car entity and a GT car that satisfy the footprint rule, best inside fraction
/// first.
std::vector<CarMatch> footprint_pairs(const std::vector<scene_schema::Entity>& entities,
                                      const std::vector<std::size_t>& cars,
                                      const std::vector<GtCar>& gt_cars,
                                      const CarMatchOptions& options) {
    std::vector<CarMatch> candidates;
    for (std::size_t i : cars) {
        const auto& e = entities[i];
        if (!small_enough(e, options)) continue;
        for (std::size_t g = 0; g < gt_cars.size(); ++g) {
            const double f =
                footprint_inside_fraction(e, gt_cars[g].points_m, options.footprint_margin_m);
            if (f < options.min_inside_fraction) continue;
            CarMatch m;
            m.entity = i;
            m.gt = g;
            m.inside_fraction = f;
            m.centre_distance_m =
                std::hypot(e.x - gt_cars[g].centroid_m.x(), e.z - gt_cars[g].centroid_m.z());
            candidates.push_back(m);
        }
    }
    std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
        return a.inside_fraction > b.inside_fraction;
    });
    return candidates;
}

/// KITTI's 2D criterion for GT cars the footprint rule cannot judge (at most
/// fallback_max_points points): projected box against mask rectangle, best IoU first.
std::vector<CarMatch> fallback_pairs(const std::vector<scene_schema::Entity>& entities,
                                     const std::vector<std::size_t>& cars,
                                     const std::vector<GtCar>& gt_cars,
                                     const CarMatchOptions& options, const StereoCamera& camera) {
    std::vector<CarMatch> fallback;
    for (std::size_t i : cars) {
        const auto& e = entities[i];
        if (!small_enough(e, options)) continue;
        for (std::size_t g = 0; g < gt_cars.size(); ++g) {
            const GtCar& car = gt_cars[g];
            if (car.pixel_count > options.fallback_max_points || car.image_pixels.empty()) continue;
            const auto box = projected_box_px(e, camera, car.image_width_px, car.image_height_px);
            if (!box) continue;
            const double iou = rect_iou(*box, car.mask_box_px);
            if (iou < options.fallback_min_iou) continue;
            CarMatch m;
            m.entity = i;
            m.gt = g;
            m.fallback = true;
            m.iou_2d = iou;
            if (car.pixel_count > 0) {
                m.inside_fraction =
                    footprint_inside_fraction(e, car.points_m, options.footprint_margin_m);
                m.centre_distance_m =
                    std::hypot(e.x - car.centroid_m.x(), e.z - car.centroid_m.z());
            }
            fallback.push_back(m);
        }
    }
    std::stable_sort(fallback.begin(), fallback.end(),
                     [](const auto& a, const auto& b) { return a.iou_2d > b.iou_2d; });
    return fallback;
}

/// True when an unmatched entity's centre projects onto a GT car without GT points (the
/// footprint rule cannot score it).
bool on_car_without_points(const scene_schema::Entity& e, const std::vector<GtCar>& gt_cars,
                           const CarMatchOptions& options, const StereoCamera* camera) {
    if (!camera || !(e.z > 0.0) || !(camera->fx_px > 0.0)) return false;
    const long u = std::lround(camera->fx_px * e.x / e.z + camera->cx_px);
    const long v = std::lround(camera->fy_px * e.y / e.z + camera->cy_px);
    for (const auto& car : gt_cars) {
        if (car.pixel_count > options.fallback_max_points || car.image_width_px <= 0 || u < 0 ||
            u >= car.image_width_px || v < 0) {
            continue;
        }
        const auto px = static_cast<std::uint32_t>(v * car.image_width_px + u);
        if (std::binary_search(car.image_pixels.begin(), car.image_pixels.end(), px)) {
            return true;
        }
    }
    return false;
}

}  // namespace

CarEvaluation evaluate_cars(const std::vector<scene_schema::Entity>& entities,
                            const std::vector<GtCar>& gt_cars, const CarMatchOptions& options,
                            const StereoCamera* camera) {
    options.validate();
    CarEvaluation result;
    std::vector<std::size_t> cars;
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const auto& e = entities[i];
        if (e.class_name != options.car_class) continue;
        cars.push_back(i);
        if (std::hypot(e.x, e.z) <= options.max_range_m) ++result.entities_in_range;
    }
    std::vector<CarMatch> candidates = footprint_pairs(entities, cars, gt_cars, options);
    // KITTI's 2D criterion after every footprint pair, so it never takes a car or an entity the
    // footprint rule would match.
    if (camera) {
        const std::vector<CarMatch> fallback =
            fallback_pairs(entities, cars, gt_cars, options, *camera);
        candidates.insert(candidates.end(), fallback.begin(), fallback.end());
    }
    std::vector<char> entity_used(entities.size(), 0), gt_used(gt_cars.size(), 0);
    for (const auto& m : candidates) {
        if (entity_used[m.entity] || gt_used[m.gt]) continue;
        entity_used[m.entity] = 1;
        gt_used[m.gt] = 1;
        result.matches.push_back(m);
    }
    for (std::size_t g = 0; g < gt_cars.size(); ++g) {
        const auto& car = gt_cars[g];
        if (car.range_m() > options.max_range_m || car.pixel_count < options.min_gt_pixels)
            continue;
        ++result.gt_owed;
        if (gt_used[g]) ++result.gt_owed_matched;
    }
    for (std::size_t i : cars) {
        const auto& e = entities[i];
        if (std::hypot(e.x, e.z) > options.max_range_m) continue;
        if (entity_used[i]) {
            ++result.entities_matched;
            for (const auto& m : result.matches) {
                if (m.entity == i && m.fallback) ++result.fallback_matched;
            }
        } else if (on_car_without_points(e, gt_cars, options, camera)) {
            ++result.entities_unscorable;
        }
    }
    return result;
}

std::vector<GtCar> load_gt_cars(const std::filesystem::path& instance_png,
                                const std::filesystem::path& disparity_png,
                                const StereoCamera& camera, const GtCarOptions& options) {
    check_camera(camera);
    options.validate();
    const ImageU16 instance = read_png_u16(instance_png);
    const ImageU16 disparity = read_png_u16(disparity_png);
    if (instance.width_px != disparity.width_px || instance.height_px != disparity.height_px) {
        throw std::runtime_error("instance image is " + std::to_string(instance.width_px) + "x" +
                                 std::to_string(instance.height_px) + " but the GT disparity is " +
                                 std::to_string(disparity.width_px) + "x" +
                                 std::to_string(disparity.height_px) + " (" +
                                 instance_png.string() + ")");
    }
    const std::vector<int> border =
        label_border_distance_px(instance.values, instance.width_px, instance.height_px);
    std::map<int, GtCar> by_instance;
    std::map<int, std::vector<GtDepth>> depths;
    for (int v = 0; v < instance.height_px; ++v) {
        for (int u = 0; u < instance.width_px; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * instance.width_px + u;
            const int value = instance.values[i];
            if ((value >> 8) != options.car_label_id) continue;
            GtCar& car = by_instance[value & 0xff];
            if (car.image_pixels.empty()) car.mask_box_px = Eigen::Vector4d(u, v, u + 1, v + 1);
            car.instance = value & 0xff;
            car.image_width_px = instance.width_px;
            car.image_height_px = instance.height_px;
            car.image_pixels.push_back(static_cast<std::uint32_t>(v * instance.width_px + u));
            car.mask_box_px = Eigen::Vector4d(std::min<double>(car.mask_box_px[0], u),
                                              std::min<double>(car.mask_box_px[1], v),
                                              std::max<double>(car.mask_box_px[2], u + 1),
                                              std::max<double>(car.mask_box_px[3], v + 1));
            const int d16 = disparity.values[i];
            if (d16 == 0) continue;
            car.points_m.push_back(reproject_pixel(camera, u, v, d16 / 256.0));
            depths[car.instance].push_back(
                {car.points_m.back().z(), border[i] >= options.min_interior_px});
        }
    }
    std::vector<GtCar> cars;
    for (auto& [id, car] : by_instance) {
        const float nearest = own_surface_min_depth_m(depths[id], options);
        const auto occluders =
            std::remove_if(car.points_m.begin(), car.points_m.end(),
                           [nearest](const Eigen::Vector3f& p) { return p.z() < nearest; });
        car.occluder_pixel_count = static_cast<std::size_t>(car.points_m.end() - occluders);
        car.points_m.erase(occluders, car.points_m.end());
        car.pixel_count = car.points_m.size();
        if (!car.points_m.empty()) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            for (const auto& p : car.points_m) sum += p.cast<double>();
            car.centroid_m = sum / static_cast<double>(car.points_m.size());
        }
        cars.push_back(std::move(car));
    }
    return cars;
}

LabeledCloud cloud_from_gt_disparity(const std::filesystem::path& disparity_png,
                                     const std::filesystem::path& semantic_png,
                                     const Palette& palette, const StereoCamera& camera) {
    check_camera(camera);
    const DisparityMap disparity = read_kitti_disparity(disparity_png);
    const ImageU8 semantic = read_image(semantic_png, ImageMode::kColour);
    if (semantic.width_px != disparity.width_px || semantic.height_px != disparity.height_px) {
        throw std::runtime_error("semantic image size differs from the disparity's (" +
                                 semantic_png.string() + ")");
    }
    const ClassImage classes = classify_pixels(semantic, palette);
    LabeledCloud cloud;
    cloud.width_px = disparity.width_px;
    cloud.height_px = disparity.height_px;
    cloud.border = match_border(camera);
    for (int v = 0; v < disparity.height_px; ++v) {
        for (int u = 0; u < disparity.width_px; ++u) {
            const std::size_t i = static_cast<std::size_t>(v) * disparity.width_px + u;
            const float d = disparity.disparity_px[i];
            if (!(d > 0.0f)) continue;
            cloud.xyz_m.push_back(reproject_pixel(camera, u, v, d));
            const std::uint8_t* rgb = semantic.at(u, v);
            cloud.colour.push_back({rgb[0], rgb[1], rgb[2]});
            cloud.class_index.push_back(classes.class_index[i]);
            cloud.pixel.push_back(static_cast<std::uint32_t>(i));
        }
    }
    return cloud;
}

}  // namespace cloud_analysis
