// libFuzzer target: the control set in JSON (read_control_json; fit and
// diagnose --control), with an ENU origin given so that e_m/n_m/u_m
// coordinates are read too.

#include <sstream>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/control/control_csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  io::ControlReadOptions o;
  o.origin = geodesy::LocalOrigin{{geodesy::Angle::degrees(47.464722), geodesy::Angle::degrees(8.549167),
                                   geodesy::EllipsoidalHeight{480.0}},
                                  geodesy::Ellipsoid::grs80()};
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    (void)io::read_control_json(in, "fuzz.json", o);
  } catch (const Error&) {
  }
  return 0;
}
