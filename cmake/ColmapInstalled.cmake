# The installed route: COLMAP 4.1.x or 4.2.x found by find_package (its
# share/colmap/colmap-config.cmake, from `cmake --install` of a COLMAP
# build, the colmap/colmap container image or a package), with PoseLib and
# COLMAP's other dependencies on CMAKE_PREFIX_PATH. No COLMAP source, no
# patch: the commands get a thin executable of their own, `dpsfm`.
#
# COLMAP's package version file accepts only an exact version, so the
# package is found without one and its version gated here.
set(DPSFM_COLMAP_ROUTE installed)
find_package(COLMAP QUIET)
if(NOT COLMAP_FOUND)
  message(FATAL_ERROR
    "dp-sfm: no installed COLMAP found (share/colmap/colmap-config.cmake). "
    "Pass -DCMAKE_PREFIX_PATH=\"<COLMAP prefix>;<PoseLib prefix>\", or "
    "build into a COLMAP checkout with -DCOLMAP_SOURCE_DIR (docs/building.md).")
endif()
if(COLMAP_VERSION MATCHES "^3\\.")
  message(FATAL_ERROR
    "dp-sfm: COLMAP ${COLMAP_VERSION} found at ${COLMAP_DIR}: the installed "
    "route needs COLMAP 4.1.x or 4.2.x. COLMAP 3.x installs a C++14 build "
    "whose Eigen vectors the plugin (C++17) cannot share; build into a 3.10 "
    "checkout instead (-DCOLMAP_SOURCE_DIR, which rebuilds it as C++17; "
    "docs/building.md).")
endif()
if(NOT COLMAP_VERSION MATCHES "^4\\.[12](\\.|$)")
  message(FATAL_ERROR
    "dp-sfm: COLMAP ${COLMAP_VERSION} found at ${COLMAP_DIR}: dp-sfm builds "
    "against COLMAP 4.1.x or 4.2.x.")
endif()
string(REGEX MATCH "^([0-9]+)\\.([0-9]+)" _ "${COLMAP_VERSION}")
set(DPSFM_COLMAP_VERSION "${COLMAP_VERSION}")
set(DPSFM_COLMAP_VERSION_MAJOR "${CMAKE_MATCH_1}")
set(DPSFM_COLMAP_VERSION_MINOR "${CMAKE_MATCH_2}")
message(STATUS "dp-sfm: building against the installed COLMAP "
               "${COLMAP_VERSION} at ${COLMAP_DIR} (the commands in `dpsfm`)")

# The installed targets carry COLMAP's include directory and definitions.
add_library(dpsfm_colmap_headers INTERFACE)
target_link_libraries(dpsfm_colmap_headers INTERFACE colmap::colmap)
target_compile_definitions(dpsfm_colmap_headers INTERFACE
    DPSFM_COLMAP_VERSION_MAJOR=${DPSFM_COLMAP_VERSION_MAJOR}
    DPSFM_COLMAP_VERSION_MINOR=${DPSFM_COLMAP_VERSION_MINOR})
