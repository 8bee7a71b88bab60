#pragma once
// One member of a JSON object read strictly (private to io): the readers of
// control sets and networks share it.

#include <cmath>
#include <string>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io::detail {

// obj[key] as a finite number; else Error(input, code) "WHERE.KEY: missing",
// "… value V is not a number" or "… not finite".
template <class Json>
double finite_json_number(const Json& obj, const std::string& key, const std::string& where, const char* code) {
  auto fail = [&](const std::string& what) { throw Error(ErrorKind::input, code, where + "." + key + ": " + what); };
  if (!obj.contains(key)) fail("missing");
  const Json& v = obj.at(key);
  if (!v.is_number()) fail("value " + v.dump() + " is not a number");
  const double d = v.template get<double>();
  if (!std::isfinite(d)) fail("not finite");
  return d;
}

}  // namespace geoanchor::io::detail
