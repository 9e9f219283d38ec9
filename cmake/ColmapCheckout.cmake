# The checkout route: a COLMAP source tree (4.1.x, 4.2.x or 3.10) with
# colmap_patches/ applied, built in this tree, so the plugin links COLMAP's
# in-tree static libraries into COLMAP's own `colmap` binary (the patch
# series registers the commands there).
set(DPSFM_COLMAP_ROUTE checkout)
include(${CMAKE_CURRENT_LIST_DIR}/CheckColmapSource.cmake)
dpsfm_check_colmap_source("${COLMAP_SOURCE_DIR}")

# COLMAP's options for a headless CPU build that downloads nothing (COLMAP 4:
# PoseLib from find_package on CMAKE_PREFIX_PATH, or the one
# cmake/ColmapRelease.cmake declares (FETCH_POSELIB), faiss from the system,
# ONNX and its learned features off); a user may override any of them.
foreach(option CUDA_ENABLED GUI_ENABLED OPENGL_ENABLED CGAL_ENABLED
               TESTS_ENABLED IPO_ENABLED UNINSTALL_ENABLED FETCH_POSELIB
               FETCH_FAISS FETCH_ONNX ONNX_ENABLED DOWNLOAD_ENABLED)
  set(${option} OFF CACHE BOOL "")
endforeach()
# COLMAP overwrites CMAKE_MODULE_PATH and the C++ standard in its own scope.
add_subdirectory(${COLMAP_SOURCE_DIR} colmap)

if(DPSFM_COLMAP_VERSION_MAJOR EQUAL 3)
  # COLMAP 3.10 sets C++14 in its own scope, and at C++14 (only) its
  # util/eigen_alignment.h specialises std::vector for some Eigen types.
  # The plugin is C++17 (std::filesystem, as COLMAP 4), and code that
  # shares those types with COLMAP must see the same vectors, so COLMAP
  # 3.10's own targets are built as C++17 too, as COLMAP 4 is.
  dpsfm_set_cxx_standard_below(${COLMAP_SOURCE_DIR} 17)
endif()
if(NOT DPSFM_COLMAP_ROUTE_DETAIL)
  set(DPSFM_COLMAP_ROUTE_DETAIL "${COLMAP_SOURCE_DIR}")
endif()
message(STATUS "dp-sfm: building into COLMAP ${DPSFM_COLMAP_VERSION} "
               "(${DPSFM_COLMAP_ROUTE_DETAIL}; the commands in `colmap`)")

# COLMAP's in-tree targets carry no include directories or definitions:
# COLMAP sets them for its own directory. Code that includes COLMAP headers
# must see the same ones (some change class layouts), so take them from
# COLMAP's directory.
get_directory_property(COLMAP_INCLUDE_DIRS DIRECTORY ${COLMAP_SOURCE_DIR}
                       INCLUDE_DIRECTORIES)
get_directory_property(COLMAP_COMPILE_DEFINITIONS DIRECTORY
                       ${COLMAP_SOURCE_DIR} COMPILE_DEFINITIONS)
add_library(dpsfm_colmap_headers INTERFACE)
target_include_directories(dpsfm_colmap_headers SYSTEM INTERFACE
                           ${COLMAP_INCLUDE_DIRS})
target_compile_definitions(dpsfm_colmap_headers INTERFACE
                           ${COLMAP_COMPILE_DEFINITIONS}
    DPSFM_COLMAP_VERSION_MAJOR=${DPSFM_COLMAP_VERSION_MAJOR}
    DPSFM_COLMAP_VERSION_MINOR=${DPSFM_COLMAP_VERSION_MINOR})

# The libraries under the names an installed COLMAP exports them by, so the
# plugin names them one way on both routes.
foreach(name controllers exe image mvs scene sensor util)
  add_library(colmap::colmap_${name} ALIAS colmap_${name})
endforeach()
