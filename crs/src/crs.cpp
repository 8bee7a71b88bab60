// A CRS as the user typed it, read through PROJ.

#include "geoanchor/crs/crs.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>
#include <proj_experimental.h>

#include "crs_impl.hpp"
#include "frame_datum_names.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {

using detail::Pj;
using detail::text_or;

namespace {

constexpr std::size_t kEchoChars = 80;  // of a text quoted back in an error

std::string echo(std::string_view text) {
  std::string t(text.substr(0, kEchoChars));
  for (char& c : t) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  return "'" + t + (text.size() > kEchoChars ? "…'" : "'");
}

[[noreturn]] void fail(std::string_view where, std::string_view text, const std::string& problem,
                       const char* code = "E_CRS") {
  throw Error(ErrorKind::input, code, std::string(where) + ": CRS " + echo(text) + ": " + problem);
}

std::string trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return std::string(s);
}

std::string type_name(PJ_TYPE t) {
  switch (t) {
    case PJ_TYPE_GEOGRAPHIC_2D_CRS: return "geographic 2D";
    case PJ_TYPE_GEOGRAPHIC_3D_CRS: return "geographic 3D";
    case PJ_TYPE_GEOCENTRIC_CRS: return "geocentric";
    case PJ_TYPE_PROJECTED_CRS: return "projected";
    case PJ_TYPE_COMPOUND_CRS: return "compound";
    case PJ_TYPE_VERTICAL_CRS: return "vertical";
    case PJ_TYPE_ENGINEERING_CRS: return "engineering";
    case PJ_TYPE_BOUND_CRS: return "bound";
    case PJ_TYPE_TEMPORAL_CRS: return "temporal";
    case PJ_TYPE_GEODETIC_CRS: return "geodetic";
    default: return "not a CRS";
  }
}

std::string last_error(PJ_CONTEXT* ctx) {
  const int e = proj_context_errno(ctx);
  return e ? text_or(proj_context_errno_string(ctx, e)) : std::string();
}

