# Every dependency is a Debian 12 package installed by scripts/setup.sh.
# Nothing is downloaded at configure or build time.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(PROJ 9 REQUIRED CONFIG)
find_package(nlohmann_json 3.11 REQUIRED)
find_package(CLI11 2.1 REQUIRED)
find_package(PkgConfig REQUIRED)
# Debian ships GeographicLib with a pkg-config file but no CMake package config.
pkg_check_modules(GeographicLib REQUIRED IMPORTED_TARGET geographiclib>=2.1)
if(NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib ALIAS PkgConfig::GeographicLib)
endif()
find_package(OpenSSL 3 REQUIRED)
find_package(Threads REQUIRED)
