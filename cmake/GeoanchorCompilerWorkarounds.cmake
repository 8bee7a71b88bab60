# Workarounds for compiler faults. Directory-wide (add_compile_options before
# any add_subdirectory), so that every target of the build gets them:
# libraries, executables, tests, benchmarks and fuzz targets, including one
# that forgets geoanchor_target_defaults.
#
# GCC < 13 (seen with Debian's GCC 12.2.0 at -O2 and -O3): the basic-block
# SLP vectorizer drops double → float → double round trips stored side by
# side. `{float(x[0]), float(x[1]), float(x[2])}` into doubles compiles to a
# 16-byte copy of x[0] and x[1] and one cvtsd2ss/cvtss2sd for x[2], so a
# float32 value is silently kept at double precision. -fno-tree-slp-vectorize
# turns that pass off; loop vectorization (-ftree-loop-vectorize) and the
# AVX2 clones stay. tests/geodesy/float32_test.cpp fails without it; the
# benchmarks before and after are in docs/architecture.md (Build).
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-fno-tree-slp-vectorize>)
endif()
