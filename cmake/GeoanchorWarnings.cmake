# geoanchor_target_defaults(<target>): C++20 and the project's warning set.
# -ffast-math is used in one translation unit only (geodesy/src/geocentric_kernel.cpp,
# see geodesy/CMakeLists.txt): the rest of the geodesy depends on IEEE semantics.
function(geoanchor_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Wnull-dereference)
  # GCC 12 reports a false -Wrestrict inside libstdc++'s std::string
  # operator+ at -O2/-O3 (GCC bug 105329, fixed in GCC 13).
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(GEOANCHOR_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
