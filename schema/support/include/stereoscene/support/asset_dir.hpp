#pragma once

/// Finding the bundled assets (models, palettes, class tables) at run time, so that a build
/// tree or an install works wherever it is moved.

#include <filesystem>

namespace stereoscene::support {

/// Environment variable that names the assets folder, before any other place.
inline constexpr const char* kAssetsEnv = "STEREOSCENE_ASSETS";

/// Assets folder of an install, relative to the folder holding the executable.
inline constexpr const char* kInstalledAssetsFromBin = "../share/stereoscene/assets";

/// The folder holding the running executable (from /proc/self/exe); empty if unknown.
std::filesystem::path executable_dir();

/// The assets folder: $STEREOSCENE_ASSETS when set (it must exist), else
/// `<executable folder>/../share/stereoscene/assets` when it exists (an install), else the
/// source tree's `assets/` the build tree was configured from. Throws FileError naming the
/// places tried when none exists.
std::filesystem::path asset_dir();

}  // namespace stereoscene::support
