# Installation and the Debian package: both tools in bin/, the assets, the schema and the
# synthetic sample under share/stereoscene/. The tools find the assets relative to their own
# folder (stereoscene::support::asset_dir()), so an install works wherever it is moved.

include(GNUInstallDirs)

set(STEREOSCENE_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/stereoscene)

install(TARGETS cloud-analysis scene-render RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/assets/ DESTINATION ${STEREOSCENE_INSTALL_DATADIR}/assets)
install(FILES ${PROJECT_SOURCE_DIR}/schema/entities.schema.json
    ${PROJECT_SOURCE_DIR}/schema/sequence.schema.json
    DESTINATION ${STEREOSCENE_INSTALL_DATADIR}/schema)
# The browser viewer's files as the build gathered them (three.js only where npm installed it).
install(DIRECTORY ${PROJECT_BINARY_DIR}/scene_viewer/web/ DESTINATION ${STEREOSCENE_INSTALL_DATADIR}/web)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/samples/synthetic/
    DESTINATION ${STEREOSCENE_INSTALL_DATADIR}/samples/synthetic)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/README.md
    DESTINATION ${CMAKE_INSTALL_DOCDIR})

# cpack -G DEB: a package for Debian bookworm. Library dependencies come from dpkg-shlibdeps;
# Mesa's EGL and llvmpipe are loaded at run time by GLVND, so they are named here.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME stereoscene)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "stereoscene maintainers <stereoscene@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libegl-mesa0, libgl1-mesa-dri")
include(CPack)
