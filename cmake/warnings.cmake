# INTERFACE target carrying the project's warning flags; link it PRIVATE.
add_library(stereoscene_warnings INTERFACE)
add_library(stereoscene::warnings ALIAS stereoscene_warnings)
target_compile_options(stereoscene_warnings INTERFACE
    $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
        -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wnull-dereference
        -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough>)
