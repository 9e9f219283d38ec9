# Pinned third-party sources, fetched, verified and patched by CMake.
#
# dpsfm_declare_source(<name>
#     ARCHIVE <file name> SHA256 <the archive's sha256>
#     URL <its release on its usual home> [URL_SHA256 <that archive's sha256>]
#     [TREE_SHA256 <the sha256 of its files>] [PATCHES <patch>...])
#
# declares <name> for FetchContent (FetchContent_Populate or
# FetchContent_MakeAvailable, here or in a project that declares it later:
# the first declaration wins). Where it comes from:
#  - <DPSFM_SOURCES_DIR>/<ARCHIVE> (a local mirror, ../shared/sources beside
#    the source tree by default) when that file's sha256 is SHA256 (URL_HASH);
#  - else URL, checked by URL_SHA256 when that host's archive is pinned (a
#    Debian orig tarball is the same file everywhere; GitHub's archives of a
#    tag are not the mirror's bytes), and in any case by TREE_SHA256.
# The extracted tree is checked against TREE_SHA256 and PATCHES are applied
# in order (cmake/PrepareSource.cmake as PATCH_COMMAND). The tree lands in
# <FETCHCONTENT_BASE_DIR>/<name>-<key>, keyed by the pins and the patch
# series (names and contents), so another series prepares another tree;
# a prepared tree is used as it is, without fetching anything again.

include(FetchContent)
set(DPSFM_PREPARE_SOURCE_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/PrepareSource.cmake")

set(DPSFM_SOURCES_DIR "" CACHE PATH
    "A local mirror of source archives (empty: ../shared/sources beside \
the source tree, or $ENV{DPSFM_SOURCES_DIR})")

# The mirror directory: the cache entry, the environment, or
# ../shared/sources beside the (resolved) source tree.
function(dpsfm_sources_dir out_var)
  if(DPSFM_SOURCES_DIR)
    set(dir "${DPSFM_SOURCES_DIR}")
  elseif(DEFINED ENV{DPSFM_SOURCES_DIR})
    set(dir "$ENV{DPSFM_SOURCES_DIR}")
  else()
    get_filename_component(root "${PROJECT_SOURCE_DIR}" REALPATH)
    set(dir "${root}/../shared/sources")
  endif()
  get_filename_component(dir "${dir}" REALPATH)
  set(${out_var} "${dir}" PARENT_SCOPE)
endfunction()

function(dpsfm_declare_source name)
  cmake_parse_arguments(PARSE_ARGV 1 arg ""
                        "ARCHIVE;SHA256;URL;URL_SHA256;TREE_SHA256" "PATCHES")
  if(NOT arg_ARCHIVE OR NOT arg_SHA256 OR NOT arg_URL)
    message(FATAL_ERROR "dpsfm_declare_source(${name}): ARCHIVE, SHA256 and "
                        "URL are required")
  endif()

  # The key: the pins and the patch series, names and contents in order.
  set(key_text "${arg_SHA256} ${arg_URL_SHA256} ${arg_TREE_SHA256}\n")
  foreach(patch IN LISTS arg_PATCHES)
    get_filename_component(patch_name "${patch}" NAME)
    file(SHA256 "${patch}" patch_hash)
    string(APPEND key_text "${patch_name} ${patch_hash}\n")
  endforeach()
  string(SHA256 key "${key_text}")
  string(SUBSTRING "${key}" 0 16 key)
  if(NOT FETCHCONTENT_BASE_DIR)
    set(FETCHCONTENT_BASE_DIR "${CMAKE_BINARY_DIR}/_deps")
  endif()
  set(source_dir "${FETCHCONTENT_BASE_DIR}/${name}-${key}")
  string(TOUPPER "${name}" upper_name)
  # A patch changes the tree's key, and COLMAP's configuration must run
  # again to prepare the new tree.
  set_property(DIRECTORY "${CMAKE_SOURCE_DIR}" APPEND PROPERTY
               CMAKE_CONFIGURE_DEPENDS ${arg_PATCHES})

  if(EXISTS "${source_dir}/.dpsfm-prepared")
    # Prepared before (verified and patched): FetchContent uses it as given.
    set(FETCHCONTENT_SOURCE_DIR_${upper_name} "${source_dir}" PARENT_SCOPE)
    message(STATUS "dp-sfm: ${name} from ${source_dir} (prepared)")
    FetchContent_Declare(${name} SOURCE_DIR "${source_dir}")
    return()
  endif()
  # Trees of other keys (an earlier patch series) are not used again.
  file(GLOB stale LIST_DIRECTORIES true "${FETCHCONTENT_BASE_DIR}/${name}-*")
  foreach(dir IN LISTS stale)
    if(IS_DIRECTORY "${dir}" AND EXISTS "${dir}/.dpsfm-prepared")
      file(REMOVE_RECURSE "${dir}")
    endif()
  endforeach()

  dpsfm_sources_dir(mirror_dir)
  set(mirror "${mirror_dir}/${arg_ARCHIVE}")
  set(from "")
  if(EXISTS "${mirror}")
    file(SHA256 "${mirror}" mirror_hash)
    if(mirror_hash STREQUAL arg_SHA256)
      set(from URL "${mirror}" URL_HASH SHA256=${arg_SHA256})
      message(STATUS "dp-sfm: ${name} from ${mirror} (sha256 matches)")
    else()
      message(WARNING "dp-sfm: ${mirror} does not have the pinned sha256 "
                      "${arg_SHA256}; not using it")
    endif()
  endif()
  if(NOT from)
    set(from URL "${arg_URL}")
    if(arg_URL_SHA256)
      list(APPEND from URL_HASH SHA256=${arg_URL_SHA256})
    endif()
    message(STATUS "dp-sfm: ${name} from ${arg_URL} (${mirror_dir} has no "
                   "${arg_ARCHIVE} with the pinned sha256)")
  endif()
  if(NOT CMAKE_VERSION VERSION_LESS 3.24)
    list(APPEND from DOWNLOAD_EXTRACT_TIMESTAMP TRUE)
  endif()

  string(REPLACE ";" "|" patches "${arg_PATCHES}")
  FetchContent_Declare(${name}
    ${from}
    SOURCE_DIR "${source_dir}"
    PATCH_COMMAND "${CMAKE_COMMAND}" "-DNAME=${name}"
                  "-DSOURCE_DIR=${source_dir}"
                  "-DTREE_SHA256=${arg_TREE_SHA256}" "-DPATCHES=${patches}"
                  -P "${DPSFM_PREPARE_SOURCE_SCRIPT}")
endfunction()