// The realizations a frame name leaves open, from the catalog: "ETRS89" is
// ETRF89 … ETRF2020; "WGS84" is G730 … G2296; "NAD83(CSRS)" is CSRSv6 ….
std::vector<std::string> catalog_realizations_of(const std::string& name) {
  std::string prefix;
  if (name == "WGS84") prefix = "WGS84(";
  if (name == "ETRS89") prefix = "ETRF";
  if (name == "NAD83(CSRS)") prefix = "NAD83(CSRSv";
  std::vector<std::string> out;
  if (prefix.empty()) return out;
  for (const auto& f : geodesy::catalog_frame_names()) {
    if (f.compare(0, prefix.size(), prefix) == 0) out.push_back(f);
  }
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// A CRS PROJ can build from the text: EPSG:n (and h+v), WKT, PROJJSON, a
// PROJ string (with +type=crs), a URN. Null when PROJ cannot.
Pj create_from_text(PJ_CONTEXT* ctx, const std::string& text, std::string& problem) {
  const bool wkt = text.find('[') != std::string::npos && std::isalpha(static_cast<unsigned char>(text[0]));
  if (wkt) {
    const char* options[] = {"STRICT=NO", nullptr};
    PROJ_STRING_LIST warnings = nullptr;
    PROJ_STRING_LIST errors = nullptr;
    Pj crs(proj_create_from_wkt(ctx, text.c_str(), options, &warnings, &errors));
    problem = errors && errors[0] ? errors[0] : "";
    proj_string_list_destroy(warnings);
    proj_string_list_destroy(errors);
    if (!crs && problem.empty()) problem = "PROJ cannot parse this WKT";
    return crs;
  }
  Pj crs(proj_create(ctx, text.c_str()));
  if (!crs) problem = last_error(ctx);
  return crs;
}

// The geographic 3D CRS of a catalog frame in PROJ's database, found by
// the frame's EPSG datum name.
Pj create_from_frame(PJ_CONTEXT* ctx, const geodesy::Frame& frame, std::string_view where, std::string_view text) {
  const std::string datum = detail::epsg_datum_name(frame);
  const PJ_TYPE types[] = {PJ_TYPE_GEODETIC_REFERENCE_FRAME, PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME,
                           PJ_TYPE_DATUM_ENSEMBLE};
  PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", datum.c_str(), types, 3, 0, 1, nullptr);
  Pj datum_obj(found && proj_list_get_count(found) > 0 ? proj_list_get(ctx, found, 0) : nullptr);
  proj_list_destroy(found);
  if (!datum_obj) {
    fail(where, text,
         "frame " + frame.name() + " has no datum in PROJ's database (looked for '" + datum +
             "'); give the CRS as EPSG:n, WKT or PROJJSON");
  }
  const char* code = proj_get_id_code(datum_obj.get(), 0);
  PJ_OBJ_LIST* crss = proj_query_geodetic_crs_from_datum(ctx, "EPSG", "EPSG", code, "geographic 3D");
  Pj crs(crss && proj_list_get_count(crss) > 0 ? proj_list_get(ctx, crss, 0) : nullptr);
  proj_list_destroy(crss);
  if (!crs) fail(where, text, "frame " + frame.name() + ": PROJ's database has no geographic 3D CRS on datum EPSG:" + text_or(code));
  return crs;
}


CrsAxis read_axis(PJ_CONTEXT* ctx, PJ* cs, int i) {
  const char* name = nullptr;
  const char* abbrev = nullptr;
  const char* direction = nullptr;
  const char* unit = nullptr;
  double factor = 0.0;
  CrsAxis a;
  if (proj_cs_get_axis_info(ctx, cs, i, &name, &abbrev, &direction, &factor, &unit, nullptr, nullptr)) {
    a.name = text_or(name);
    a.abbreviation = text_or(abbrev);
    a.direction = text_or(direction);
    a.unit_name = text_or(unit);
    a.unit_to_si = factor;
  }
  const int type = proj_cs_get_type(ctx, cs);
  a.unit_type = type == PJ_CS_TYPE_ELLIPSOIDAL && i < 2 ? "angular" : "linear";
  return a;
}

// The meridians a coordinate system's axes point along (polar
// projections), which PROJ's C API leaves out and its PROJJSON states.
std::vector<std::optional<double>> read_meridians(PJ_CONTEXT* ctx, PJ* cs, int n) {
  std::vector<std::optional<double>> out(static_cast<std::size_t>(n));
  const char* text = proj_as_projjson(ctx, cs, nullptr);
  const auto j = nlohmann::json::parse(text_or(text, "{}"), nullptr, false);
  if (j.is_discarded() || !j.contains("axis") || !j["axis"].is_array()) return out;
  for (int i = 0; i < n && static_cast<std::size_t>(i) < j["axis"].size(); ++i) {
    const auto& axis = j["axis"][static_cast<std::size_t>(i)];
    if (!axis.is_object() || !axis.contains("meridian")) continue;
    const auto& lon = axis["meridian"].value("longitude", nlohmann::json());
    if (lon.is_number()) {
      out[static_cast<std::size_t>(i)] = lon.get<double>();  // degrees, PROJJSON's default unit
    } else if (lon.is_object() && lon.contains("value") && lon["value"].is_number()) {
      // {"value": V, "unit": U}: U a unit name ("degree") or {"conversion_factor": radians per unit}
      double factor = detail::kRadiansPerDegree;
      if (lon.contains("unit") && lon["unit"].is_object() && lon["unit"].contains("conversion_factor")) {
        factor = lon["unit"]["conversion_factor"].get<double>();
      } else if (lon.contains("unit") && lon["unit"].is_string() && lon["unit"] == "grad") {
        factor = detail::kRadiansPerGrad;
      } else if (lon.contains("unit") && lon["unit"].is_string() && lon["unit"] == "radian") {
        factor = 1.0;
      }
      out[static_cast<std::size_t>(i)] = lon["value"].get<double>() * factor / detail::kRadiansPerDegree;
    }
  }
  return out;
}

void read_axes(PJ_CONTEXT* ctx, PJ* crs, std::vector<CrsAxis>& out) {
  Pj cs(proj_crs_get_coordinate_system(ctx, crs));
  if (!cs) return;
  const int n = proj_cs_get_axis_count(ctx, cs.get());
  const std::size_t first = out.size();
  bool along_meridian = false;
  for (int i = 0; i < n; ++i) {
    out.push_back(read_axis(ctx, cs.get(), i));
    along_meridian = along_meridian || out.back().direction == "north" || out.back().direction == "south";
  }
  if (!along_meridian || proj_cs_get_type(ctx, cs.get()) != PJ_CS_TYPE_CARTESIAN) return;
  const auto meridians = read_meridians(ctx, cs.get(), n);
  for (std::size_t i = 0; i < meridians.size(); ++i) out[first + i].meridian_deg = meridians[i];
}

// An ensemble's name, members and accuracy.
void read_ensemble(PJ_CONTEXT* ctx, PJ* ensemble, CrsDescription& d) {
  d.datum = text_or(proj_get_name(ensemble));
  d.ensemble = true;
  const int n = proj_datum_ensemble_get_member_count(ctx, ensemble);
  for (int i = 0; i < n; ++i) {
    Pj member(proj_datum_ensemble_get_member(ctx, ensemble, i));
    if (member) d.ensemble_members.push_back(text_or(proj_get_name(member.get())));
  }
  const double accuracy = proj_datum_ensemble_get_accuracy(ctx, ensemble);
  if (accuracy > 0.0) d.ensemble_accuracy_m = accuracy;
}

// The datum (or ensemble) of a geodetic CRS, and what the catalog calls it.
void read_datum(PJ_CONTEXT* ctx, PJ* geodetic, CrsDescription& d) {
  Pj datum(proj_crs_get_datum(ctx, geodetic));
  if (datum) {
    d.datum = text_or(proj_get_name(datum.get()));
    if (proj_get_type(datum.get()) == PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME) {
      d.dynamic = true;
      d.frame_reference_epoch = proj_dynamic_datum_get_frame_reference_epoch(ctx, datum.get());
    }
  } else if (Pj ensemble(proj_crs_get_datum_ensemble(ctx, geodetic)); ensemble) {
    read_ensemble(ctx, ensemble.get(), d);
  }
  // A PROJ string's +datum=WGS84 (or a WKT1 datum) names the datum without
  // its ensemble: it is the ensemble all the same.
  if (!d.ensemble && (d.datum == "World Geodetic System 1984" || d.datum == "European Terrestrial Reference System 1989")) {
    const std::string name = d.datum + " ensemble";
    const PJ_TYPE types[] = {PJ_TYPE_DATUM_ENSEMBLE};
    PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", name.c_str(), types, 1, 0, 1, nullptr);
    Pj ensemble(found && proj_list_get_count(found) > 0 ? proj_list_get(ctx, found, 0) : nullptr);
    proj_list_destroy(found);
    if (ensemble) read_ensemble(ctx, ensemble.get(), d);
  }
  const std::string frame = detail::frame_name_of_epsg_datum(d.datum);
  const auto catalog = geodesy::catalog_frame_names();
  if (std::find(catalog.begin(), catalog.end(), frame) != catalog.end()) d.catalog_frame = frame;
  Pj ell(proj_get_ellipsoid(ctx, geodetic));
  double a = 0.0, b = 0.0, rf = 0.0;
  int computed = 0;
  if (ell && proj_ellipsoid_get_parameters(ctx, ell.get(), &a, &b, &computed, &rf)) {
    d.ellipsoid = CrsEllipsoid{text_or(proj_get_name(ell.get())), a, rf};
  }
  Pj pm(proj_get_prime_meridian(ctx, geodetic));
  double longitude = 0.0, factor = 0.0;
  const char* unit = nullptr;
  if (pm && proj_prime_meridian_get_parameters(ctx, pm.get(), &longitude, &factor, &unit)) {
    d.prime_meridian = text_or(proj_get_name(pm.get()));
    d.prime_meridian_deg = factor > 0.0 ? longitude * factor / detail::kRadiansPerDegree : longitude;
  }
}

void read_projection(PJ_CONTEXT* ctx, PJ* projected, CrsDescription& d) {
  Pj op(proj_crs_get_coordoperation(ctx, projected));
  if (!op) return;
  const char* method = nullptr;
  const char* auth = nullptr;
  const char* code = nullptr;
  if (proj_coordoperation_get_method_info(ctx, op.get(), &method, &auth, &code)) {
    d.projection_method = text_or(method);
    d.projection_method_code = auth && code ? std::string(auth) + ":" + code : "";
  }
  const int n = proj_coordoperation_get_param_count(ctx, op.get());
  for (int i = 0; i < n; ++i) {
    const char* name = nullptr;
    const char* pauth = nullptr;
    const char* pcode = nullptr;
    const char* unit = nullptr;
    double value = 0.0;
    if (!proj_coordoperation_get_param(ctx, op.get(), i, &name, &pauth, &pcode, &value, nullptr, nullptr, &unit,
                                       nullptr, nullptr, nullptr)) {
      continue;
    }
    d.projection_parameters.push_back(CrsParameter{text_or(name),
                                                   pauth && pcode && std::string(pauth) == "EPSG" ? pcode : "", value,
                                                   text_or(unit)});
  }
}

// The transformation of PROJ's database that applies the geoid grid
// `d.geoid_model`, which names the geoid model: the operation itself when it
// has a code, else the one among the steps its name lists ("ETRS89 to NAP
// height (2) + Inverse of Amersfoort to ETRS89 (9) + RD New"; PROJ builds
// such operations without codes, nor steps the C API can list) that uses
// the grid.
void name_geoid_model(PJ_CONTEXT* ctx, PJ* op, CrsDescription& d) {
  // "EPSG:10084"; PROJ names the authority of an object it derived from a
  // database one "DERIVED_FROM(EPSG)".
  auto code_of = [](const PJ* o) {
    const char* auth = proj_get_id_auth_name(o, 0);
    const char* code = proj_get_id_code(o, 0);
    if (!auth || !code) return std::string();
    std::string a(auth);
    constexpr std::string_view kDerived = "DERIVED_FROM(";
    if (a.rfind(kDerived, 0) == 0 && a.back() == ')') a = a.substr(kDerived.size(), a.size() - kDerived.size() - 1);
    return a + ":" + code;
  };
  if (const std::string id = code_of(op); !id.empty()) {
    d.geoid_operation = text_or(proj_get_name(op));
    d.geoid_operation_id = id;
    return;
  }
  const std::string name = text_or(proj_get_name(op));
  constexpr std::string_view kJoin = " + ", kInverse = "Inverse of ";
  for (std::size_t start = 0; start <= name.size();) {
    const std::size_t end = std::min(name.find(kJoin, start), name.size());
    std::string step = name.substr(start, end - start);
    start = end + kJoin.size();
    if (step.rfind(kInverse, 0) == 0) step.erase(0, kInverse.size());
    const PJ_TYPE types[] = {PJ_TYPE_TRANSFORMATION, PJ_TYPE_OTHER_COORDINATE_OPERATION};
    PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", step.c_str(), types, 2, 0, 2, nullptr);
    Pj match(found && proj_list_get_count(found) == 1 ? proj_list_get(ctx, found, 0) : nullptr);
    proj_list_destroy(found);
    if (!match || text_or(proj_get_name(match.get())) != step) continue;
    const int grids = proj_coordoperation_get_grid_used_count(ctx, match.get());
    for (int g = 0; g < grids; ++g) {
      const char* short_name = nullptr;
      if (proj_coordoperation_get_grid_used(ctx, match.get(), g, &short_name, nullptr, nullptr, nullptr, nullptr, nullptr,
                                            nullptr) &&
          short_name && d.geoid_model == short_name) {
        d.geoid_operation = step;
        d.geoid_operation_id = code_of(match.get());
        return;
      }
    }
  }
}

// The geoid of a compound CRS: the grid of PROJ's best operation from the
// horizontal part's ellipsoidal heights (its geographic 3D CRS) to it.
void read_geoid(PJ_CONTEXT* ctx, PJ* horizontal, PJ* compound, CrsDescription& d) {
  Pj geodetic(proj_crs_get_geodetic_crs(ctx, horizontal));
  Pj geographic3d(geodetic ? proj_crs_promote_to_3D(ctx, nullptr, geodetic.get()) : nullptr);
  if (!geographic3d) return;
  PJ_OPERATION_FACTORY_CONTEXT* fc = proj_create_operation_factory_context(ctx, nullptr);
  proj_operation_factory_context_set_allow_ballpark_transformations(ctx, fc, 0);
  proj_operation_factory_context_set_grid_availability_use(ctx, fc, PROJ_GRID_AVAILABILITY_IGNORED);
  proj_operation_factory_context_set_spatial_criterion(ctx, fc, PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  PJ_OBJ_LIST* ops = proj_create_operations(ctx, geographic3d.get(), compound, fc);
  proj_operation_factory_context_destroy(fc);
  const int n = ops ? proj_list_get_count(ops) : 0;
  // The geoid model is named only where every operation with a grid names
  // the same one (NAVD88 heights are GEOID18 in CONUS and GEOID12B in
  // Alaska: no one name holds for every point, so none is written).
  bool one_model = true;
  std::string model, model_id;
  for (int i = 0; i < n; ++i) {
    Pj op(proj_list_get(ctx, ops, i));
    if (!op || proj_coordoperation_has_ballpark_transformation(ctx, op.get())) continue;
    const int grids = proj_coordoperation_get_grid_used_count(ctx, op.get());
    std::string grid;
    int available = 0;
    for (int g = 0; g < grids && grid.empty(); ++g) {
      const char* short_name = nullptr;
      if (proj_coordoperation_get_grid_used(ctx, op.get(), g, &short_name, nullptr, nullptr, nullptr, nullptr, nullptr,
                                            &available) &&
          short_name) {
        grid = short_name;
      }
    }
    if (grid.empty()) continue;
    if (d.geoid_model.empty()) {  // PROJ's best-ranked operation's grid
      d.geoid_model = grid;
      d.geoid_available = available != 0;
    }
    CrsDescription named;
    named.geoid_model = grid;
    name_geoid_model(ctx, op.get(), named);
    if (named.geoid_operation.empty() || (!model.empty() && (named.geoid_operation != model || named.geoid_operation_id != model_id))) {
      one_model = false;
      break;
    }
    model = named.geoid_operation;
    model_id = named.geoid_operation_id;
  }
  if (one_model && !model.empty()) {
    d.geoid_operation = model;
    d.geoid_operation_id = model_id;
  }
  proj_list_destroy(ops);
}

CrsDescription describe(PJ_CONTEXT* ctx, PJ* crs) {
  CrsDescription d;
  d.name = text_or(proj_get_name(crs));
  const char* auth = proj_get_id_auth_name(crs, 0);
  const char* code = proj_get_id_code(crs, 0);
  if (auth && code) {
    d.identifier = std::string(auth) + ":" + code;
  } else if (proj_get_type(crs) != PJ_TYPE_COMPOUND_CRS) {
    // A WKT or PROJ string without an ID: the EPSG CRS PROJ holds it to be,
    // when it is sure (confidence 100).
    int* confidence = nullptr;
    PJ_OBJ_LIST* matches = proj_identify(ctx, crs, "EPSG", nullptr, &confidence);
    if (matches && proj_list_get_count(matches) >= 1 && confidence && confidence[0] == 100) {
      Pj match(proj_list_get(ctx, matches, 0));
      const char* ma = match ? proj_get_id_auth_name(match.get(), 0) : nullptr;
      const char* mc = match ? proj_get_id_code(match.get(), 0) : nullptr;
      if (ma && mc) d.identifier = std::string(ma) + ":" + mc;
    }
    proj_int_list_destroy(confidence);
    proj_list_destroy(matches);
  }
  const PJ_TYPE type = proj_get_type(crs);
  d.type = type_name(type);
  Pj horizontal_owner, vertical_owner;
  PJ* horizontal = crs;
  PJ* vertical = nullptr;
  if (type == PJ_TYPE_COMPOUND_CRS) {
    horizontal_owner.reset(proj_crs_get_sub_crs(ctx, crs, 0));
    vertical_owner.reset(proj_crs_get_sub_crs(ctx, crs, 1));
    horizontal = horizontal_owner.get();
    vertical = vertical_owner.get();
  } else if (type == PJ_TYPE_VERTICAL_CRS) {
    vertical = crs;
    horizontal = nullptr;
  }
  if (horizontal) {
    d.horizontal_type = type_name(proj_get_type(horizontal));
    Pj geodetic(proj_crs_get_geodetic_crs(ctx, horizontal));
    if (geodetic) read_datum(ctx, geodetic.get(), d);
    read_axes(ctx, horizontal, d.axes);
    if (proj_get_type(horizontal) == PJ_TYPE_PROJECTED_CRS) read_projection(ctx, horizontal, d);
  }
  if (vertical) {
    d.vertical_crs = text_or(proj_get_name(vertical));
    Pj vdatum(proj_crs_get_datum(ctx, vertical));
    if (vdatum) d.vertical_datum = text_or(proj_get_name(vdatum.get()));
    read_axes(ctx, vertical, d.axes);
    if (horizontal) read_geoid(ctx, horizontal, crs, d);
  }
  if (Pj normalized(proj_normalize_for_visualization(ctx, crs)); normalized) {
    const PJ_TYPE ntype = proj_get_type(normalized.get());
    if (ntype == PJ_TYPE_COMPOUND_CRS) {
      Pj h(proj_crs_get_sub_crs(ctx, normalized.get(), 0));
      Pj v(proj_crs_get_sub_crs(ctx, normalized.get(), 1));
      if (h) read_axes(ctx, h.get(), d.visualization_axes);
      if (v) read_axes(ctx, v.get(), d.visualization_axes);
    } else {
      read_axes(ctx, normalized.get(), d.visualization_axes);
    }
  }
  double west = 0.0, south = 0.0, east = 0.0, north = 0.0;
  const char* area_name = nullptr;
  if (proj_get_area_of_use(ctx, crs, &west, &south, &east, &north, &area_name) && west > -1000.0) {
    d.area = CrsArea{text_or(area_name), west, south, east, north};
  } else if (horizontal && horizontal != crs &&
             proj_get_area_of_use(ctx, horizontal, &west, &south, &east, &north, &area_name) && west > -1000.0) {
    d.area = CrsArea{text_or(area_name), west, south, east, north};  // a compound CRS built from EPSG:h+v
  }
  if (d.identifier.empty() && horizontal && vertical && horizontal != crs) {
    // EPSG:h+v: PROJ gives the compound no code of its own.
    const char* ha = proj_get_id_auth_name(horizontal, 0);
    const char* hc = proj_get_id_code(horizontal, 0);
    const char* va = proj_get_id_auth_name(vertical, 0);
    const char* vc = proj_get_id_code(vertical, 0);
    if (ha && hc && va && vc && std::string(ha) == va) d.identifier = std::string(ha) + ":" + hc + "+" + vc;
  }
  return d;
}

}  // namespace

bool CrsArea::contains(double lon_deg, double lat_deg) const {
  if (!(lat_deg >= south_deg && lat_deg <= north_deg)) return false;
  if (west_deg <= east_deg) return lon_deg >= west_deg && lon_deg <= east_deg;
  return lon_deg >= west_deg || lon_deg <= east_deg;  // across the antimeridian
}

Crs::Crs(std::shared_ptr<Impl> impl, std::optional<geodesy::DecimalYear> epoch, std::string text)
    : impl_(std::move(impl)), epoch_(epoch), text_(std::move(text)) {}

Crs Crs::parse(std::string_view typed, std::string_view where) {
  std::string text = trim(typed);
  if (text.empty()) fail(where, typed, "empty; expected EPSG:n, EPSG:h+v, WKT, PROJJSON, a PROJ string, @FILE or a frame name");
  std::string definition = text;
  std::optional<geodesy::DecimalYear> epoch;
  // CRS@EPOCH. WKT and PROJJSON end at their closing bracket: what follows
  // is nothing or @EPOCH (an '@' inside a quoted name or remark is the
  // text's own). Otherwise the last '@' (a file is @FILE, at 0) begins the
  // epoch, unless what follows it is a PROJ string's ("+nadgrids=@null").
  const bool wkt_or_json = definition.find_first_of("[{") != std::string::npos && definition[0] != '@';
  if (wkt_or_json) {
    const auto close = definition.find_last_of("]}");
    const std::string tail = close == std::string::npos ? std::string() : trim(std::string_view(definition).substr(close + 1));
    if (!tail.empty()) {
      if (tail[0] != '@') {
        fail(where, text, "text after the CRS's closing bracket (" + echo(tail) + "); expected nothing or @EPOCH, e.g. @2024.5");
      }
      const std::string year = trim(std::string_view(tail).substr(1));
      if (year.empty()) fail(where, text, "nothing after '@'; expected the coordinate epoch as a decimal year, e.g. CRS@2024.5", "E_EPOCH");
      epoch = geodesy::parse_decimal_year(year, std::string(where) + ": coordinate epoch of CRS " + echo(text));
      definition = trim(std::string_view(definition).substr(0, close + 1));
    }
  } else if (const auto at = definition.rfind('@'); at != std::string::npos && at > 0) {
    const std::string tail = trim(std::string_view(definition).substr(at + 1));
    if (tail.empty()) fail(where, text, "nothing after '@'; expected the coordinate epoch as a decimal year, e.g. CRS@2024.5", "E_EPOCH");
    if (tail.find_first_of(" +=:") == std::string::npos) {
      epoch = geodesy::parse_decimal_year(tail, std::string(where) + ": coordinate epoch of CRS " + echo(text));
      definition = trim(std::string_view(definition).substr(0, at));
    }
  }
  if (!definition.empty() && definition[0] == '@') {
    const std::string path = definition.substr(1);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorKind::io, "E_CRS", std::string(where) + ": CRS file " + path + ": cannot be read");
    std::ostringstream content;
    content << in.rdbuf();
    definition = content.str();
    if (definition.rfind("\xEF\xBB\xBF", 0) == 0) definition.erase(0, 3);  // a UTF-8 byte-order mark
    definition = trim(definition);
    if (definition.empty()) fail(where, text, "the file " + path + " is empty; expected a CRS definition in it");
    if (definition[0] == '@') fail(where, text, "the file " + path + " names another file; give the CRS itself");
    if (definition.find_first_of("[{") != std::string::npos) {
      const auto close = definition.find_last_of("]}");
      if (close != std::string::npos && close + 1 < definition.size()) {
        fail(where, text, "the file " + path + " has text after the CRS's closing bracket (" +
                              echo(trim(std::string_view(definition).substr(close + 1))) +
                              "); give the epoch as @FILE@EPOCH");
      }
    }
  }

  auto impl = std::make_shared<Impl>();
  impl->ctx = detail::quiet_context();
  PJ_CONTEXT* ctx = impl->ctx.get();
  bool from_frame_name = false;
  const bool looks_like_proj_text = definition.find(':') != std::string::npos || definition[0] == '{' ||
                                    definition.find('[') != std::string::npos || definition.find('=') != std::string::npos;
  if (looks_like_proj_text) {
    std::string problem;
    impl->crs = create_from_text(ctx, definition, problem);
    const auto colon = definition.find(':');
    const bool code_form = colon != std::string::npos && colon > 0 &&
                           definition.find_first_of("[{= ") == std::string::npos &&
                           std::all_of(definition.begin(), definition.begin() + static_cast<std::ptrdiff_t>(colon),
                                       [](unsigned char ch) { return std::isalpha(ch) != 0; });
    if (!impl->crs && code_form) {
      fail(where, text, "PROJ's database (" + text_or(proj_context_get_database_path(ctx)) + ") has no CRS " + definition +
                            "; expected a code of a CRS, e.g. EPSG:4326, EPSG:7856+5711");
    }
    if (!impl->crs) {
      fail(where, text, "PROJ cannot read it" + (problem.empty() ? std::string() : " (" + problem + ")") +
                            "; expected EPSG:n, EPSG:h+v, WKT, PROJJSON, a PROJ string with +type=crs, @FILE or a "
                            "frame name");
    }
    if (!proj_is_crs(impl->crs.get())) {
      fail(where, text, "PROJ reads it as a coordinate operation, not a CRS" +
                            std::string(definition.find("+proj") != std::string::npos ? " (a PROJ string needs +type=crs)" : ""));
    }
  } else {
    const geodesy::Frame frame = geodesy::Frame::parse(definition, where);
    const auto realizations = catalog_realizations_of(frame.name());
    if (!realizations.empty()) {
      fail(where, text,
           frame.name() + " names " + (frame.name() == "NAD83(CSRS)" ? "a datum with several realizations" : "an ensemble") +
               ", not one realization; give one of " + joined(realizations) +
               (frame.name() == "NAD83(CSRS)" ? "" : ", or its EPSG code where the realization cannot matter"),
           "E_CRS_ENSEMBLE");
    }
    impl->crs = create_from_frame(ctx, frame, where, text);
    from_frame_name = true;
  }
  impl->description = describe(ctx, impl->crs.get());
  const CrsDescription& d = impl->description;
  if (d.type == "bound") {
    fail(where, text, "a bound CRS (WKT1 TOWGS84 or +towgs84): PROJ would apply its built-in datum shift; give the CRS "
                      "without it");
  }
  if (d.type != "geographic 2D" && d.type != "geographic 3D" && d.type != "geocentric" && d.type != "projected" &&
      d.type != "compound") {
    fail(where, text, "'" + d.name + "' is " + (d.type[0] == 'e' ? "an " : "a ") + d.type +
                          " CRS; expected a geographic, geocentric, projected or compound (horizontal + vertical) CRS");
  }
  if (d.type == "compound" && d.horizontal_type != "geographic 2D" && d.horizontal_type != "projected") {
    fail(where, text, "'" + d.name + "': the horizontal part is a " + d.horizontal_type +
                          " CRS; expected a geographic 2D or projected CRS");
  }
  // An epoch on a static CRS is kept: a time-dependent operation between
  // two static frames (ETRF2000 -> ETRF2014) is evaluated at it; where
  // nothing uses it, CrsOperation refuses it.
  Crs out(std::move(impl), epoch, text);
  out.from_frame_name_ = from_frame_name;
  return out;
}

