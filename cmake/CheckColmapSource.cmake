# Fails configuration early, with a message that says what to do, when
# COLMAP_SOURCE_DIR is not a COLMAP tree dp-sfm builds into (3.10, 4.1.x or
# 4.2.x) with colmap_patches/ applied. Sets DPSFM_COLMAP_VERSION (e.g. 4.1.1)
# and DPSFM_COLMAP_VERSION_MAJOR / _MINOR in the caller's scope.
function(dpsfm_check_colmap_source dir)
  if(NOT EXISTS "${dir}/src/colmap/exe/colmap.cc")
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} is not a COLMAP source tree "
      "(no src/colmap/exe/colmap.cc).")
  endif()
  file(STRINGS "${dir}/CMakeLists.txt" version_line
       REGEX "^set\\(COLMAP_VERSION \"[0-9]+\\.[0-9]+")
  string(REGEX MATCH "\"([0-9]+)\\.([0-9]+)([^\"]*)\"" version_match
         "${version_line}")
  set(major "${CMAKE_MATCH_1}")
  set(minor "${CMAKE_MATCH_2}")
  set(version "${major}.${minor}${CMAKE_MATCH_3}")
  if(NOT (version MATCHES "^3\\.10" OR version MATCHES "^4\\.[12]\\."))
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} is COLMAP '${version}'; dp-sfm builds into "
      "COLMAP 4.1.x, 4.2.x or 3.10.")
  endif()
  file(STRINGS "${dir}/src/colmap/exe/colmap.cc" registered
       REGEX "dpsfm::Commands\\(\\)")
  if(NOT registered)
    message(FATAL_ERROR
      "COLMAP_SOURCE_DIR=${dir} does not register the dp-sfm commands. Apply "
      "the patch series first:\n  cd ${dir} && git apply "
      "${PROJECT_SOURCE_DIR}/colmap_patches/*.patch")
  endif()
  set(DPSFM_COLMAP_VERSION "${version}" PARENT_SCOPE)
  set(DPSFM_COLMAP_VERSION_MAJOR "${major}" PARENT_SCOPE)
  set(DPSFM_COLMAP_VERSION_MINOR "${minor}" PARENT_SCOPE)
endfunction()

# Sets CXX_STANDARD on every compiled target defined in dir or below it.
function(dpsfm_set_cxx_standard_below dir standard)
  get_directory_property(targets DIRECTORY "${dir}" BUILDSYSTEM_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY|EXECUTABLE)$")
      set_target_properties(${target} PROPERTIES CXX_STANDARD ${standard})
    endif()
  endforeach()
  get_directory_property(subdirs DIRECTORY "${dir}" SUBDIRECTORIES)
  foreach(subdir IN LISTS subdirs)
    dpsfm_set_cxx_standard_below("${subdir}" ${standard})
  endforeach()
endfunction()
