# libFuzzer builds (STEREOSCENE_FUZZ, clang only; scripts/fuzz.sh configures build-fuzz/ with it).
# Every library is instrumented for coverage with AddressSanitizer and UBSan; the harnesses in
# tests/fuzz link libFuzzer's main.
if(STEREOSCENE_FUZZ)
    if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
        message(FATAL_ERROR "STEREOSCENE_FUZZ needs clang (CXX=clang++): libFuzzer is clang's")
    endif()
    add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
        -fno-sanitize-recover=undefined)
    add_link_options(-fsanitize=address,undefined)
endif()
