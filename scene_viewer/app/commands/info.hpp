#pragma once

/// `--info`: the GL vendor, renderer and version headless rendering gets.

namespace scene_render {

/// Prints the GL strings on stdout; throws Failure when EGL cannot start.
int run_info();

}  // namespace scene_render
