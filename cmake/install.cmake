# `cmake --install`: the headers, the shared library as libsketchbody.so.X.Y.Z with the
# libsketchbody.so.X (SONAME) and libsketchbody.so symlinks, the static library, the CMake package
# (sketchbodyConfig.cmake, sketchbodyConfigVersion.cmake) and sketchbody.pc. Included by the
# top-level CMakeLists.txt after the imported targets are defined.

set(SKB_REAL_NAME "${SKB_SONAME}.${PROJECT_VERSION_MINOR}.${PROJECT_VERSION_PATCH}")
set(SKB_LINK_NAME "${CMAKE_SHARED_LIBRARY_PREFIX}sketchbody${CMAKE_SHARED_LIBRARY_SUFFIX}")
set(SKB_STATIC_NAME "${CMAKE_STATIC_LIBRARY_PREFIX}sketchbody${CMAKE_STATIC_LIBRARY_SUFFIX}")
set(SKB_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/sketchbody")

# Release builds install the libraries without what a consumer does not need: the shared library
# without debug info and without its static symbol table (the exported skb_* symbols are in the
# dynamic one), the static library without debug info and without the LLVM bitcode of the Rust
# standard library's objects (.llvmbc, .llvmcmd: only rustc's LTO reads them; linkers exclude
# them). The test command prints the installed sizes (cpp_tests/consumer/run.sh; figures in
# docs/plugins.md). Debug and RelWithDebInfo keep everything, and so does SKB_KEEP_DEBUG_INFO=ON.
set(SKB_STRIP_ON_INSTALL OFF)
if(NOT SKB_KEEP_DEBUG_INFO AND NOT CMAKE_BUILD_TYPE MATCHES "^(Debug|RelWithDebInfo)$" AND CMAKE_STRIP)
  set(SKB_STRIP_ON_INSTALL ON)
endif()

install(FILES include/sketchbody.h include/sketchbody.hpp
        DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}" COMPONENT Development)
install(FILES "${SKB_SHARED_LIB}" DESTINATION "${CMAKE_INSTALL_LIBDIR}" RENAME "${SKB_REAL_NAME}"
        PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE
        COMPONENT Runtime)
install(FILES "${SKB_STATIC_LIB}" DESTINATION "${CMAKE_INSTALL_LIBDIR}" COMPONENT Development)

# The symlinks (and the stripping) happen at install time, in the folder actually installed to
# (`--prefix` and DESTDIR respected).
install(CODE "
  set(skb_libdir \"${CMAKE_INSTALL_LIBDIR}\")
  if(NOT IS_ABSOLUTE \"\${skb_libdir}\")
    set(skb_libdir \"\${CMAKE_INSTALL_PREFIX}/\${skb_libdir}\")
  endif()
  set(skb_libdir \"\$ENV{DESTDIR}\${skb_libdir}\")
  set(skb_strip ${SKB_STRIP_ON_INSTALL})
  if(skb_strip)
    foreach(skb_strip_args \"--strip-unneeded;${SKB_REAL_NAME}\"
                           \"--strip-debug;--remove-section=.llvmbc;--remove-section=.llvmcmd;${SKB_STATIC_NAME}\")
      list(POP_BACK skb_strip_args skb_lib)
      message(STATUS \"Stripping (\${skb_strip_args}): \${skb_libdir}/\${skb_lib}\")
      execute_process(COMMAND \"${CMAKE_STRIP}\" \${skb_strip_args} \"\${skb_libdir}/\${skb_lib}\"
                      RESULT_VARIABLE skb_rc)
      if(NOT skb_rc EQUAL 0)
        message(FATAL_ERROR \"strip \${skb_strip_args} failed on \${skb_lib}\")
      endif()
    endforeach()
  endif()
  file(CREATE_LINK \"${SKB_REAL_NAME}\" \"\${skb_libdir}/${SKB_SONAME}\" SYMBOLIC)
  file(CREATE_LINK \"${SKB_SONAME}\" \"\${skb_libdir}/${SKB_LINK_NAME}\" SYMBOLIC)
  message(STATUS \"Symlinks: ${SKB_LINK_NAME} -> ${SKB_SONAME} -> ${SKB_REAL_NAME}\")
" COMPONENT Runtime)

# The CMake package.
set(SKB_INSTALL_STATIC_DEPS "m;pthread;${CMAKE_DL_LIBS}")
configure_package_config_file(cmake/sketchbodyConfig.cmake.in
  "${CMAKE_CURRENT_BINARY_DIR}/sketchbodyConfig.cmake"
  INSTALL_DESTINATION "${SKB_CMAKE_DIR}"
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR CMAKE_INSTALL_LIBDIR)
# From 1.0 every minor version keeps the ABI (docs/c-api.md, "Compatibility policy").
write_basic_package_version_file("${CMAKE_CURRENT_BINARY_DIR}/sketchbodyConfigVersion.cmake"
  VERSION "${PROJECT_VERSION}" COMPATIBILITY SameMajorVersion)
install(FILES "${CMAKE_CURRENT_BINARY_DIR}/sketchbodyConfig.cmake"
              "${CMAKE_CURRENT_BINARY_DIR}/sketchbodyConfigVersion.cmake"
        DESTINATION "${SKB_CMAKE_DIR}" COMPONENT Development)

# pkg-config: prefix relative to the .pc file, so the installed tree can be moved.
file(RELATIVE_PATH SKB_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
string(REGEX REPLACE "/$" "" SKB_PC_TO_PREFIX "${SKB_PC_TO_PREFIX}")
set(SKB_PC_PRIVATE "")
foreach(skb_dep IN LISTS SKB_INSTALL_STATIC_DEPS)
  string(APPEND SKB_PC_PRIVATE " -l${skb_dep}")
endforeach()
string(STRIP "${SKB_PC_PRIVATE}" SKB_PC_PRIVATE)
configure_file(cmake/sketchbody.pc.in "${CMAKE_CURRENT_BINARY_DIR}/sketchbody.pc" @ONLY)
install(FILES "${CMAKE_CURRENT_BINARY_DIR}/sketchbody.pc"
        DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig" COMPONENT Development)
