#pragma once

/// The entity file: the contract between cloud-analysis (writer) and scene-render (reader).
/// The format is specified in schema/entities.schema.json and docs/format.md.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "stereoscene/support/atomic_file.hpp"

namespace scene_schema {

/// Major.minor.patch of the format this library writes; files with another major are refused.
inline constexpr const char* kSchemaVersion = "1.3.0";
inline constexpr int kSchemaMajor = 1;

/// The only coordinate convention of version 1: KITTI's rectified left camera.
inline constexpr const char* kConventionKittiCamera = "kitti_camera";

/// Bounds of the numbers in an entity file (the schema's "minimum"/"maximum"): far beyond any
/// scene a camera sees, close enough that every reader can turn them into ints and floats.
inline constexpr double kMaxPosition_m = 1e5;                 ///< |x|, |y|, |z| of a box centre
inline constexpr double kMaxSize_m = 1e4;                     ///< W, H, L and the stereo baseline
inline constexpr double kMaxTheta_rad = 1e3;                  ///< |theta|
inline constexpr double kMaxClassId = 2147483647.0;           ///< class_id fits an int
inline constexpr double kMaxPointCount = 9007199254740991.0;  ///< 2^53 - 1: exact in a double
inline constexpr double kMaxImageSide_px = 1e6;               ///< camera width and height
inline constexpr double kMaxPixelValue_px = 1e9;              ///< |fx|, |fy|, |cx|, |cy|
inline constexpr double kMaxSpeed_mps = 1e3;                  ///< |vx|, |vz| (1.1)
inline constexpr double kMaxTimestamp_s = 1e11;               ///< frame.timestamp (1.1)
inline constexpr double kMaxTrackId = 2147483647.0;           ///< track_id fits an int (1.1)
inline constexpr double kMaxPoseValue = 1e7;                  ///< |pose entry| (1.2)
/// |world x, y, z| (1.3): a pose's translation plus a box centre turned by its rotation.
inline constexpr double kMaxWorldPosition_m = 2e7;

/// A validation or read failure, located by a JSON pointer into the document.
class SchemaError : public std::runtime_error {
  public:
    SchemaError(std::string pointer, std::string rule);
    /// JSON pointer of the offending value ("" for the whole document).
    const std::string& pointer() const { return pointer_; }
    /// The rule broken, e.g. "must be > 0".
    const std::string& rule() const { return rule_; }

