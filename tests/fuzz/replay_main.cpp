// Replays inputs through the libFuzzer harnesses without libFuzzer, so the normal and the
// sanitizer builds run every input scripts/fuzz.sh kept in tests/corpus/fuzz/<harness>/. Each
// harness source is compiled with LLVMFuzzerTestOneInput renamed to replay_<harness>.
// usage: replay_fuzz_inputs <harness> <file or folder>...
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#define STEREOSCENE_HARNESS(name) \
    extern "C" int replay_##name(const std::uint8_t* data, std::size_t size);
STEREOSCENE_HARNESS(fuzz_calibration)
STEREOSCENE_HARNESS(fuzz_entities)
STEREOSCENE_HARNESS(fuzz_palettes)
STEREOSCENE_HARNESS(fuzz_gltf)
STEREOSCENE_HARNESS(fuzz_point_clouds)
STEREOSCENE_HARNESS(fuzz_kitti_labels)
STEREOSCENE_HARNESS(fuzz_frame_lists)
#undef STEREOSCENE_HARNESS

int main(int argc, char** argv) {
    using Harness = int (*)(const std::uint8_t*, std::size_t);
    const std::map<std::string, Harness> harnesses = {
        {"fuzz_calibration", &replay_fuzz_calibration},
        {"fuzz_entities", &replay_fuzz_entities},
        {"fuzz_palettes", &replay_fuzz_palettes},
        {"fuzz_gltf", &replay_fuzz_gltf},
        {"fuzz_point_clouds", &replay_fuzz_point_clouds},
        {"fuzz_kitti_labels", &replay_fuzz_kitti_labels},
        {"fuzz_frame_lists", &replay_fuzz_frame_lists}};
    const auto harness = argc > 1 ? harnesses.find(argv[1]) : harnesses.end();
    if (harness == harnesses.end()) {
        std::fprintf(stderr, "usage: replay_fuzz_inputs <harness> <file or folder>...\n");
        return 2;
    }
    std::vector<std::filesystem::path> files;
    for (int i = 2; i < argc; ++i) {
        const std::filesystem::path arg(argv[i]);
        if (std::filesystem::is_directory(arg)) {
            for (const auto& entry : std::filesystem::directory_iterator(arg)) {
                if (entry.is_regular_file()) files.push_back(entry.path());
            }
        } else if (std::filesystem::is_regular_file(arg)) {
            files.push_back(arg);
        }
    }
    for (const auto& file : files) {
        std::ifstream in(file, std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                      std::istreambuf_iterator<char>());
        harness->second(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    }
    std::printf("%s: %zu inputs replayed\n", argv[1], files.size());
    return 0;
}
