#include "play.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string_view>
#include <vector>

#include "scene_schema/sequence.hpp"
#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/render/image.hpp"
#include "scene_viewer/render/render_setup.hpp"
#include "scene_viewer/views/trails.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"
#include "stereoscene/support/output_transaction.hpp"

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

/// The folders of `folder` that do not exist yet, made now (outermost first), or a Failure.
std::vector<fs::path> make_folders(const fs::path& folder) {
    std::vector<fs::path> missing;
    std::error_code ec;
    for (fs::path p = folder; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
        missing.insert(missing.begin(), p);
    }
    for (const fs::path& p : missing) {
        if (!fs::create_directory(p, ec) && ec) {
            throw Failure{"cannot create the output folder", ec.message(), folder.string()};
        }
    }
    return missing;
}

/// Everything play writes, committed together after the last frame: every frame's PNG, the
/// strip and the video. Until then the files are staged under hidden names beside their
/// targets (and the video's frames in a hidden folder of --out-dir); a failure removes all of
/// it, and the folders this run made, so the output paths hold what they held before the run.
class PlayOutputs {
  public:
    PlayOutputs(const PlayArgs& a, const std::vector<std::string>& names) : args_(a) {
        check_output_folder(a.out_dir, "cannot write the frames");
        made_ = make_folders(a.out_dir);
        try {
            for (const std::string& name : names) files_.declare(frame_path(name), "frame");
            if (!a.strip.empty()) files_.declare(a.strip, "--strip");
            if (!a.video.empty()) files_.declare(a.video, "--video");
            if (!a.video.empty()) {
                std::string work = (fs::path(a.out_dir) / ".play-video-XXXXXX").string();
                if (::mkdtemp(work.data()) == nullptr) {
                    throw Failure{"cannot encode the video", std::strerror(errno), a.out_dir};
                }
                video_work_ = work;
            }
        } catch (const stereoscene::support::FileError& e) {
            remove_made_folders();
            throw Failure{"unusable output path", e.reason(), e.path().string()};
        } catch (...) {
            remove_made_folders();
            throw;
        }
    }
    PlayOutputs(const PlayOutputs&) = delete;
    PlayOutputs& operator=(const PlayOutputs&) = delete;
    ~PlayOutputs() {
        std::error_code ignored;
        if (!video_work_.empty()) fs::remove_all(video_work_, ignored);
        if (committed_) return;
        files_.roll_back();
        remove_made_folders();
    }

    /// Stages frame `index` (named `name`) as a PNG, and as the video's next frame.
    void frame(std::size_t index, const std::string& name, const ImageRgba8& image) {
        const std::vector<unsigned char> png = encode_png(image, 1);
        const std::string_view bytes(reinterpret_cast<const char*>(png.data()), png.size());
        try {
            files_.stage(frame_path(name), bytes);
            if (!video_work_.empty()) {
                char numbered[32];
                std::snprintf(numbered, sizeof numbered, "%06zu.png", index);
                stereoscene::support::write_file_atomic(
                    video_work_ / numbered, bytes, stereoscene::support::FileSync::kAtomicOnly);
            }
        } catch (const stereoscene::support::FileError& e) {
            throw Failure{"cannot write image", e.reason(), e.path().string()};
        }
    }

    /// Stages the strip and the video, then commits every file.
    void commit(const std::vector<ImageRgba8>& strip, double fps) {
        try {
            if (!args_.strip.empty()) {
                const std::vector<unsigned char> png = encode_png(side_by_side(strip), 1);
                files_.stage(
                    args_.strip,
                    std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
            }
            if (!args_.video.empty()) {
                const std::string mp4 = encode_video(fps);
                files_.stage(args_.video, mp4);
            }
            files_.commit();
        } catch (const stereoscene::support::FileError& e) {
            throw Failure{"cannot write output", e.reason(), e.path().string()};
        }
        committed_ = true;
    }

  private:
    void remove_made_folders() noexcept {
        std::error_code ignored;
        for (auto it = made_.rbegin(); it != made_.rend(); ++it) fs::remove(*it, ignored);
    }

    std::string frame_path(const std::string& name) const {
        return (fs::path(args_.out_dir) / (name + ".png")).string();
    }

    /// Runs ffmpeg on the numbered frames of the hidden folder; returns the MP4's bytes.
    std::string encode_video(double fps) const {
        const std::string ffmpeg = find_on_path("ffmpeg");
        if (ffmpeg.empty()) {
            throw Failure{"cannot encode the video",
                          "ffmpeg not found on PATH (Debian: apt-get install ffmpeg)", args_.video};
        }
        const std::string input = (video_work_ / "%06d.png").string();
        const std::string output = (video_work_ / "video.mp4").string();
        const std::string rate = std::to_string(fps);
        const pid_t pid = ::fork();
        if (pid == 0) {
            ::execl(ffmpeg.c_str(), "ffmpeg", "-y", "-loglevel", "error", "-framerate",
                    rate.c_str(), "-i", input.c_str(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                    "-c:v", "libx264", "-pix_fmt", "yuv420p", "-r", rate.c_str(), output.c_str(),
                    static_cast<char*>(nullptr));
            ::_exit(127);
        }
        int status = 0;
        if (pid < 0 || ::waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) ||
            WEXITSTATUS(status) != 0) {
            throw Failure{"cannot encode the video", "ffmpeg failed (see its message above)",
                          args_.video};
        }
        try {
            return stereoscene::support::read_file_bounded(
                output, stereoscene::support::limits().max_file_bytes);
        } catch (const stereoscene::support::FileError& e) {
            throw Failure{"cannot encode the video", e.reason(), args_.video};
        }
    }

    const PlayArgs& args_;
    std::vector<fs::path> made_;  ///< folders this run made, outermost first
    stereoscene::support::OutputTransaction files_;
    fs::path video_work_;  ///< hidden folder of the video's numbered frames; empty: no video
    bool committed_ = false;
};

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
    std::vector<std::string> names;
    for (const auto& f : index.frames) names.push_back(fs::path(f.file).stem().string());
    PlayOutputs outputs(a, names);

    auto gpu = start_gpu(classes);
    TrailHistory trails(a.trail);
    std::vector<ImageRgba8> strip;
    const std::size_t n = index.frames.size();
    const std::size_t every = std::max<std::size_t>(1, (n + a.strip_frames - 1) / a.strip_frames);
    for (std::size_t i = 0; i < n; ++i) {
        const auto file = scene_schema::frame_file(index_path, index.frames[i]);
        const auto document = read_entities(file.string());
        gpu->renderer.load(trails.with_trails(document), cloud ? &*cloud : nullptr, options);
        ImageRgba8 image = gpu->renderer.render_frame();
        if (!a.backgrounds.empty()) {
            const fs::path bg = fs::path(a.backgrounds) / (names[i] + ".png");
            try {
                composite_background(image, decode_image(bg), a.opacity, options.shading);
            } catch (const std::exception& e) {
                throw Failure{"cannot read background image", e.what(), bg.string()};
            }
        }
        outputs.frame(i, names[i], image);
        if (!a.strip.empty() && (i % every == 0 || i + 1 == n) &&
            static_cast<int>(strip.size()) < a.strip_frames) {
            strip.push_back(std::move(image));
        }
        trails.remember(document);
    }
    outputs.commit(strip, fps);
    std::fprintf(stderr, "play: %zu frames at %.3g fps -> %s\n", n, fps, a.out_dir.c_str());
    return 0;
}

}  // namespace scene_render
