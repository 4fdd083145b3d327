# Man pages and bash completion for the apps, and the Debian package (CPack), issue 20.
include(GNUInstallDirs)

set(_geohaz_apps sph-slope debris-runout dem-avalanche geohaz-report geohaz-ensemble geohaz-calibrate slope-stability)

# Man pages: generated from each app's --help (and --help-config as a CONFIGURATION section) by
# help2man (Debian package help2man) after the app is built. Without help2man there are none; nor
# in the sanitizer build (nothing is installed from it).
find_program(GEOHAZ_HELP2MAN help2man)
if(GEOHAZ_HELP2MAN AND NOT GEOHAZ_SANITIZE)
  set(_man_dir ${PROJECT_BINARY_DIR}/man)
  set(_pages "")
  foreach(app IN LISTS _geohaz_apps)
    if(NOT TARGET ${app})
      continue()
    endif()
    set(page ${_man_dir}/${app}.1)
    add_custom_command(
      OUTPUT ${page}
      COMMAND ${CMAKE_COMMAND} -DAPP=$<TARGET_FILE:${app}> -DNAME=${app} -DHELP2MAN=${GEOHAZ_HELP2MAN}
              -DOUT=${page} -DVERSION=${PROJECT_VERSION} -P ${PROJECT_SOURCE_DIR}/cmake/geohaz_man_page.cmake
      DEPENDS ${app} ${PROJECT_SOURCE_DIR}/cmake/geohaz_man_page.cmake
      COMMENT "Man page ${app}.1 from ${app} --help"
      VERBATIM)
    list(APPEND _pages ${page})
  endforeach()
  add_custom_target(geohaz_man_pages ALL DEPENDS ${_pages})
  install(FILES ${_pages} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)
else()
  message(STATUS "help2man not found: no man pages (Debian package help2man, scripts/setup)")
endif()

# bash completion: one script (scripts/completion/geohaz.bash) that reads the options from the
# app's --help and the config keys from --help-config, installed under each app's name where
# bash-completion looks for it.
foreach(app IN LISTS _geohaz_apps)
  if(TARGET ${app})
    install(FILES ${PROJECT_SOURCE_DIR}/scripts/completion/geohaz.bash
            DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME ${app} COMPONENT runtime)
  endif()
endforeach()

# Debian package: cpack -G DEB in the build folder → geohaz_<version>_amd64.deb, prefix /usr.
# Depends: the shared libraries the apps and the Python module link (dpkg-shlibdeps) plus python3
# and python3-numpy; Recommends: the -dev packages a C++ project using find_package(geohaz) needs.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME geohaz)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "geohaz developers <geohaz@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3 (>= 3.9), python3-numpy")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "cmake, libeigen3-dev, libboost-program-options-dev, libgdal-dev, libcgal-dev, libhdf5-dev, libtomlplusplus-dev, nlohmann-json3-dev, libcairo2-dev, libpango1.0-dev, libnlopt-cxx-dev")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3-matplotlib, bash-completion")
set(CPACK_PACKAGE_DESCRIPTION
    "geohaz: landslides from the first slip to the final deposit. SPH slope failure (sph-slope), depth-averaged debris runout with hazard maps (debris-runout), bonded-disc DEM (dem-avalanche), rainfall-driven stability maps of a DSM (slope-stability), the C++ libraries with their CMake package, the Python module geohaz, example data and documentation (/usr/share/geohaz).")
# Only what `cmake --install` installs (no test or benchmark binaries: they are not installed).
include(CPack)
