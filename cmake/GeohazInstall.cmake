# Install rules and the CMake package of geohaz (issue 20): headers, the five libraries, the apps,
# geohazConfig.cmake / geohazConfigVersion.cmake exporting geohaz::core, geohaz::sph,
# geohaz::runout, geohaz::dem and the report layer above them (geohaz::report), and the README,
# docs and example data under share/geohaz with the layout of the source tree (so every relative
# link keeps working).
#
# Included from the top-level CMakeLists.txt after the libraries and apps exist; the libraries'
# own CMakeLists.txt stay free of install details.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(GEOHAZ_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/geohaz CACHE STRING
    "Where geohazConfig.cmake is installed (relative to the prefix)")
set(GEOHAZ_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/geohaz CACHE STRING
    "Where README.md, docs/ and data/ are installed (relative to the prefix)")

set(_geohaz_libs core sph runout dem report)
foreach(lib IN LISTS _geohaz_libs)
  set(t geohaz_${lib})
  # The libraries name their include folder by absolute source path: usable in the build tree
  # only. Installed, the headers are under <prefix>/include.
  get_target_property(_dirs ${t} INTERFACE_INCLUDE_DIRECTORIES)
  set(_wrapped "")
  foreach(d IN LISTS _dirs)
    if(d MATCHES "^\\$<")
      list(APPEND _wrapped "${d}")
    else()
      list(APPEND _wrapped "$<BUILD_INTERFACE:${d}>")
    endif()
  endforeach()
  set_property(TARGET ${t} PROPERTY INTERFACE_INCLUDE_DIRECTORIES
               ${_wrapped} "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${lib} OUTPUT_NAME geohaz_${lib})
  # Position-independent code (-fPIC rather than Debian's default -fPIE), so that the static
  # libraries can go into the Python module, a shared object. Only then: docs/performance.md
  # ("Python module overhead") compares the apps built both ways.
  if(GEOHAZ_BUILD_PYTHON OR GEOHAZ_SHARED_LIBS)
    set_target_properties(${t} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endif()
  if(GEOHAZ_SHARED_LIBS)
    set_target_properties(${t} PROPERTIES VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  endif()
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/libs/${lib}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          COMPONENT dev FILES_MATCHING PATTERN "*.hpp")
endforeach()
set_target_properties(geohaz_options PROPERTIES EXPORT_NAME options)

install(TARGETS geohaz_options geohaz_core geohaz_sph geohaz_runout geohaz_dem geohaz_report
        EXPORT geohazTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT libs
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT geohazTargets NAMESPACE geohaz:: DESTINATION ${GEOHAZ_INSTALL_CMAKEDIR} COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/geohazConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/geohazConfig.cmake
                              INSTALL_DESTINATION ${GEOHAZ_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/geohazConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/geohazConfig.cmake ${PROJECT_BINARY_DIR}/geohazConfigVersion.cmake
        DESTINATION ${GEOHAZ_INSTALL_CMAKEDIR} COMPONENT dev)

# Apps: installed by their own CMakeLists.txt; with shared libraries they find them relative to
# themselves.
if(GEOHAZ_SHARED_LIBS)
  foreach(app sph-slope debris-runout dem-avalanche geohaz-report geohaz-ensemble geohaz-calibrate slope-stability)
    if(TARGET ${app})
      set_target_properties(${app} PROPERTIES INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
    endif()
  endforeach()
endif()

# README, docs and example data with the source tree's layout: share/geohaz/{README.md,docs,data}.
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${GEOHAZ_INSTALL_DATADIR} COMPONENT apps)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs ${PROJECT_SOURCE_DIR}/data DESTINATION ${GEOHAZ_INSTALL_DATADIR}
        COMPONENT apps)
