// Entity files: the strict JSON reader, the schema's validator and the conversion to types.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        // from_json() runs validate() and throws on its first issue: the text is parsed once.
        const scene_schema::EntityDocument parsed =
            scene_schema::from_json(scene_schema::parse_json(text));
        scene_schema::dump(parsed);
    } catch (const std::exception&) {
    }
    return 0;
}
