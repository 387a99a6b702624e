#pragma once

/// Turning what a user asks for (text sizes and points, several files in one figure, a render
/// laid over a photo) into render options and images: the product rules behind scene-render's
/// flags, kept here so that they are tested without the executable.

#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "scene_schema/entities.hpp"
#include "scene_viewer/assets/class_table.hpp"
#include "scene_viewer/render/scene_renderer.hpp"

namespace scene_viewer {

/// "WxH" (or "WXH") -> {width, height} in pixels, each side 1..kMaxImageSide; throws
/// std::invalid_argument ("expected WxH, got '...'" or the range) otherwise.
std::pair<int, int> parse_image_size(const std::string& text);

/// "x,y,z" in metres -> a point; throws std::invalid_argument otherwise.
glm::vec3 parse_point_m(const std::string& text);

/// Image size of a view when none is asked for: the camera view takes the document's camera
/// (else RenderOptions' default 1242x375), bev 800x800, chase and free 1280x720.
std::pair<int, int> default_image_size(ViewKind kind, const scene_schema::EntityDocument& document);

/// One camera for every tile of a figure: the first document's intrinsics, and for the bird's
/// eye view one framing of every document's entities (fit_bev turned off). `documents` must
/// not be empty.
void share_view(const std::vector<scene_schema::EntityDocument>& documents, RenderOptions& options);

/// Classes of the loaded scene drawn as boxes for want of a model, except classes of kind
/// "block" in `table` (boxes by design), sorted by name.
std::vector<std::string> classes_missing_models(const SceneRenderer& renderer,
                                                const ClassTable& table);

/// Lays `render` over `background` (resized to the render, nearest pixel) with the render's
/// `opacity` 0..1; the render's clear colour is the background colour of `shading`.
void composite_background(ImageRgba8& render, const ImageRgba8& background, float opacity,
                          Shading shading);

}  // namespace scene_viewer
