# The release route: a pinned COLMAP release (DPSFM_COLMAP_RELEASE) fetched,
# verified and patched with colmap_patches/ by CMake (cmake/FetchSource.cmake),
# then built as a checkout (cmake/ColmapCheckout.cmake). The README's
# commands take this route (make passes -DDPSFM_COLMAP_RELEASE=4.1.1, or 3.10).
#
# The pins: each archive's sha256 as the local mirror (../shared/sources,
# `git archive` tarballs) holds it, and the sha256 of its files, which a
# download of the same tag from its usual home must match.
#   4.1.1  COLMAP 4.1.1 (2026-07-17), tag 4.1.1, with PoseLib a69263d: 4.1.1
#          pins PoseLib fa7280f, which no archive at hand holds; a69263d
#          (2026-03-18, after v2.0.5) is the newest that does, and builds it.
#          It is declared before COLMAP's own declaration, so it wins, and
#          COLMAP builds and installs it with its libraries (FETCH_POSELIB).
#   3.10   COLMAP 3.10 (2024): Debian's orig tarball, the same file on every
#          Debian mirror (DPSFM_DEBIAN_MIRROR).
#   main   COLMAP's main branch of 2026-08-08 (4.2.0.dev0), 5d968cf: for
#          make check-colmap-main, which compiles dp-sfm against its headers;
#          COLMAP itself does not build from it with this PoseLib.
set(DPSFM_DEBIAN_MIRROR "http://deb.debian.org/debian" CACHE STRING
    "The Debian mirror COLMAP 3.10's orig tarball is downloaded from")

file(GLOB DPSFM_COLMAP_PATCHES "${PROJECT_SOURCE_DIR}/colmap_patches/*.patch")
list(SORT DPSFM_COLMAP_PATCHES)

set(poselib_pin
    ARCHIVE PoseLib-a69263d.tar.gz
    SHA256 23b53638f5de08077d55fb09399c65bf9d3b2e56f3cbad765e538a08ad6211dc
    TREE_SHA256 bfa1560f4f309b977f19105d24c3a838c26f70b906a41a496b3547c0d5117b93
    URL https://github.com/PoseLib/PoseLib/archive/a69263d5d824b5de11e48756f33f6e8ebb231f0c.tar.gz)
if(DPSFM_COLMAP_RELEASE STREQUAL "4.1.1")
  set(colmap_pin
      ARCHIVE colmap-4.1.1.tar.gz
      SHA256 40c13979bca58db4cd0429e1a0e51c1482dd6adb12ec9ac1e0796bdaf6e20d9c
      TREE_SHA256 5b2153a2e08716034b8be05ff7b6698a911424c923abba2508d776407404cb57
      URL https://github.com/colmap/colmap/archive/refs/tags/4.1.1.tar.gz)
elseif(DPSFM_COLMAP_RELEASE STREQUAL "3.10")
  set(poselib_pin "")
  set(colmap_pin
      ARCHIVE colmap_3.10.orig.tar.gz
      SHA256 61850f323e201ab6a1abbfb0e4a8b3ba1c4cedbf55e0a5716bdea1df8ae1813a
      URL ${DPSFM_DEBIAN_MIRROR}/pool/main/c/colmap/colmap_3.10.orig.tar.gz
      URL_SHA256 61850f323e201ab6a1abbfb0e4a8b3ba1c4cedbf55e0a5716bdea1df8ae1813a)
elseif(DPSFM_COLMAP_RELEASE STREQUAL "main")
  set(colmap_pin
      ARCHIVE colmap-main-5d968cf.tar.gz
      SHA256 81adf4db8bf87b7a2c55aa89e27c9531fb011be99f17a339d195ae81c7ead8fb
      TREE_SHA256 18c2ef9e22f3b2bdf1fc40ffbca63d556ed57e04cf52a613c78ff1a7831f7a24
      URL https://github.com/colmap/colmap/archive/5d968cf38aa2574fd284b0dc86c3d58d124940b3.tar.gz)
else()
  message(FATAL_ERROR
    "dp-sfm: DPSFM_COLMAP_RELEASE=${DPSFM_COLMAP_RELEASE} is not a COLMAP "
    "release dp-sfm fetches (4.1.1, 3.10; main for the compile check); for "
    "another COLMAP use -DCOLMAP_SOURCE_DIR=<your patched checkout> or an "
    "installed COLMAP (docs/building.md)")
endif()

include(${CMAKE_CURRENT_LIST_DIR}/FetchSource.cmake)
if(poselib_pin)
  dpsfm_declare_source(poselib ${poselib_pin})
  set(FETCH_POSELIB ON CACHE BOOL "")
endif()
dpsfm_declare_source(colmap ${colmap_pin} PATCHES ${DPSFM_COLMAP_PATCHES})
FetchContent_GetProperties(colmap)
if(NOT colmap_POPULATED)
  FetchContent_Populate(colmap)
endif()
set(COLMAP_SOURCE_DIR "${colmap_SOURCE_DIR}")
set(DPSFM_COLMAP_ROUTE_DETAIL "the release, fetched, verified and patched")
include(${CMAKE_CURRENT_LIST_DIR}/ColmapCheckout.cmake)
