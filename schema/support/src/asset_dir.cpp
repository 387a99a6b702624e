#include "stereoscene/support/asset_dir.hpp"

#include <cstdlib>
#include <string>
#include <system_error>

#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/build_tree.hpp"

namespace stereoscene::support {

namespace fs = std::filesystem;

fs::path executable_dir() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : exe.parent_path();
}

fs::path asset_dir() {
    std::error_code ec;
    if (const char* env = std::getenv(kAssetsEnv); env != nullptr && *env != '\0') {
        if (!fs::is_directory(env, ec)) {
            throw FileError(std::string(env) + ": no such assets folder (from $" + kAssetsEnv +
                            ")");
        }
        return fs::path(env);
    }
    std::string tried;
    if (const fs::path bin = executable_dir(); !bin.empty()) {
        const fs::path installed = (bin / kInstalledAssetsFromBin).lexically_normal();
        if (fs::is_directory(installed, ec)) return installed;
        tried = installed.string() + ", ";
    }
    const fs::path source(kSourceTreeAssetsDir);
    if (fs::is_directory(source, ec)) return source;
    throw FileError(tried + source.string() + ": no assets folder found; set $" +
                    std::string(kAssetsEnv));
}

}  // namespace stereoscene::support