const CrsDescription& Crs::description() const { return impl_->description; }

std::string Crs::display_name() const {
  const auto& d = impl_->description;
  std::string s = !d.identifier.empty() ? d.identifier + " (" + d.name + ")"
                  : d.name == "unknown" || d.name.empty() ? echo(text_.substr(0, text_.rfind('@') == std::string::npos || !epoch_ ? std::string::npos : text_.rfind('@')))
                                                          : "'" + d.name + "'";
  if (epoch_) s += "@" + geodesy::format_decimal_year(*epoch_);
  return s;
}

namespace {

// The compound CRS with GEOIDMODEL on its vertical part (built through its
// PROJJSON, read back by PROJ and held equivalent to the CRS), or null when
// it names a geoid model already, PROJ knows none, or PROJ refuses it.
Pj with_geoid_model(PJ_CONTEXT* ctx, PJ* crs, const CrsDescription& d) {
  if (d.type != "compound" || d.geoid_operation.empty()) return nullptr;
  auto j = nlohmann::json::parse(text_or(proj_as_projjson(ctx, crs, nullptr), "{}"), nullptr, false);
  if (j.is_discarded() || !j.contains("components") || !j["components"].is_array() || j["components"].size() != 2) {
    return nullptr;
  }
  auto& vertical = j["components"][1];
  if (!vertical.is_object() || vertical.contains("geoid_model") || vertical.contains("geoid_models")) return nullptr;
  nlohmann::json model = {{"name", d.geoid_operation}};
  if (const auto colon = d.geoid_operation_id.find(':'); colon != std::string::npos) {
    const std::string code = d.geoid_operation_id.substr(colon + 1);
    const bool digits = !code.empty() && std::all_of(code.begin(), code.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
    model["id"] = {{"authority", d.geoid_operation_id.substr(0, colon)},
                   {"code", digits ? nlohmann::json(std::stol(code)) : nlohmann::json(code)}};
  }
  vertical["geoid_model"] = model;
  Pj out(proj_create(ctx, j.dump().c_str()));
  if (!out || !proj_is_equivalent_to_with_ctx(ctx, out.get(), crs, PJ_COMP_EQUIVALENT)) return nullptr;
  return out;
}

}  // namespace

std::string Crs::wkt2() const {
  const char* options[] = {"MULTILINE=NO", nullptr};
  PJ_CONTEXT* ctx = impl_->ctx.get();
  const Pj geoid = with_geoid_model(ctx, impl_->crs.get(), impl_->description);
  const char* w = proj_as_wkt(ctx, geoid ? geoid.get() : impl_->crs.get(), PJ_WKT2_2019, options);
  return text_or(w);
}

std::string Crs::projjson() const {
  const char* options[] = {"MULTILINE=NO", nullptr};
  const char* j = proj_as_projjson(impl_->ctx.get(), impl_->crs.get(), options);
  return text_or(j);
}

Crs Crs::at_epoch(geodesy::DecimalYear epoch, std::string_view where) const {
  if (!impl_->description.dynamic) {
    fail(where, text_, "'" + impl_->description.name + "' is on a static datum: its coordinates have no epoch",
         "E_CRS_EPOCH");
  }
  Crs out = *this;
  out.epoch_ = epoch;
  return out;
}

Crs Crs::without_epoch() const {
  Crs out = *this;
  out.epoch_.reset();
  return out;
}

bool Crs::same_as(const Crs& other) const {
  if (epoch_.has_value() != other.epoch_.has_value() || (epoch_ && epoch_->year != other.epoch_->year)) return false;
  return proj_is_equivalent_to_with_ctx(impl_->ctx.get(), impl_->crs.get(), other.impl_->crs.get(), PJ_COMP_EQUIVALENT) != 0;
}

Crs Crs::promoted_to_3d(std::string_view where) const {
  const auto& d = impl_->description;
  if (d.axes.size() >= 3) return *this;
  auto impl = std::make_shared<Impl>();
  impl->ctx = detail::quiet_context();
  // A PJ belongs to its context: rebuild it there from its PROJJSON.
  Pj same(proj_create(impl->ctx.get(), projjson().c_str()));
  Pj promoted(same ? proj_crs_promote_to_3D(impl->ctx.get(), nullptr, same.get()) : nullptr);
  if (!promoted) fail(where, text_, "'" + d.name + "' cannot be given an ellipsoidal height axis");
  impl->crs = std::move(promoted);
  impl->description = describe(impl->ctx.get(), impl->crs.get());
  Crs out(std::move(impl), epoch_, text_);
  out.from_frame_name_ = from_frame_name_;
  return out;
}

Crs Crs::horizontal(std::string_view where) const {
  const auto& d = impl_->description;
  const bool three_d = d.type == "geographic 3D" || (d.type == "projected" && d.axes.size() >= 3);
  if (d.type != "compound" && !three_d) return *this;
  auto impl = std::make_shared<Impl>();
  impl->ctx = detail::quiet_context();
  PJ_CONTEXT* ctx = impl->ctx.get();
  // A PJ belongs to its context: rebuild it there from its PROJJSON.
  Pj same(proj_create(ctx, projjson().c_str()));
  if (same && d.type == "compound") {
    impl->crs.reset(proj_crs_get_sub_crs(ctx, same.get(), 0));
  } else if (same) {
    impl->crs.reset(proj_crs_demote_to_2D(ctx, nullptr, same.get()));
  }
  if (!impl->crs) fail(where, text_, "'" + d.name + "': PROJ gives no horizontal part of it");
  impl->description = describe(ctx, impl->crs.get());
  Crs out(std::move(impl), epoch_, text_);
  out.from_frame_name_ = from_frame_name_;
  return out;
}

Crs Crs::geocentric(std::string_view where) const {
  const auto& d = impl_->description;
  if (d.type == "geocentric") return *this;
  auto impl = std::make_shared<Impl>();
  impl->ctx = detail::quiet_context();
  PJ_CONTEXT* ctx = impl->ctx.get();
  Pj same(proj_create(ctx, projjson().c_str()));
  Pj geodetic(same ? proj_crs_get_geodetic_crs(ctx, same.get()) : nullptr);
  // The database's geocentric CRS of the datum (found by the datum's name:
  // a CRS read from WKT or PROJJSON carries no code on its datum), else one
  // built on the datum itself.
  Pj datum(geodetic ? proj_crs_get_datum(ctx, geodetic.get()) : nullptr);
  if (!datum && geodetic) datum.reset(proj_crs_get_datum_ensemble(ctx, geodetic.get()));
  if (datum && d.prime_meridian_deg != 0.0) {
    // geoanchor's ECEF has its X axis through Greenwich; PROJ's geocentric
    // CRS of a datum on another meridian (NTF (Paris)) through that
    // meridian. The same datum with Greenwich as its prime meridian: PROJ
    // moves between the two by the change of meridian alone (a "ballpark"
    // it holds exact: the same name and ellipsoid; CrsOperation allows it).
    auto j = nlohmann::json::parse(text_or(proj_as_projjson(ctx, datum.get(), nullptr), "{}"), nullptr, false);
    if (!j.is_discarded() && j.is_object()) {
      j.erase("prime_meridian");
      j.erase("id");
      nlohmann::json cs = {{"subtype", "Cartesian"},
                           {"axis", nlohmann::json::array({{{"name", "Geocentric X"}, {"abbreviation", "X"}, {"direction", "geocentricX"}, {"unit", "metre"}},
                                                           {{"name", "Geocentric Y"}, {"abbreviation", "Y"}, {"direction", "geocentricY"}, {"unit", "metre"}},
                                                           {{"name", "Geocentric Z"}, {"abbreviation", "Z"}, {"direction", "geocentricZ"}, {"unit", "metre"}}})}};
      const nlohmann::json crs = {{"type", "GeodeticCRS"},
                                  {"name", d.datum + " (geocentric, X through Greenwich)"},
                                  {"datum", j},
                                  {"coordinate_system", cs}};
      impl->crs.reset(proj_create(ctx, crs.dump().c_str()));
    }
  } else if (datum) {
    const PJ_TYPE types[] = {PJ_TYPE_GEODETIC_REFERENCE_FRAME, PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME,
                             PJ_TYPE_DATUM_ENSEMBLE};
    const char* name = proj_get_name(datum.get());
    PJ_OBJ_LIST* found = name ? proj_create_from_name(ctx, "EPSG", name, types, 3, 0, 1, nullptr) : nullptr;
    Pj db_datum(found && proj_list_get_count(found) > 0 ? proj_list_get(ctx, found, 0) : nullptr);
    proj_list_destroy(found);
    const char* code = db_datum ? proj_get_id_code(db_datum.get(), 0) : nullptr;
    if (code && proj_is_equivalent_to(db_datum.get(), datum.get(), PJ_COMP_EQUIVALENT)) {
      PJ_OBJ_LIST* crss = proj_query_geodetic_crs_from_datum(ctx, "EPSG", "EPSG", code, "geocentric");
      impl->crs.reset(crss && proj_list_get_count(crss) > 0 ? proj_list_get(ctx, crss, 0) : nullptr);
      proj_list_destroy(crss);
    }
    if (!impl->crs) {
      const std::string crs_name = d.datum + " (geocentric)";
      impl->crs.reset(proj_create_geocentric_crs_from_datum(ctx, crs_name.c_str(), datum.get(), "metre", 1.0));
    }
  }
  if (!impl->crs) {
    fail(where, text_, "'" + d.name + "': PROJ's database has no geocentric CRS on its datum (" + d.datum +
                           "); give x_m, y_m, z_m in an EPSG geocentric CRS");
  }
  impl->description = describe(ctx, impl->crs.get());
  Crs out(std::move(impl), epoch_, text_);
  out.from_frame_name_ = from_frame_name_;
  return out;
}

geodesy::Ellipsoid typed_ellipsoid(const CrsEllipsoid& e) {
  constexpr double kEllipsoidMatch = 1e-9;  // relative, in a and 1/f
  const auto wgs84 = geodesy::Ellipsoid::wgs84(), grs80 = geodesy::Ellipsoid::grs80();
  auto same = [&](const geodesy::Ellipsoid& g) {
    return std::abs(e.a_m - g.a_m()) < kEllipsoidMatch * g.a_m() && std::abs(e.rf - g.rf()) < kEllipsoidMatch * g.rf();
  };
  return same(wgs84) ? wgs84 : same(grs80) ? grs80 : geodesy::Ellipsoid::custom(e.a_m, e.rf, e.name.empty() ? "custom" : e.name);
}

std::string proj_version_text() { return text_or(proj_info().version); }

std::string column_unit_suffix(const CrsAxis& axis, std::string_view crs_name) {
  constexpr double kFoot_m = 0.3048;
  constexpr double kUsFoot_m = 1200.0 / 3937.0;
  constexpr double kKilometre_m = 1000.0;
  if (axis.unit_type == "angular") {
    if (detail::same_unit_factor(axis.unit_to_si, detail::kRadiansPerDegree)) return "deg";
    if (detail::same_unit_factor(axis.unit_to_si, detail::kRadiansPerGrad)) return "grad";
  } else {
    if (detail::same_unit_factor(axis.unit_to_si, 1.0)) return "m";
    if (detail::same_unit_factor(axis.unit_to_si, kUsFoot_m)) return "ftus";
    if (detail::same_unit_factor(axis.unit_to_si, kFoot_m)) return "ft";
    if (detail::same_unit_factor(axis.unit_to_si, kKilometre_m)) return "km";
  }
  throw Error(ErrorKind::input, "E_CRS_UNIT",
              "CRS '" + std::string(crs_name) + "': axis '" + axis.name + "' is in " + axis.unit_name +
                  " (" + format_shortest(axis.unit_to_si) + (axis.unit_type == "angular" ? " rad" : " m") +
                  "), a unit geoanchor has no column name for; columns are named in m, ft, ftus, km, deg or grad");
}

std::optional<std::string> projjson_from_wkt(const std::string& wkt) {
  struct Ctx {
    PJ_CONTEXT* c = proj_context_create();
    ~Ctx() { proj_context_destroy(c); }
  } ctx;
  std::unique_ptr<PJ, decltype(&proj_destroy)> op(proj_create(ctx.c, wkt.c_str()), proj_destroy);
  if (!op) return std::nullopt;
  const char* json = proj_as_projjson(ctx.c, op.get(), nullptr);
  if (!json) return std::nullopt;
  return std::string(json);
}

}  // namespace geoanchor::io
