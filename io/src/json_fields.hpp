#pragma once
// One member of a JSON object read strictly, and the strict readers' check
// for keys they do not read (private to io): the readers of control sets,
// networks, transform files, sidecars, the map metadata contract and
// GeoJSON share them, each framing its own message.

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
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

// The first key of the object `obj`, in its order, that is not one of
// `known` (a set, a vector or an array of names), or nullopt when it has
// none: the "unknown key; expected …" check.
template <class Json, class Known>
std::optional<std::string> first_unknown_key(const Json& obj, const Known& known) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (std::find(std::begin(known), std::end(known), it.key()) == std::end(known)) return it.key();
  }
  return std::nullopt;
}

// The names of `known`, in its order, with ", " between them: the list
// after "expected".
template <class Known>
std::string key_list(const Known& known) {
  std::string list;
  for (const auto& k : known) list += (list.empty() ? "" : ", ") + std::string(k);
  return list;
}

}  // namespace geoanchor::io::detail
