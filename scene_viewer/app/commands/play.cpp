#include "play.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "scene_schema/sequence.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "scene_viewer/views/trails.hpp"

namespace scene_render {

using namespace scene_viewer;
namespace fs = std::filesystem;

CLI::App* add_play_command(CLI::App& app, PlayArgs& a) {
    CLI::App* p = app.add_subcommand(
        "play",
        "render a drive (sequence index) to numbered PNGs, an MP4 and a strip, with "
        "track trails (see docs/cli.md)");
    p->add_option("input", a.input, "sequence index, or a folder with sequence.json")->required();
    p->add_option("--out-dir", a.out_dir, "folder of the frames' PNGs")->required();
    p->add_option("--video", a.video, "also encode the frames to this MP4 (needs ffmpeg)");
    p->add_option("--strip", a.strip, "also write this PNG: frames side by side");
    p->add_option("--strip-frames", a.strip_frames, "frames in the strip, evenly spaced")
        ->capture_default_str();
    p->add_option("--trail", a.trail, "past positions drawn per track, 0 = none")
        ->capture_default_str();
    p->add_option("--fps", a.fps, "video frame rate (default: the index's, else 10)");
    p->add_option("--backgrounds", a.backgrounds,
                  "camera view: folder of <frame>.png laid under the render (e.g. image_2)");
    p->add_option("--opacity", a.opacity, "--backgrounds: opacity of the render, 0..1")
        ->capture_default_str();
    add_view_options(*p, a.view);
    return p;
}

namespace {

/// The path of `name` on PATH, or empty.
std::string find_on_path(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::stringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
        if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
    return {};
}

/// Runs ffmpeg on the numbered frames; the MP4 is made beside the target, then renamed.
void encode_video(const PlayArgs& a, double fps, const std::vector<std::string>& names) {
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) {
        throw Failure{"cannot encode the video",
                      "ffmpeg not found on PATH (Debian: apt-get install ffmpeg)", a.video};
    }
    // ffmpeg's image2 demuxer wants consecutive numbers: link the frames as 000000.png...
    const fs::path work = fs::path(a.out_dir) / ".video-frames";
    fs::remove_all(work);
    fs::create_directories(work);
    for (std::size_t i = 0; i < names.size(); ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "%06zu.png", i);
        fs::create_symlink(fs::absolute(fs::path(a.out_dir) / (names[i] + ".png")), work / name);
    }
    const std::string tmp = a.video + ".tmp.mp4";
    const std::string rate = std::to_string(fps);
    const pid_t pid = ::fork();
    if (pid == 0) {
        const std::string input = (work / "%06d.png").string();
        ::execl(ffmpeg.c_str(), "ffmpeg", "-y", "-loglevel", "error", "-framerate", rate.c_str(),
                "-i", input.c_str(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
                "-pix_fmt", "yuv420p", "-r", rate.c_str(), tmp.c_str(),
                static_cast<char*>(nullptr));
        ::_exit(127);
    }
    int status = 0;
    if (pid < 0 || ::waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
        fs::remove(tmp);
        fs::remove_all(work);
        throw Failure{"cannot encode the video", "ffmpeg failed (see its message above)", a.video};
    }
    fs::remove_all(work);
    fs::rename(tmp, a.video);
}

}  // namespace

int run_play(const PlayArgs& a) {
    if (a.trail < 0) usage("must be >= 0", "--trail");
    if (a.strip_frames < 1) usage("must be >= 1", "--strip-frames");
    if (!(a.opacity >= 0.0f && a.opacity <= 1.0f)) usage("must be in 0..1", "--opacity");
    if (a.fps < 0.0 || a.fps > 1000.0) usage("must be in (0, 1000]", "--fps");
    const fs::path index_path =
        fs::is_directory(a.input) ? fs::path(a.input) / "sequence.json" : fs::path(a.input);
    scene_schema::SequenceIndex index;
    try {
        index = scene_schema::read_sequence_file(index_path);
    } catch (const std::exception& e) {
        throw Failure{"cannot read the drive", e.what(), a.input};
    }
    if (index.frames.empty()) throw Failure{"cannot play the drive", "it has no frames", a.input};
    const double fps = a.fps > 0.0 ? a.fps : index.fps.value_or(10.0);
    const std::string first_path = scene_schema::frame_file(index_path, index.frames[0]).string();
    const auto first = read_entities(first_path);
    RenderOptions options = render_options(a.view, first, first_path);
    if (!a.backgrounds.empty()) {
        if (options.view.kind != ViewKind::camera) usage("needs --view camera", "--backgrounds");
        options.keep_alpha = true;
    }
    const auto cloud = read_cloud(a.view);
    const auto classes = read_classes(a.view.boxes, a.view.classes);
    std::error_code ec;
    fs::create_directories(a.out_dir, ec);
    if (ec) throw Failure{"cannot create the output folder", ec.message(), a.out_dir};

    auto gpu = start_gpu(classes);
    TrailHistory trails(a.trail);
    std::vector<std::string> names;
    std::vector<ImageRgba8> strip;
    const std::size_t n = index.frames.size();
    const std::size_t every = std::max<std::size_t>(1, (n + a.strip_frames - 1) / a.strip_frames);
    for (std::size_t i = 0; i < n; ++i) {
        const auto& f = index.frames[i];
        const auto file = scene_schema::frame_file(index_path, f);
        const auto document = read_entities(file.string());
        gpu->renderer.load(trails.with_trails(document), cloud ? &*cloud : nullptr, options);
        ImageRgba8 image = gpu->renderer.render_frame();
        const std::string name = fs::path(f.file).stem().string();
        if (!a.backgrounds.empty()) {
            const fs::path bg = fs::path(a.backgrounds) / (name + ".png");
            try {
                composite_background(image, decode_image(bg), a.opacity, options.shading);
            } catch (const std::exception& e) {
                throw Failure{"cannot read background image", e.what(), bg.string()};
            }
        }
        write_png_output((fs::path(a.out_dir) / (name + ".png")).string(), image);
        names.push_back(name);
        if (!a.strip.empty() && (i % every == 0 || i + 1 == n) &&
            static_cast<int>(strip.size()) < a.strip_frames) {
            strip.push_back(std::move(image));
        }
        trails.remember(document);
    }
    if (!a.strip.empty()) write_png_output(a.strip, side_by_side(strip));
    if (!a.video.empty()) encode_video(a, fps, names);
    std::fprintf(stderr, "play: %zu frames at %.3g fps -> %s\n", n, fps, a.out_dir.c_str());
    return 0;
}

}  // namespace scene_render
