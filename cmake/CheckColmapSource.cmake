# Fails configuration early, with a message that says what to do, when
# COLMAP_SOURCE_DIR is not a COLMAP 3.10 tree with colmap_patches/ applied.
function(dpsfm_check_colmap_source dir)
  if(NOT EXISTS "${dir}/src/colmap/exe/colmap.cc")
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} is not a COLMAP source tree "
      "(no src/colmap/exe/colmap.cc).")
  endif()
  file(STRINGS "${dir}/CMakeLists.txt" version_line
       REGEX "set\\(COLMAP_VERSION \"3\\.10")
  if(NOT version_line)
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} is not COLMAP 3.10; dp-sfm is built against "
      "COLMAP 3.10 only.")
  endif()
  file(STRINGS "${dir}/src/colmap/exe/colmap.cc" registered
       REGEX "dpsfm::Commands\\(\\)")
  if(NOT registered)
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} does not register the dp-sfm commands. Apply "
      "the patch series first:\n  cd ${dir} && git apply "
      "${PROJECT_SOURCE_DIR}/colmap_patches/*.patch")
  endif()
endfunction()
