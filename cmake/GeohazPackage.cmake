# Man pages and bash completion for the apps, and the Debian package (CPack), issue 20.
include(GNUInstallDirs)

set(_geohaz_apps sph-slope debris-runout dem-avalanche geohaz-report geohaz-ensemble geohaz-calibrate slope-stability
    sph-slope-mpi)

# Which Debian package (CPack DEB component) each app goes into: the MPI app on its own, so that
# the other apps do not pull in Open MPI.
set(_geohaz_app_component_geohaz-ensemble mpi)
set(_geohaz_app_component_geohaz-calibrate mpi)
set(_geohaz_app_component_sph-slope-mpi mpi)
foreach(app IN LISTS _geohaz_apps)
  if(NOT DEFINED _geohaz_app_component_${app})
    set(_geohaz_app_component_${app} apps)
  endif()
  # The apps' own install() rules (apps/*/CMakeLists.txt) have no component; this one puts each
  # app into its package (CPACK_COMPONENTS_ALL below leaves the component-less copy out).
  if(TARGET ${app})
    install(TARGETS ${app} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT ${_geohaz_app_component_${app}})
  endif()
endforeach()

# Man pages: generated from each app's --help (and --help-config as a CONFIGURATION section) by
# help2man (Debian package help2man) after the app is built. Without help2man there are none; nor
# in the sanitizer build (nothing is installed from it). SEE ALSO names the data folder of the
# prefix the page is installed under (substituted at install time, so `cpack` with prefix /usr and
# `cmake --install --prefix ~/.local` both get the right path); installed gzipped (gzip -9n, as
# Debian policy 12.3 asks).
find_program(GEOHAZ_HELP2MAN help2man)
find_program(GEOHAZ_GZIP gzip)
if(GEOHAZ_HELP2MAN AND GEOHAZ_GZIP AND NOT GEOHAZ_SANITIZE)
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
    install(CODE "
      set(_dest \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_MANDIR}/man1\")
      file(MAKE_DIRECTORY \"\${_dest}\")
      file(READ \"${page}\" _text)
      string(REPLACE \"@GEOHAZ_DATADIR@\" \"\${CMAKE_INSTALL_PREFIX}/${GEOHAZ_INSTALL_DATADIR}\" _text \"\${_text}\")
      file(WRITE \"\${_dest}/${app}.1\" \"\${_text}\")
      execute_process(COMMAND ${GEOHAZ_GZIP} -9nf \"\${_dest}/${app}.1\" RESULT_VARIABLE _rc)
      if(NOT _rc EQUAL 0)
        message(FATAL_ERROR \"gzip failed on \${_dest}/${app}.1\")
      endif()
      message(STATUS \"Installing: \${_dest}/${app}.1.gz\")
      " COMPONENT ${_geohaz_app_component_${app}})
  endforeach()
  add_custom_target(geohaz_man_pages ALL DEPENDS ${_pages})
else()
  message(STATUS "help2man or gzip not found: no man pages (Debian package help2man, scripts/setup)")
endif()

# bash completion: one script (scripts/completion/geohaz.bash) that reads the options from the
# app's --help and the config keys from --help-config, installed under each app's name where
# bash-completion looks for it.
foreach(app IN LISTS _geohaz_apps)
  if(TARGET ${app})
    install(FILES ${PROJECT_SOURCE_DIR}/scripts/completion/geohaz.bash
            DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME ${app}
            COMPONENT ${_geohaz_app_component_${app}})
  endif()
endforeach()

# Debian packages (issue 37): `cpack -G DEB` in the build folder writes one package per component,
# prefix /usr, split as Debian would:
#   geohaz             the apps sph-slope, debris-runout, dem-avalanche, geohaz-report, their man
#                      pages and completions, README, docs and example data (share/geohaz)
#   geohaz-ensemble    the MPI apps geohaz-ensemble, geohaz-calibrate and sph-slope-mpi (Open MPI only
#                      for those who install it)
#   python3-geohaz     the Python package, for the python3 it was built for
#   libgeohaz-dev      headers, the static libraries and the CMake package (find_package(geohaz))
#   libgeohaz<so>      the shared libraries, only with GEOHAZ_SHARED_LIBS=ON
# The libraries are static by default (GEOHAZ_SHARED_LIBS OFF): their only users are the apps and
# the module, built together, and an unstable C++ ABI (0.x, templates in headers) would need a new
# package name at every release; so the static libraries go into -dev with the headers, as Debian
# does for header-heavy libraries without a stable ABI, and the apps carry their code.
# Depends of the binary packages come from dpkg-shlibdeps (GDAL, HDF5, Boost, libgomp, Open MPI).
set(GEOHAZ_PACKAGE_MAINTAINER "" CACHE STRING
    "Maintainer field of the Debian packages, 'Name <email>' (default: $DEBFULLNAME <$DEBEMAIL>)")
set(_maintainer "${GEOHAZ_PACKAGE_MAINTAINER}")
if(NOT _maintainer AND DEFINED ENV{DEBEMAIL})
  if(DEFINED ENV{DEBFULLNAME})
    set(_maintainer "$ENV{DEBFULLNAME} <$ENV{DEBEMAIL}>")
  else()
    set(_maintainer "$ENV{DEBEMAIL}")
  endif()
endif()
if(NOT _maintainer)
  set(_maintainer "geohaz developers <geohaz@localhost>")
  message(STATUS "Debian packages: no maintainer given, using '${_maintainer}' "
                 "(set -DGEOHAZ_PACKAGE_MAINTAINER='Name <email>' or DEBFULLNAME/DEBEMAIL)")
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME geohaz)
set(CPACK_PACKAGE_VENDOR geohaz)
# CPackDeb puts CPACK_PACKAGE_DESCRIPTION_SUMMARY (by default the project's description) before
# every package's own synopsis unless it is CPack's default text; each package has its own
# synopsis (CPACK_DEBIAN_<COMPONENT>_DESCRIPTION below), so the default text it is.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "geohaz built using CMake")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${_maintainer}")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${_maintainer}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)

set(CPACK_COMPONENTS_ALL apps mpi dev)
if(GEOHAZ_SHARED_LIBS)
  list(APPEND CPACK_COMPONENTS_ALL libs)
endif()
if(TARGET geohaz_python)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()

set(_soname ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
set(CPACK_DEBIAN_APPS_PACKAGE_NAME geohaz)
set(CPACK_DEBIAN_MPI_PACKAGE_NAME geohaz-ensemble)
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-geohaz)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME libgeohaz-dev)
set(CPACK_DEBIAN_LIBS_PACKAGE_NAME libgeohaz${_soname})
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_LIBS_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)

# Inter-package dependencies. The ensemble reads the same example data and docs as the apps.
set(CPACK_DEBIAN_MPI_PACKAGE_DEPENDS "geohaz (= ${PROJECT_VERSION})")
set(CPACK_DEBIAN_APPS_PACKAGE_SUGGESTS "geohaz-ensemble, python3-geohaz, python3-matplotlib, bash-completion")
# python3:Depends as dh_python3 would write it for an extension module built for one version:
# python3 (>= 3.X), python3 (<< 3.X+1); NumPy for the arrays.
if(TARGET geohaz_python)
  math(EXPR _py_next "${GEOHAZ_PYTHON_VERSION_MINOR} + 1")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
      "python3 (>= ${GEOHAZ_PYTHON_VERSION_MAJOR}.${GEOHAZ_PYTHON_VERSION_MINOR}), python3 (<< ${GEOHAZ_PYTHON_VERSION_MAJOR}.${_py_next}), python3-numpy")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SUGGESTS "geohaz, python3-matplotlib")
endif()
# The CMake package's find_dependency() calls need these at the consumer's configure time.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "cmake (>= 3.25), libeigen3-dev, libboost-program-options-dev, libgdal-dev, libcgal-dev, libhdf5-dev, libtomlplusplus-dev, nlohmann-json3-dev, libcairo2-dev, libpango1.0-dev, libnlopt-cxx-dev")
if(GEOHAZ_SHARED_LIBS)
  set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libgeohaz${_soname} (= ${PROJECT_VERSION}), ${CPACK_DEBIAN_DEV_PACKAGE_DEPENDS}")
  set(CPACK_DEBIAN_LIBS_PACKAGE_SHLIBDEPS ON)
endif()

# Descriptions: a synopsis under 80 characters, then lines under 80 (lintian).
set(CPACK_DEBIAN_APPS_DESCRIPTION "landslide models: SPH slope failure, debris runout, bonded DEM
The apps of geohaz: sph-slope (SPH slope failure, strength reduction),
debris-runout (depth-averaged debris runout with hazard maps as GeoTIFF and
QGIS styles), dem-avalanche (bonded-disc DEM), slope-stability (rainfall
infiltration and the infinite-slope factor of safety over a DSM) and
geohaz-report, with man
pages, bash completion, the documentation and example data
(/usr/share/geohaz).")
set(CPACK_DEBIAN_MPI_DESCRIPTION "landslide models: ensembles, calibration and SPH over MPI
geohaz-ensemble runs ensembles of debris-runout with sampled parameters over
MPI ranks and writes probability, mean and percentile maps; geohaz-calibrate
fits debris-runout's parameters to an observed event over the same ranks;
sph-slope-mpi runs sph-slope's SPH model with its particles decomposed over
MPI ranks, for slopes too large for one machine.")
set(CPACK_DEBIAN_PYTHON_DESCRIPTION "landslide models: Python module geohaz
The Python package geohaz runs the geohaz models in-process and returns maps,
particles and series as NumPy arrays; geohaz.read_run reads any output folder
back.")
set(CPACK_DEBIAN_DEV_DESCRIPTION "landslide models: development files
Headers, static libraries and the CMake package of geohaz (find_package:
geohaz::core, geohaz::sph, geohaz::runout, geohaz::dem,
geohaz::report).")
set(CPACK_DEBIAN_LIBS_DESCRIPTION "landslide models: shared libraries
The shared libraries of geohaz (core, sph, runout, dem, report).")
include(CPack)

# The QGIS plugin (qgis/geohaz_provider, docs/qgis.md) as the zip QGIS's plugin manager installs
# ("Install from ZIP"): `cmake --build build --target geohaz_qgis_plugin` → build/geohaz_provider-<v>.zip.
file(GLOB _qgis_plugin_files CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/qgis/geohaz_provider/*.py
     ${PROJECT_SOURCE_DIR}/qgis/geohaz_provider/metadata.txt)
set(_qgis_zip ${PROJECT_BINARY_DIR}/geohaz_provider-${PROJECT_VERSION}.zip)
add_custom_command(
  OUTPUT ${_qgis_zip}
  COMMAND ${CMAKE_COMMAND} -E tar cf ${_qgis_zip} --format=zip -- geohaz_provider
  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}/qgis
  DEPENDS ${_qgis_plugin_files}
  COMMENT "QGIS plugin zip geohaz_provider-${PROJECT_VERSION}.zip"
  VERBATIM)
add_custom_target(geohaz_qgis_plugin DEPENDS ${_qgis_zip})
