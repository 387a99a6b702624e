#include "cloud_analysis/synthetic/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/limits.hpp"

namespace cloud_analysis {
namespace {

using stereoscene::support::kPi;

/// An upright box of the scene with its class and surface shade.
struct Box {
    std::string cls;
    int class_id;
    Rgb colour;
    double x, y, z, theta, W, H, L;  // entity convention: centre, yaw, sizes
    double shade;                    // mean grey level
};

struct Hit {
    double t = std::numeric_limits<double>::infinity();
    int box = -1;  // -1 ground, -2 sky
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

/// Integer lattice hash -> [0, 1).
double lattice(long long i, long long j, long long k, unsigned seed) {
    std::uint64_t h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
                      static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full ^
                      static_cast<std::uint64_t>(k) * 0x165667B19E3779F9ull ^ seed;
    h ^= h >> 33;
    h *= 0xFF51AFD7ED558CCDull;
    h ^= h >> 33;
    h *= 0xC4CEB9FE1A85EC53ull;
    h ^= h >> 33;
    return static_cast<double>(h >> 11) / 9007199254740992.0;
}

/// Trilinear value noise with cells of `cell` metres.
double value_noise(const Eigen::Vector3d& p, double cell, unsigned seed) {
    const Eigen::Vector3d q = p / cell;
    const double fx = std::floor(q.x()), fy = std::floor(q.y()), fz = std::floor(q.z());
    const auto i = static_cast<long long>(fx), j = static_cast<long long>(fy),
               k = static_cast<long long>(fz);
    const double tx = q.x() - fx, ty = q.y() - fy, tz = q.z() - fz;
    double sum = 0.0;
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) {
                const double w = (a ? tx : 1 - tx) * (b ? ty : 1 - ty) * (c ? tz : 1 - tz);
                sum += w * lattice(i + a, j + b, k + c, seed);
            }
    return sum;
}

std::vector<Box> scene_boxes(double ground_y) {
    const auto on_ground = [&](std::string cls, int id, Rgb colour, double x, double z,
                               double theta, double W, double H, double L, double shade) {
        return Box{std::move(cls), id, colour, x, ground_y - H / 2, z, theta, W, H, L, shade};
    };
    const Rgb car{0, 0, 142}, person{220, 20, 60}, building{70, 70, 70};
    return {
        on_ground("car", 26, car, -2.0, 11.0, -kPi / 2, 1.8, 1.5, 4.2, 70),
        on_ground("car", 26, car, 2.2, 17.0, -kPi / 2 + 0.35, 1.8, 1.5, 4.4, 95),
        on_ground("car", 26, car, -0.4, 30.0, -kPi / 2, 1.9, 1.6, 4.6, 60),
        on_ground("person", 24, person, 5.3, 9.0, -kPi / 2, 0.6, 1.75, 0.5, 110),
        on_ground("person", 24, person, -5.6, 14.0, 0.0, 0.6, 1.7, 0.5, 100),
        on_ground("building", 11, building, -10.0, 22.0, -kPi / 2, 4.0, 8.0, 30.0, 130),
        on_ground("building", 11, building, 0.0, 42.0, 0.0, 2.0, 11.0, 40.0, 140),
    };
}

/// Slab intersection of a ray with an upright box rotated by theta about +y.
bool intersect(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t) {
    const Eigen::Vector3d c(b.x, b.y, b.z);
    const Eigen::Vector3d h(std::cos(b.theta), 0.0, -std::sin(b.theta));  // length axis
    const Eigen::Vector3d a(std::sin(b.theta), 0.0, std::cos(b.theta));   // width axis
    const Eigen::Vector3d up(0.0, 1.0, 0.0);
    const Eigen::Vector3d axes[3] = {h, up, a};
    const double half[3] = {b.L / 2, b.H / 2, b.W / 2};
    double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        const double oc = axes[k].dot(o - c);
        const double dk = axes[k].dot(d);
        if (std::abs(dk) < 1e-12) {
            if (std::abs(oc) > half[k]) return false;
            continue;
        }
        double ta = (-half[k] - oc) / dk, tb = (half[k] - oc) / dk;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    t = t0;
    return t0 > 0.0;
}

Hit cast(const std::vector<Box>& boxes, double ground_y, const Eigen::Vector3d& o,
         const Eigen::Vector3d& d) {
    Hit hit;
    hit.box = -2;
    if (d.y() > 1e-9) {
        const double t = (ground_y - o.y()) / d.y();
        if (t > 0.0 && t < hit.t) {
            hit.t = t;
            hit.box = -1;
        }
    }
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        double t = 0.0;
        if (intersect(boxes[i], o, d, t) && t < hit.t) {
            hit.t = t;
            hit.box = static_cast<int>(i);
        }
    }
    if (hit.box != -2) hit.p = o + hit.t * d;
    return hit;
}

/// Grey level of a surface point: the surface's shade plus two octaves of noise.
double shade(const std::vector<Box>& boxes, const Hit& hit, unsigned seed) {
    if (hit.box == -2) return 200.0;
    const double base = hit.box == -1 ? (std::abs(hit.p.x()) < 4.0 ? 95.0 : 150.0)
                                      : boxes[static_cast<std::size_t>(hit.box)].shade;
    const double n = 0.6 * value_noise(hit.p, 0.12, seed) + 0.4 * value_noise(hit.p, 0.5, seed + 7);
    return std::clamp(base + 150.0 * (n - 0.5), 0.0, 255.0);
}

/// The left and right grey views (supersampled), and from the left view's centre rays the
/// semantic image and the ground-truth disparity.
void render_views(SyntheticScene& s, const std::vector<Box>& boxes, double ground_y,
                  const SyntheticOptions& o) {
    const StereoCamera& cam = s.camera;
    const std::size_t n = static_cast<std::size_t>(o.width_px) * o.height_px;
    s.left = ImageU8{o.width_px, o.height_px, 1, std::vector<std::uint8_t>(n)};
    s.right = s.left;
    s.semantic = ImageU8{o.width_px, o.height_px, 3, std::vector<std::uint8_t>(3 * n)};
    s.disparity = DisparityMap{o.width_px, o.height_px, std::vector<float>(n, kNoDisparity)};
    const Rgb road{128, 64, 128}, sidewalk{244, 35, 232}, sky{70, 130, 180};
    const int ss = o.supersampling;
    for (int view = 0; view < 2; ++view) {
        const Eigen::Vector3d origin(view == 0 ? 0.0 : o.baseline_m, 0.0, 0.0);
        ImageU8& img = view == 0 ? s.left : s.right;
        for (int v = 0; v < o.height_px; ++v) {
            for (int u = 0; u < o.width_px; ++u) {
                double sum = 0.0;
                for (int sy = 0; sy < ss; ++sy) {
                    for (int sx = 0; sx < ss; ++sx) {
                        const double pu = u + (sx + 0.5) / ss - 0.5;
                        const double pv = v + (sy + 0.5) / ss - 0.5;
                        const Eigen::Vector3d d((pu - cam.cx_px) / cam.fx_px,
                                                (pv - cam.cy_px) / cam.fy_px, 1.0);
                        sum += shade(boxes, cast(boxes, ground_y, origin, d), o.seed);
                    }
                }
                const std::size_t i = static_cast<std::size_t>(v) * o.width_px + u;
                img.data[i] = static_cast<std::uint8_t>(std::lround(sum / (ss * ss)));
                if (view != 0) continue;
                // Labels and ground truth from the centre ray of the left view.
                const Eigen::Vector3d d((u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px,
                                        1.0);
                const Hit hit = cast(boxes, ground_y, origin, d);
                Rgb colour = sky;
                if (hit.box == -1) {
                    colour = std::abs(hit.p.x()) < 4.0 ? road : sidewalk;
                } else if (hit.box >= 0) {
                    colour = boxes[static_cast<std::size_t>(hit.box)].colour;
                }
                std::copy(colour.begin(), colour.end(), s.semantic.data.begin() + 3 * i);
                if (hit.box != -2) {
                    s.disparity.disparity_px[i] =
                        static_cast<float>(cam.fx_px * cam.baseline_m / hit.p.z());
                }
            }
        }
    }
}

/// The truth of the scene: every box, and the visible road and sidewalks as flat entities.
scene_schema::EntityDocument truth_document(const StereoCamera& cam, const std::vector<Box>& boxes,
                                            double ground_y, const SyntheticOptions& o) {
    scene_schema::EntityDocument doc;
    doc.frame.id = "synthetic-street";
    scene_schema::CameraIntrinsics intr;
    intr.width_px = cam.width_px;
    intr.height_px = cam.height_px;
    intr.fx_px = cam.fx_px;
    intr.fy_px = cam.fy_px;
    intr.cx_px = cam.cx_px;
    intr.cy_px = cam.cy_px;
    intr.baseline_m = cam.baseline_m;
    doc.frame.camera = intr;
    doc.source = nlohmann::json{{"tool", "cloud-analysis make-sample"},
                                {"seed", o.seed},
                                {"note", "ground truth of the rendered synthetic scene"}};
    std::map<std::string, int> counts;
    const auto add = [&](const std::string& cls, int id, double x, double y, double z, double theta,
                         double W, double H, double L) {
        scene_schema::Entity e;
        e.id = cls + "-" + std::to_string(++counts[cls]);
        e.class_name = cls;
        e.class_id = id;
        e.x = x;
        e.y = y;
        e.z = z;
        e.theta = theta;
        e.W = W;
        e.H = H;
        e.L = L;
        e.method = "ground_truth";
        doc.entities.push_back(e);
    };
    for (const Box& b : boxes) add(b.cls, b.class_id, b.x, b.y, b.z, b.theta, b.W, b.H, b.L);
    // The visible ground: road |x| < 4 m, sidewalks 4..12 m either side, out to the back wall.
    const double far = 41.0, near = o.camera_height_m * cam.fy_px / (o.height_px - cam.cy_px);
    const double mid = 0.5 * (near + far), len = far - near;
    add("road", 7, 0.0, ground_y, mid, -kPi / 2, 8.0, 0.05, len);
    add("sidewalk", 8, -8.0, ground_y, mid, -kPi / 2, 8.0, 0.05, len);
    add("sidewalk", 8, 8.0, ground_y, mid, -kPi / 2, 8.0, 0.05, len);
    return doc;
}

}  // namespace

void SyntheticOptions::validate() const {
    if (width_px < 64) throw std::invalid_argument("width_px: must be >= 64");
    if (height_px < 32) throw std::invalid_argument("height_px: must be >= 32");
    const std::uint64_t pixels =
        static_cast<std::uint64_t>(width_px) * static_cast<std::uint64_t>(height_px);
    const std::uint64_t limit = stereoscene::support::limits().max_image_pixels;
    if (pixels > limit) {
        throw std::invalid_argument("width_px x height_px: " + std::to_string(pixels) +
                                    " pixels is more than the limit of " + std::to_string(limit) +
                                    "; " + stereoscene::support::kPixelsHint);
    }
    if (!(fx_px > 0.0)) throw std::invalid_argument("fx_px: must be > 0");
    if (!(baseline_m > 0.0)) throw std::invalid_argument("baseline_m: must be > 0");
    if (!(camera_height_m > 0.0)) throw std::invalid_argument("camera_height_m: must be > 0");
    if (supersampling < 1 || supersampling > 4) {
        throw std::invalid_argument("supersampling: must be 1..4");
    }
}

SyntheticScene make_synthetic_scene(const SyntheticOptions& o) {
    o.validate();
    SyntheticScene s;
    StereoCamera& cam = s.camera;
    cam.width_px = o.width_px;
    cam.height_px = o.height_px;
    cam.fx_px = cam.fy_px = o.fx_px;
    cam.cx_px = cam.cx_right_px = 0.5 * o.width_px;
    cam.cy_px = 0.46 * o.height_px;  // KITTI's horizon sits a little above the centre
    cam.baseline_m = o.baseline_m;
    const double ground_y = o.camera_height_m;
    const std::vector<Box> boxes = scene_boxes(ground_y);
    render_views(s, boxes, ground_y, o);
    s.truth = truth_document(cam, boxes, ground_y, o);
    scene_schema::check(s.truth);
    return s;
}

std::string synthetic_calibration_yaml(const StereoCamera& c) {
    std::ostringstream out;
    out.precision(10);
    out << "# stereoscene calibration (docs/cli.md): rectified pinhole rig, pixels and metres\n"
        << "fx: " << c.fx_px << "\nfy: " << c.fy_px << "\ncx: " << c.cx_px << "\ncy: " << c.cy_px
        << "\nbaseline_m: " << c.baseline_m << "\nwidth: " << c.width_px
        << "\nheight: " << c.height_px << "\n";
    return out.str();
}

}  // namespace cloud_analysis
