# Compiler cache (issue 41): every build tree compiles through ccache when it is installed
# (SEMAP_CCACHE=ON, the default). The cache itself (directory, size, base dir) is set by the
# scripts (scripts/ccache-env.sh): CI builds a fresh clone in another folder each run, so the
# cache lives outside the clone and paths under the clone are hashed relative to it.
option(SEMAP_CCACHE "Compile through ccache when it is installed" ON)
if(SEMAP_CCACHE)
  find_program(SEMAP_CCACHE_PROGRAM ccache)
  if(SEMAP_CCACHE_PROGRAM)
    # Precompiled headers with ccache (ccache manual, "Precompiled headers"): the PCH's own
    # defines and time macros are not hashed, include-file times do not matter (a fresh clone
    # has new ones), and CMake's clang PCH is built with -fno-pch-timestamp. That serves the gcc
    # trees in any clone; a clang PCH still misses in a clone other than the one that filled the
    # cache (its absolute paths), so the clang ASan tree builds without one (scripts/lib/asan-tree.sh).
    set(_semap_ccache_env CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime)
    set(CMAKE_C_COMPILER_LAUNCHER ${CMAKE_COMMAND} -E env ${_semap_ccache_env} ${SEMAP_CCACHE_PROGRAM})
    set(CMAKE_CXX_COMPILER_LAUNCHER ${CMAKE_COMMAND} -E env ${_semap_ccache_env} ${SEMAP_CCACHE_PROGRAM})
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang" AND SEMAP_PRECOMPILE_HEADERS)
      add_compile_options("SHELL:-Xclang -fno-pch-timestamp")
    endif()
    message(STATUS "ccache: ${SEMAP_CCACHE_PROGRAM}")
  endif()
endif()
