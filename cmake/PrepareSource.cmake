# Prepares a fetched source tree: checks its files against their pinned
# checksum, then applies a patch series. Runs as a script (cmake -P), as the
# PATCH_COMMAND of dpsfm_declare_source (cmake/FetchSource.cmake), in the
# extracted tree:
#   cmake -DNAME=<what> -DSOURCE_DIR=<tree> [-DTREE_SHA256=<sha256>]
#         [-DPATCHES=<patch>|<patch>...] -P PrepareSource.cmake
#
# TREE_SHA256 is the sha256 of the tree's files, names and contents (what
# `find . -type f | sort | xargs sha256sum | sha256sum` prints): archives of
# one tag made by different hosts (GitHub's, a `git archive` mirror's) differ
# in their bytes but hold the same files, so the files are what is pinned.
# A tree that passes gets the marker file .dpsfm-prepared, which
# dpsfm_declare_source takes as "nothing to fetch".
cmake_minimum_required(VERSION 3.16)

# The sha256 of the regular files under dir (symbolic links are not files
# here, as for find -type f), in byte order of their paths.
function(dpsfm_tree_sha256 dir out_var)
  file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE "${dir}" "${dir}/*")
  list(SORT files)
  set(listing "")
  foreach(file IN LISTS files)
    if(IS_SYMLINK "${dir}/${file}")
      continue()
    endif()
    file(SHA256 "${dir}/${file}" hash)
    string(APPEND listing "${hash}  ./${file}\n")
  endforeach()
  string(SHA256 tree "${listing}")
  set(${out_var} "${tree}" PARENT_SCOPE)
endfunction()

if(NOT CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  return()  # included for dpsfm_tree_sha256 only
endif()

if(NOT IS_DIRECTORY "${SOURCE_DIR}")
  message(FATAL_ERROR "dp-sfm: ${NAME}: no source tree at '${SOURCE_DIR}'")
endif()
file(REMOVE "${SOURCE_DIR}/.dpsfm-prepared")

if(TREE_SHA256)
  dpsfm_tree_sha256("${SOURCE_DIR}" actual)
  if(NOT actual STREQUAL TREE_SHA256)
    message(FATAL_ERROR
      "dp-sfm: the files fetched for ${NAME} are not ${NAME}'s (their sha256 "
      "is ${actual}, pinned ${TREE_SHA256}): a wrong or altered archive; "
      "nothing was built from it")
  endif()
endif()

# git apply, kept from looking for a repository above the tree (a build
# directory inside a clone would otherwise make it apply the patches
# relative to the clone, skipping every file).
find_program(GIT_EXECUTABLE git)
if(PATCHES AND NOT GIT_EXECUTABLE)
  message(FATAL_ERROR "dp-sfm: git is needed to patch ${NAME}")
endif()
get_filename_component(parent "${SOURCE_DIR}" DIRECTORY)
set(ENV{GIT_CEILING_DIRECTORIES} "${parent}")
string(REPLACE "|" ";" patches "${PATCHES}")
foreach(patch IN LISTS patches)
  get_filename_component(patch_name "${patch}" NAME)
  execute_process(
    COMMAND "${GIT_EXECUTABLE}" apply --whitespace=nowarn "${patch}"
    WORKING_DIRECTORY "${SOURCE_DIR}"
    RESULT_VARIABLE status ERROR_VARIABLE error)
  if(NOT status EQUAL 0)
    string(STRIP "${error}" error)
    message(FATAL_ERROR
      "dp-sfm: patch ${patch_name} does not apply to ${NAME}: ${error}")
  endif()
  message(STATUS "dp-sfm: applied ${patch_name} to ${NAME}")
endforeach()

file(WRITE "${SOURCE_DIR}/.dpsfm-prepared" "${NAME}\n")
