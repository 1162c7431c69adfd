# `cmake --install build --prefix P` (docs/cli.md, "Installing"): the tools in P/bin, the libraries
# (static) in P/lib, each library's public headers in P/include, the CMake package
# (find_package(tomodem): targets tomodem::core, tomodem::dem, ...) in P/lib/cmake/tomodem, one man
# page per tool in P/share/man/man1 and its bash completion in P/share/bash-completion/completions,
# both generated at install time from the tool's own options (TOOL --help-man, --help-completion).
# Only the libraries this build has are installed (the MPI build leaves out image and carve).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(_tomodem_libs core spatial linalg dem network pipeline geometry image mechanics carve fields)
set(_tomodem_exported)
foreach(lib ${_tomodem_libs})
  if(NOT TARGET tomodem_${lib})
    continue()
  endif()
  # In-tree the headers come from libs/<lib>/include, installed from P/include.
  get_target_property(_inc tomodem_${lib} INTERFACE_INCLUDE_DIRECTORIES)
  set(_wrapped)
  foreach(d ${_inc})
    list(APPEND _wrapped "$<BUILD_INTERFACE:${d}>")
  endforeach()
  list(APPEND _wrapped "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  set_target_properties(tomodem_${lib} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_wrapped}" EXPORT_NAME ${lib})
  list(APPEND _tomodem_exported tomodem_${lib})
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/libs/${lib}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
# Interface targets a static library links privately (its objects need them at link time): the
# DEM's private headers (nothing to install: build tree only) and, in the MPI build, tomodem_mpi.
foreach(t tomodem_dem_private tomodem_mpi)
  if(TARGET ${t})
    get_target_property(_inc ${t} INTERFACE_INCLUDE_DIRECTORIES)
    if(_inc)
      set(_wrapped)
      foreach(d ${_inc})
        list(APPEND _wrapped "$<BUILD_INTERFACE:${d}>")
      endforeach()
      set_target_properties(${t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_wrapped}")
    endif()
    string(REPLACE "tomodem_" "" _name ${t})
    set_target_properties(${t} PROPERTIES EXPORT_NAME ${_name})
    list(APPEND _tomodem_exported ${t})
  endif()
endforeach()

install(TARGETS ${_tomodem_exported} EXPORT tomodemTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT tomodemTargets NAMESPACE tomodem:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tomodem)

# The find_dependency calls of tomodemConfig.cmake: every package whose targets the exported
# (static) libraries link, plus the header-only ones the public headers include
# (nlohmann/json.hpp in core/summary.hpp, yaml-cpp in dem/yaml_fields.hpp, CLI11 in core/cli.hpp).
set(TOMODEM_CONFIG_DEPENDENCIES "find_dependency(OpenMP COMPONENTS CXX)
find_dependency(fmt)
find_dependency(yaml-cpp)
find_dependency(nlohmann_json 3)
")
if(TARGET tomodem_linalg OR TARGET tomodem_network OR TARGET tomodem_mechanics)
  string(APPEND TOMODEM_CONFIG_DEPENDENCIES "find_dependency(Eigen3 3.3 NO_MODULE)\n")
endif()
if(TARGET tomodem_geometry OR TARGET tomodem_carve)
  string(APPEND TOMODEM_CONFIG_DEPENDENCIES "find_dependency(CGAL)\n")
endif()
if(TARGET tomodem_image)
  string(APPEND TOMODEM_CONFIG_DEPENDENCIES
    "find_dependency(ITK 5 COMPONENTS ${TOMODEM_ITK_COMPONENTS})\n"
    "find_dependency(ZLIB)\n"
    "list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/local/lib/cmake/OpenVDB)\n"
    "find_dependency(OpenVDB)\n"
    "# Debian's small OpenCV packages have no CMake config: the libraries are linked by path then.\n"
    "find_package(OpenCV QUIET COMPONENTS core imgproc)\n")
endif()
if(TARGET tomodem_mpi)
  string(APPEND TOMODEM_CONFIG_DEPENDENCIES
    "find_dependency(MPI COMPONENTS C CXX)\n"
    "find_dependency(PkgConfig)\n"
    "pkg_check_modules(PETSC REQUIRED IMPORTED_TARGET PETSc)\n")
endif()

configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/tomodemConfig.cmake.in
  ${CMAKE_BINARY_DIR}/cmake/tomodemConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tomodem)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cmake/tomodemConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cmake/tomodemConfig.cmake ${CMAKE_BINARY_DIR}/cmake/tomodemConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/tomodem)

# The dispatcher `tomodem VERB` (the verbs install themselves: tools/CMakeLists.txt).
install(TARGETS tomodem RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Man pages and completions, written at install time by the installed tools' own binaries.
set(_tomodem_tools)
foreach(verb dem run conduct segment phantom pack bond young sinter fracture carve cg)
  if(TARGET tomodem-${verb})
    list(APPEND _tomodem_tools tomodem-${verb})
  endif()
endforeach()
foreach(t ${_tomodem_tools})
  install(CODE "
    set(_root \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}\")
    file(MAKE_DIRECTORY \"\${_root}/${CMAKE_INSTALL_MANDIR}/man1\" \"\${_root}/${CMAKE_INSTALL_DATAROOTDIR}/bash-completion/completions\")
    foreach(_kind man completion)
      if(_kind STREQUAL man)
        set(_out \"\${_root}/${CMAKE_INSTALL_MANDIR}/man1/${t}.1\")
      else()
        set(_out \"\${_root}/${CMAKE_INSTALL_DATAROOTDIR}/bash-completion/completions/${t}\")
      endif()
      message(STATUS \"Installing: \${_out}\")
      execute_process(COMMAND \"$<TARGET_FILE:${t}>\" --help-\${_kind} OUTPUT_FILE \"\${_out}\" RESULT_VARIABLE _rc)
      if(NOT _rc EQUAL 0)
        message(FATAL_ERROR \"${t} --help-\${_kind} failed (\${_rc})\")
      endif()
      list(APPEND CMAKE_INSTALL_MANIFEST_FILES \"\${_out}\")
    endforeach()
  ")
endforeach()