  private:
    std::string pointer_;
    std::string rule_;
};

/// Pinhole intrinsics of the rectified left camera that saw the frame (optional in the file).
struct CameraIntrinsics {
    int width_px = 0;         ///< image width in pixels
    int height_px = 0;        ///< image height in pixels
    double fx_px = 0.0;       ///< focal length along x in pixels
    double fy_px = 0.0;       ///< focal length along y in pixels
    double cx_px = 0.0;       ///< principal point x in pixels
    double cy_px = 0.0;       ///< principal point y in pixels
    double baseline_m = 0.0;  ///< stereo baseline in metres (0 when unknown)
};

/// What the coordinates refer to.
struct Frame {
    std::string id;                                   ///< image pair or scene id
    std::string convention = kConventionKittiCamera;  ///< coordinate convention
    std::optional<CameraIntrinsics> camera;           ///< intrinsics, when known
    std::optional<double> timestamp_s;  ///< capture time in seconds, >= 0 (1.1; a sequence's clock)
    /// Pose of this frame's camera in the drive's world (1.2): the 3x4 matrix [R | t] of
    /// T_world_camera, row-major (KITTI odometry poses; the world is the first frame's camera).
    std::optional<std::array<double, 12>> pose;
    nlohmann::json extra = nlohmann::json::object();  ///< unknown members, kept verbatim
};

/// Ground-plane velocity of an entity in the frame's camera coordinates (1.1): metres per
/// second along x (right) and z (forward), relative to the camera that saw the frame.
struct Velocity {
    double vx_mps = 0.0;  ///< along +x (right), m/s
    double vz_mps = 0.0;  ///< along +z (forward), m/s
};

/// One object or stuff extent: an upright box in the camera frame.
struct Entity {
    std::string id;                        ///< unique within the file
    std::string class_name;                ///< e.g. "car", "road"
    int class_id = 0;                      ///< numeric class id of the palette in use
    double x = 0.0;                        ///< box centre, metres, right
    double y = 0.0;                        ///< box centre, metres, down
    double z = 0.0;                        ///< box centre, metres, forward
    double theta = 0.0;                    ///< yaw about +y in radians (KITTI rotation_y)
    double W = 1.0;                        ///< width across the heading, metres, > 0
    double H = 1.0;                        ///< height along y, metres, > 0
    double L = 1.0;                        ///< length along the heading, metres, > 0
    std::int64_t point_count = 0;          ///< cloud points that support the entity, >= 0
    double confidence = 1.0;               ///< 0..1
    std::optional<std::string> method;     ///< extractor that made it
    std::optional<std::int64_t> track_id;  ///< the same object across a sequence's frames (1.1)
    std::optional<Velocity> velocity;      ///< tracked ground-plane velocity (1.1)
    nlohmann::json extra = nlohmann::json::object();  ///< unknown members, kept verbatim
};

/// An entity's box in the drive's world (1.3): its centre and heading carried by the frame's
/// pose. Derived, never stored: to_json writes it for every entity of a frame with a pose.
struct WorldPlacement {
    double x = 0.0, y = 0.0, z = 0.0;  ///< box centre in the world frame, metres
    double theta = 0.0;  ///< heading in the world frame, radians in [-pi, pi] (as `theta`)
};

/// Where `pose` (T_world_camera, row-major 3x4) puts an entity's box: the centre R p + t and
/// the heading (cos theta, 0, -sin theta) turned by R, read back as a yaw about +y.
WorldPlacement world_placement(const std::array<double, 12>& pose, const Entity& entity);

/// A whole entity file.
struct EntityDocument {
    std::string schema_version = kSchemaVersion;
    Frame frame;
    std::optional<nlohmann::json> source;  ///< free-form provenance object
    std::vector<Entity> entities;
    nlohmann::json extra = nlohmann::json::object();  ///< unknown top-level members
};

/// One broken rule, as reported by validate().
struct ValidationIssue {
    std::string pointer;  ///< JSON pointer, e.g. "/entities/3/W"
    std::string rule;     ///< e.g. "must be > 0"
    /// "/entities/3/W: must be > 0"
    std::string message() const;
};

/// Every rule the document breaks, in document order (empty when valid).
std::vector<ValidationIssue> validate(const nlohmann::json& document);

/// Validates and converts; throws SchemaError with the first issue.
EntityDocument from_json(const nlohmann::json& document);

/// Converts back; unknown members in `extra` are written back verbatim.
nlohmann::json to_json(const EntityDocument& document);

/// Validates the in-memory document (sizes, ids...) exactly as a reader would.
void check(const EntityDocument& document);

/// Parses text; a syntax error becomes SchemaError at pointer "" with the byte offset.
EntityDocument parse(std::string_view text);

/// Canonical text: 2-space indent, sorted keys, trailing newline.
std::string dump(const EntityDocument& document);

/// check() then dump(), converting the document to JSON once.
std::string dump_checked(const EntityDocument& document);

/// Reads and validates a file ("-": standard input); throws FileError
/// "<path>: <pointer>: <rule>".
EntityDocument read_file(const std::filesystem::path& path);

/// Validates, then writes atomically (temp file beside the target, then rename).
void write_file(const EntityDocument& document, const std::filesystem::path& path);

/// A file could not be read, parsed or written; what() is "<path>: <pointer>: <rule>" or
/// "<path>: <reason>".
using FileError = stereoscene::support::FileError;

}  // namespace scene_schema
