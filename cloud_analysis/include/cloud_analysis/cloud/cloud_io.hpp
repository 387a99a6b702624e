#pragma once

/// Writers of a LabeledCloud in the three formats viewers read (docs/clouds.md):
/// - ASCII .xyz, header kXyzHeader (CloudCompare's ASCII reader);
/// - PCD v0.7 binary, fields `x y z rgb label` (PCL; rgb packed as uint32 in a float field);
/// - PLY 1.0 binary little endian, float x y z, uchar red green blue, int scalar_class.
/// Class is the palette class id (Cityscapes labelId), 0 for void pixels. Each formatter builds
/// the whole file in one buffer (no per-point iostream).

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cloud_analysis/cloud/types.hpp"

namespace cloud_analysis {

/// The supported cloud file formats.
enum class CloudFormat { kXyz, kPcd, kPly };

/// Format from a file extension (.xyz, .pcd, .ply); throws std::invalid_argument otherwise.
CloudFormat cloud_format_from_path(const std::filesystem::path& path);

/// First line of an .xyz file. CloudCompare reads a header that starts with `//`; it keeps
/// the RGB columns as colours and every other named column as a scalar field, except one
/// headed `Intensity`, which it drops when the colours are present (the luma is therefore
/// called `Luma`).
inline constexpr std::string_view kXyzHeader = "//X Y Z R G B Class Luma\n";

/// Class id written for void points.
inline constexpr int kVoidClassId = 0;

/// Palette indices of class names (e.g. "sky"); "void" names the points without a class.
/// Throws std::invalid_argument "no class '<name>' in palette '<palette>'".
std::vector<std::uint16_t> class_indices(const Palette& palette,
                                         const std::vector<std::string>& names);

/// The cloud without the points of the classes `dropped` (palette indices or kVoidClass), e.g.
/// the sky, whose points at 40-70 m stand as a wall in every cloud viewer.
LabeledCloud without_classes(const LabeledCloud& cloud, const std::vector<std::uint16_t>& dropped);

/// Whole-file bytes of the cloud in the format.
std::string format_xyz(const LabeledCloud& cloud, const Palette& palette);
std::string format_pcd(const LabeledCloud& cloud, const Palette& palette);
std::string format_ply(const LabeledCloud& cloud, const Palette& palette);
std::string format_cloud(const LabeledCloud& cloud, const Palette& palette, CloudFormat format);

}  // namespace cloud_analysis
