#include "scene_viewer/systems/build_scene_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "scene_viewer/assets/colours.hpp"
#include "scene_viewer/assets/palette.hpp"
#include "scene_viewer/assets/vehicle_paints.hpp"
#include "scene_viewer/ecs/coordinates.hpp"
#include "scene_viewer/ecs/render_options.hpp"
#include "scene_viewer/views/views.hpp"
#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/limits.hpp"

using stereoscene::support::kPi;

namespace scene_viewer {

std::string class_model_key(const std::string& class_name, bool low) {
    return "class:" + class_name + (low ? ":low" : "");
}

namespace {

glm::vec4 to_colour(const Rgb8& c) { return {c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1.0f}; }

/// Largest height of a ground patch, metres: roads are drawn as thin slabs.
constexpr double kMaxGroundPatchHeight = 0.1;
/// Height of the KITTI camera above the road when the file has no ground class, metres.
constexpr float kDefaultCameraHeight = 1.65f;

/// Grid lines every `step` metres over [x0, x1] x [z0, z1] at height y (KITTI); lines on
/// multiples of 10 m (or of ten steps, for coarse steps) are darker. Counted in doubles, so a view
/// of any size cannot overflow an int.
MeshData grid_mesh(float x0, float x1, float z0, float z1, float y, double step) {
    MeshData m;
    m.topology = Topology::lines;
    const glm::vec4 minor(0.55f, 0.55f, 0.58f, 1.0f), major(0.25f, 0.25f, 0.28f, 1.0f);
    const double major_every = step > 10.0 ? step * 10.0 : 10.0;
    auto lines = [&](double lo, double hi, auto&& add) {
        const double first = std::floor(lo / step);
        const double count = std::floor(std::ceil(hi) / step) - first + 1.0;
        for (double i = 0.0; i < count; i += 1.0) {
            const double v = (first + i) * step;
            add(static_cast<float>(v), std::fmod(v, major_every) == 0.0 ? major : minor);
        }
    };
    lines(static_cast<double>(x0), static_cast<double>(x1), [&](float x, const glm::vec4& c) {
        m.positions.insert(m.positions.end(), {{x, y, z0}, {x, y, z1}});
        m.colours.insert(m.colours.end(), {c, c});
    });
    lines(static_cast<double>(z0), static_cast<double>(z1), [&](float z, const glm::vec4& c) {
        m.positions.insert(m.positions.end(), {{x0, y, z}, {x1, y, z}});
        m.colours.insert(m.colours.end(), {c, c});
    });
    return m;
}

/// Grid step in metres: 1 m while lines stay at least 6 px apart, else 5 m, else 10 m, then
/// 50, 100, 500 ... m while the view would need more than `max_lines` lines in all across a
/// `width_m` x `height_m` view.
double grid_step_m(float pixels_per_metre, double width_m, double height_m,
                   std::uint64_t max_lines) {
    double step = pixels_per_metre >= 6.0f ? 1.0 : pixels_per_metre * 5.0f >= 6.0f ? 5.0 : 10.0;
    const double budget = static_cast<double>(std::max<std::uint64_t>(max_lines, 4));
    while ((width_m + height_m) / step + 4.0 > budget) {
        step *= std::fmod(std::log10(step), 1.0) == 0.0 ? 5.0 : 2.0;
    }
    return step;
}

MeshData cloud_mesh(const PointCloud& cloud, Shading shading) {
    MeshData m;
    m.topology = Topology::points;
    m.positions = cloud.positions_kitti;
    m.colours.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        Rgb8 c{200, 200, 200};
        if (shading == Shading::semantic && !cloud.class_ids.empty()) {
            c = class_colour(cloud.class_ids[i], "");
        } else if (!cloud.colours.empty()) {
            c = cloud.colours[i];
        } else if (!cloud.class_ids.empty()) {
            c = class_colour(cloud.class_ids[i], "");
        }
        m.colours.push_back(to_colour(c));
    }
    return m;
}

/// One entity per document entity (ground classes as flat patches on their box's bottom face);
/// returns the top of the highest ground patch (KITTI y), or the default camera height.
float add_document_entities(World& world, const scene_schema::EntityDocument& document,
                            const RenderOptions& options, ModelLibrary& models) {
    const bool lit = options.shading == Shading::lit;
    const std::uint32_t box = *models.find("box");
    float ground_top_y = kDefaultCameraHeight;
    bool has_ground = false;
    std::vector<std::uint16_t> instance_ids;
    if (options.shading == Shading::instance) {
        std::vector<int> class_ids;
        for (const auto& src : document.entities) class_ids.push_back(src.class_id);
        instance_ids = kitti_instance_ids(class_ids);
    }

    for (std::size_t i = 0; i < document.entities.size(); ++i) {
        const auto& src = document.entities[i];
        const EntityId e = world.create();
        const bool ground = is_ground_class(src.class_id, src.class_name);
        Transform t;
        t.centre_kitti = {src.x, src.y, src.z};
        t.theta_rad = src.theta;
        const double h = ground ? std::min(src.H, kMaxGroundPatchHeight) : src.H;
        t.size_whl = {src.W, h, src.L};
        // A ground patch lies on the box's bottom face (KITTI y grows downwards).
        if (ground) t.centre_kitti.y = static_cast<float>(src.y + 0.5 * src.H - 0.5 * h);
        world.transforms.set(e, t);
        if (ground) {
            const float top = t.centre_kitti.y - static_cast<float>(0.5 * h);
            ground_top_y = has_ground ? std::min(ground_top_y, top) : top;
            has_ground = true;
        }

        MeshRef mesh{box, glm::mat4(1.0f), true};
        bool own_colours = false;
        if (!ground) {
            std::optional<std::uint32_t> m;
            if (src.H < std::max(src.W, src.L))
                m = models.find(class_model_key(src.class_name, true));
            if (!m) m = models.find(class_model_key(src.class_name));
            if (m) {
                const UploadedModel& model = models.at(*m);
                mesh =
                    MeshRef{*m, fit_bounds_to_unit_cube(model.bounds_min, model.bounds_max), true};
                own_colours = true;
            }
        }
        world.meshes.set(e, mesh);
        Material material;
        // Lit models keep their own material colours; boxes and semantic renders use the class.
        material.colour = lit && own_colours
                              ? glm::vec4(1.0f)
                              : to_colour(class_colour(src.class_id, src.class_name));
        material.lit = lit;
        material.procedural = lit && options.procedural_texture;
        if (lit && options.vehicle_paints && is_painted_class(src.class_name)) {
            material.painted = true;
            material.paint = to_colour(vehicle_paint(src.id, options.paint_seed).srgb);
        }
        if (!instance_ids.empty()) {
            material.colour = {(instance_ids[i] >> 8) / 255.0f, (instance_ids[i] & 0xff) / 255.0f,
                               0.0f, 1.0f};
        }
        world.materials.set(e, material);
        world.sources.set(
            e, SourceEntity{static_cast<std::int32_t>(i), src.id, src.class_id, src.class_name});
    }
    return ground_top_y;
}

/// The ego car under the camera: KITTI's camera sits 1.65 m above the road, about 1 m ahead of
/// the car's centre.
void add_ego(World& world, const RenderOptions& options, ModelLibrary& models, float ground_top_y) {
    const bool lit = options.shading == Shading::lit;
    const EntityId e = world.create();
    const float car_h = 1.5f;
    world.transforms.set(
        e, Transform{{0.0f, ground_top_y - 0.5f * car_h, -1.0f}, -kPi / 2, {1.8f, car_h, 4.4f}});
    MeshRef mesh{*models.find("box"), glm::mat4(1.0f), true};
    glm::vec4 lit_colour = to_colour(kLitEgoColour);
    if (auto m = models.find(class_model_key("car"))) {
        const UploadedModel& model = models.at(*m);
        mesh = MeshRef{*m, fit_bounds_to_unit_cube(model.bounds_min, model.bounds_max), true};
        lit_colour = glm::vec4(1.0f);
    }
    world.meshes.set(e, mesh);
    Material material;
    material.colour = lit ? lit_colour : to_colour(class_colour(26, "car"));
    material.lit = lit;
    world.materials.set(e, material);
    world.sources.set(e, SourceEntity{-1, "ego", 26, "car"});
}

/// The camera entity: the options' view, the frame's camera for the camera view, a BEV framing
/// every entity when asked. Returns the camera's view.
ViewSpec add_camera(World& world, const scene_schema::EntityDocument& document,
                    const RenderOptions& options) {
    Camera camera;
    camera.width_px = options.width_px;
    camera.height_px = options.height_px;
    camera.spec = options.view;
    const ViewKind kind = options.view.kind;
    if (kind == ViewKind::camera && !camera.spec.intrinsics) {
        camera.spec.intrinsics = document.frame.camera;
    }
    if (kind == ViewKind::bev && options.fit_bev) {
        const ViewSpec fitted = bev_view_fitting(
            document, static_cast<float>(options.width_px) / static_cast<float>(options.height_px));
        camera.spec.bev_centre_xz = fitted.bev_centre_xz;
        camera.spec.bev_half_height_m = fitted.bev_half_height_m;
    }
    const EntityId camera_entity = world.create();
    world.cameras.set(camera_entity, camera);
    world.sources.set(camera_entity, SourceEntity{-1, "camera", 0, ""});
    return camera.spec;
}

/// The BEV's metre grid over the camera's view, just above the highest ground patch: visible
/// on the road, hidden under objects.
void add_grid(World& world, const RenderOptions& options, const ViewSpec& spec,
              ModelLibrary& models, float ground_top_y) {
    const float aspect =
        static_cast<float>(options.width_px) / static_cast<float>(options.height_px);
    const float hh = spec.bev_half_height_m, hw = hh * aspect;
    const glm::vec2 c = spec.bev_centre_xz;
    const double step = grid_step_m(static_cast<float>(options.height_px) / (2.0f * hh),
                                    2.0 * static_cast<double>(hw), 2.0 * static_cast<double>(hh),
                                    stereoscene::support::limits().max_grid_lines);
    const std::uint32_t grid = models.put(
        "grid", grid_mesh(c.x - hw, c.x + hw, c.y - hh, c.y + hh, ground_top_y - 0.01f, step));
    const EntityId e = world.create();
    world.meshes.set(e, MeshRef{grid, glm::mat4(1.0f), false});
    Material material;
    material.lit = false;
    material.vertex_colour = true;
    world.materials.set(e, material);
    world.sources.set(e, SourceEntity{-1, "grid", 0, ""});
}

void add_cloud(World& world, const PointCloud& cloud, const RenderOptions& options,
               ModelLibrary& models) {
    const std::uint32_t points = models.put("cloud", cloud_mesh(cloud, options.shading));
    const EntityId e = world.create();
    world.meshes.set(e, MeshRef{points, glm::mat4(1.0f), false});
    Material material;
    material.lit = false;
    material.vertex_colour = true;
    material.point_size_px = options.point_size_px;
    world.materials.set(e, material);
    world.sources.set(e, SourceEntity{-1, "cloud", 0, ""});
}

}  // namespace

void build_scene(World& world, const scene_schema::EntityDocument& document,
                 const PointCloud* cloud, const RenderOptions& options, ModelLibrary& models) {
    world.clear();
    const float ground_top_y = add_document_entities(world, document, options, models);
    const ViewKind kind = options.view.kind;
    if (options.ego && kind != ViewKind::camera) add_ego(world, options, models, ground_top_y);
    const ViewSpec spec = add_camera(world, document, options);
    if (kind == ViewKind::bev && options.grid) add_grid(world, options, spec, models, ground_top_y);
    if (cloud != nullptr && cloud->size() > 0) add_cloud(world, *cloud, options, models);
}

}  // namespace scene_viewer
