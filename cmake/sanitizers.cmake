# Global AddressSanitizer + UndefinedBehaviorSanitizer switch (STEREOSCENE_SANITIZE).
# -O1 -g1 (after the build type's -O2 -g): the instrumentation and its checks are the same, the
# reports keep file and line, and the build takes far less time than at -O2 with full debug
# information, which on two cores is most of the sanitizer run.
if(STEREOSCENE_SANITIZE)
    add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
        -O1 -g1)
    add_link_options(-fsanitize=address,undefined)
endif()
