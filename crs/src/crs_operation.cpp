// Coordinates between two CRSs through PROJ, over whole arrays.

#include "geoanchor/crs/crs_operation.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <set>

#include <proj_experimental.h>

#include "crs_impl.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/hash.hpp"

namespace geoanchor::io {

using detail::Pj;
using detail::text_or;

namespace {

struct Candidate {
  CrsOperationCandidate info;
  Pj op;  // normalized for visualization; null when a grid is missing or PROJ cannot run it
  bool instantiable = false;
  std::string unusable;  // why PROJ cannot run it although its grids are here ("" when it can)
  // The areas of use of its datum-changing steps (not of its conversions,
  // which hold wherever their formulas do): a point it moves must lie in
  // each. Empty for a conversion.
  std::vector<CrsArea> datum_areas;
  bool holds(double lon, double lat) const {
    return std::all_of(datum_areas.begin(), datum_areas.end(), [&](const CrsArea& a) { return a.contains(lon, lat); });
  }
};

std::string joined(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::string accuracy_text(const std::optional<double>& a) {
  return a ? "±" + format_shortest(*a) + " m" : std::string("accuracy not stated");
}

// Whether an operation (or a step of a concatenated one) is evaluated at an
// epoch: EPSG's time-dependent Helmert methods and point-motion (velocity
// grid) methods.
bool is_time_dependent(PJ_CONTEXT* ctx, PJ* op) {
  const int steps = proj_concatoperation_get_step_count(ctx, op);
  if (steps > 0) {
    for (int i = 0; i < steps; ++i) {
      Pj step(proj_concatoperation_get_step(ctx, op, i));
      if (step && is_time_dependent(ctx, step.get())) return true;
    }
    return false;
  }
  const char* method = nullptr;
  if (!proj_coordoperation_get_method_info(ctx, op, &method, nullptr, nullptr) || !method) return false;
  std::string m(method);
  for (char& c : m) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return m.find("time-dependent") != std::string::npos || m.find("point motion") != std::string::npos ||
         m.find("velocity") != std::string::npos;
}

struct ListDeleter {
  void operator()(PJ_OBJ_LIST* l) const { proj_list_destroy(l); }
};
using PjList = std::unique_ptr<PJ_OBJ_LIST, ListDeleter>;

// The areas of use of an operation's datum-changing steps (see Candidate).
void datum_change_areas(PJ_CONTEXT* ctx, PJ* op, std::vector<CrsArea>& out) {
  const PJ_TYPE type = proj_get_type(op);
  if (type == PJ_TYPE_CONCATENATED_OPERATION) {
    const int steps = proj_concatoperation_get_step_count(ctx, op);
    for (int i = 0; i < steps; ++i) {
      Pj step(proj_concatoperation_get_step(ctx, op, i));
      if (step) datum_change_areas(ctx, step.get(), out);
    }
    return;
  }
  if (type == PJ_TYPE_CONVERSION) return;
  double west = 0, south = 0, east = 0, north = 0;
  const char* name = nullptr;
  if (proj_get_area_of_use(ctx, op, &west, &south, &east, &north, &name) && west > -1000.0) {
    out.push_back(CrsArea{text_or(name), west, south, east, north});
  }
}

// PROJ's candidate operations for the pair. With `grids` =
// PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID they are exactly
// those proj_create_crs_to_crs chooses among (network access off), and
// `keep` receives PROJ's list for proj_get_suggested_operation; with
// PROJ_GRID_AVAILABILITY_IGNORED they include the operations whose grids
// are not on the machine.
std::vector<Candidate> list_operations(PJ_CONTEXT* ctx, PJ* src, PJ* dst, bool allow_ballpark,
                                       PROJ_GRID_AVAILABILITY_USE grid_use, PjList* keep = nullptr) {
  PJ_OPERATION_FACTORY_CONTEXT* fc = proj_create_operation_factory_context(ctx, nullptr);
  proj_operation_factory_context_set_allow_ballpark_transformations(ctx, fc, allow_ballpark ? 1 : 0);
  proj_operation_factory_context_set_spatial_criterion(ctx, fc, PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  proj_operation_factory_context_set_grid_availability_use(ctx, fc, grid_use);
  PJ_OBJ_LIST* list = proj_create_operations(ctx, src, dst, fc);
  proj_operation_factory_context_destroy(fc);
  std::vector<Candidate> out;
  const int n = list ? proj_list_get_count(list) : 0;
  for (int i = 0; i < n; ++i) {
    Pj raw(proj_list_get(ctx, list, i));
    if (!raw) continue;
    if (!allow_ballpark && proj_coordoperation_has_ballpark_transformation(ctx, raw.get())) {
      if (keep) return {};  // a ballpark one in the list PROJ chooses from: not a list geoanchor uses
      continue;
    }
    Candidate c;
    c.info.name = text_or(proj_get_name(raw.get()));
    const char* auth = proj_get_id_auth_name(raw.get(), 0);
    const char* code = proj_get_id_code(raw.get(), 0);
    if (auth && code) c.info.identifier = std::string(auth) + ":" + code;
    const double accuracy = proj_coordoperation_get_accuracy(ctx, raw.get());
    if (accuracy >= 0.0) c.info.accuracy_m = accuracy;
    if (proj_get_type(raw.get()) == PJ_TYPE_CONVERSION) c.info.accuracy_m = 0.0;  // exact by definition
    const int grids = proj_coordoperation_get_grid_used_count(ctx, raw.get());
    for (int g = 0; g < grids; ++g) {
      const char* short_name = nullptr;
      const char* full_name = nullptr;
      int available = 0;
      if (!proj_coordoperation_get_grid_used(ctx, raw.get(), g, &short_name, &full_name, nullptr, nullptr, nullptr,
                                             nullptr, &available)) {
        continue;
      }
      CrsGridFile f;
      f.name = text_or(short_name);
      f.path = text_or(full_name);
      f.available = available != 0 && !f.path.empty();
      c.info.grids.push_back(std::move(f));
    }
    c.instantiable = proj_coordoperation_is_instantiable(ctx, raw.get()) != 0;
    const bool grids_here =
        std::all_of(c.info.grids.begin(), c.info.grids.end(), [](const CrsGridFile& g) { return g.available; });
    if (!c.instantiable && grids_here) {
      // Its grids are here, yet PROJ cannot run it (a method PROJ does not
      // implement): PROJ says why when asked for its pipeline.
      (void)detail::take_last_proj_error();
      (void)proj_as_proj_string(ctx, raw.get(), PJ_PROJ_5, nullptr);
      c.unusable = detail::take_last_proj_error();
      if (c.unusable.empty()) c.unusable = "PROJ cannot instantiate it";
    }
    c.instantiable = c.instantiable && grids_here;
    datum_change_areas(ctx, raw.get(), c.datum_areas);
    double west = 0, south = 0, east = 0, north = 0;
    const char* area = nullptr;
    if (proj_get_area_of_use(ctx, raw.get(), &west, &south, &east, &north, &area) && west > -1000.0) {
      c.info.area = CrsArea{text_or(area), west, south, east, north};
    }
    c.info.time_dependent = is_time_dependent(ctx, raw.get());
    if (const char* ps = proj_as_proj_string(ctx, raw.get(), PJ_PROJ_5, nullptr)) {
      const std::string text(ps);  // methods PROJ writes as PROJ strings: deformation models, epoch-dependent sets
      c.info.time_dependent = c.info.time_dependent || text.find("t_epoch") != std::string::npos ||
                              text.find("proj=deformation") != std::string::npos ||
                              text.find("proj=defmodel") != std::string::npos;
    }
    if (c.instantiable) {
      (void)detail::take_last_proj_error();
      c.op.reset(proj_normalize_for_visualization(ctx, raw.get()));
      if (!c.op) {
        c.instantiable = false;
        c.unusable = detail::take_last_proj_error();
        if (c.unusable.empty()) c.unusable = "PROJ cannot give it in longitude/easting-first order";
      }
    }
    if (c.op) {
      const char* proj_text = proj_as_proj_string(ctx, c.op.get(), PJ_PROJ_5, nullptr);
      c.info.proj_string = text_or(proj_text);
    }
    out.push_back(std::move(c));
  }
  if (keep) {
    keep->reset(list);
  } else {
    proj_list_destroy(list);
  }
  return out;
}

bool is_geographic_degrees(const CrsDescription& d) {
  if (d.horizontal_type != "geographic 2D" && d.horizontal_type != "geographic 3D") return false;
  if (d.prime_meridian_deg != 0.0 || d.axes.size() < 2) return false;
  return detail::same_unit_factor(d.axes[0].unit_to_si, detail::kRadiansPerDegree);
}

// Points outside an area of use: counted, the first kept.
struct AreaTally {
  std::string crs;
  std::optional<CrsArea> area;
  std::size_t outside = 0, seen = 0;
  std::string first;
  void check(double lon, double lat, const std::function<std::string()>& name) {
    ++seen;
    if (!area || area->contains(lon, lat)) return;
    if (outside++ == 0) first = name() + " (latitude " + format_shortest(lat) + "°, longitude " + format_shortest(lon) + "°)";
  }
  std::optional<std::string> warning() const {
    if (outside == 0) return std::nullopt;
    return std::to_string(outside) + " of " + std::to_string(seen) + " points lie outside the area of use of " + crs +
           " (" + area->name + ": longitude " + format_shortest(area->west_deg) + "° to " +
           format_shortest(area->east_deg) + "°, latitude " + format_shortest(area->south_deg) + "° to " +
           format_shortest(area->north_deg) + "°); the first is " + first;
  }
};

// The geographic 3D CRS (latitude, longitude, ellipsoidal height; degrees,
// metres) on a geocentric CRS's datum.
Pj geographic_3d_on_datum(PJ_CONTEXT* ctx, PJ* geocentric) {
  Pj datum(proj_crs_get_datum(ctx, geocentric));
  if (!datum) datum.reset(proj_crs_get_datum_ensemble(ctx, geocentric));
  if (!datum) return nullptr;
  Pj cs(proj_create_ellipsoidal_3D_cs(ctx, PJ_ELLPS3D_LATITUDE_LONGITUDE_HEIGHT, "degree", detail::kRadiansPerDegree, "metre", 1.0));
  const std::string name = text_or(proj_get_name(geocentric)) + " (geographic 3D)";
  return Pj(cs ? proj_create_geographic_crs_from_datum(ctx, name.c_str(), datum.get(), cs.get()) : nullptr);
}

}  // namespace

struct CrsOperation::Impl {
  detail::PjContext ctx;
  PjList available;  // PROJ's list of the candidates it chooses among (the first `available_count` of `all`)
  std::size_t available_count = 0;
  Pj src, dst;
  // A geocentric source with several candidates is chosen for from its
  // geographic 3D form (PROJ 9.1 chooses a geocentric point's operation as
  // if it were at latitude 0): `pre` converts to it, exactly, first.
  Pj pre;
  std::string src_name, dst_name;
  std::string where;
  Options options;
  // PROJ's candidates with their grids on the machine, in PROJ's order,
  // then those whose grids are missing (never used; named when better).
  std::vector<Candidate> all;
  bool source_swapped = false;  // the source's own axis order is not the visualisation order
  std::optional<double> t;
  // A time-dependent operation between CRSs that state no epoch: whether its
  // result depends on the epoch is checked on the points (issue 40 point 5).
  std::string epoch_probe;      // the operation's name; empty: no check due
  std::size_t epoch_probed = 0;  // points checked so
  bool probing = false;         // inside the check
  double epoch_free_worst_m = 0.0;  // the largest difference the check saw
  std::vector<std::string> notes;
  Pj to_lonlat;  // source → geographic longitude/latitude, degrees (for choices and areas)
  bool source_is_lonlat = false, target_is_lonlat = false;
  std::vector<std::string> axis_labels;  // the source's axes in the order the coordinates are given ("Lon", "Lat", "h")
  bool source_is_planar = false;  // a projected source: a box in its plane bounds a batch (not so for x, y, z)
  AreaTally source_area, target_area;  // points outside either CRS's area of use: warned
  std::size_t fallbacks = 0;
  std::string first_fallback;
  std::set<std::string> fallback_reasons;  // why the better operations were not used: missing grids named
  // Points whose PROJ choice was set aside for one whose area holds them.
  std::size_t set_aside = 0;
  std::string first_set_aside;

  // The candidate PROJ would use at (lon, lat), from index `from` on, and a
  // better-ranked one whose grid is missing (when there is one).
  struct Choice {
    std::optional<std::size_t> use, missing_better;
    // PROJ's own choice, set aside: its datum change does not hold the point
    // (PROJ judges areas by a box in the source CRS).
    std::optional<std::size_t> set_aside;
  };
  // PROJ's own choice for a point (proj_get_suggested_operation on its list,
  // given the point in the source's own axis order), and a candidate with a
  // missing grid whose area holds (lon, lat) and whose accuracy is better.
  Choice choose(double a, double b, double c, double lon, double lat, bool lonlat_known) const;
  // After a candidate failed at a point: the best other available one that
  // holds it (--allow-fallback), skipping `tried`.
  std::optional<std::size_t> fallback(double lon, double lat, const std::vector<std::size_t>& tried) const;
  // Whether every point of a batch in a projected source lies inside each
  // of `areas` (see the definition).
  bool batch_inside(const std::vector<const CrsArea*>& areas, const std::vector<double>& a, const std::vector<double>& b) const;
  // The one candidate every point in a longitude/latitude box takes (see
  // the definition), from PROJ's choice at one of them: a0, b0, c0 in the
  // source's coordinates, at lon0, lat0.
  struct Box {
    double west, south, east, north;
  };
  std::optional<std::size_t> uniform_choice(const Box& box, double a0, double b0, double c0, double lon0, double lat0) const;
  // A batch's box, when it has one (nullopt if a point's longitude or
  // latitude is not finite).
  static std::optional<Box> box_of(const std::vector<double>& lon, const std::vector<double>& lat);
  // Which of the candidates' areas (areas_chosen_by) hold a point, a bit
  // each: PROJ's choice and choose()'s checks depend on nothing else, so
  // points with one signature share one Choice (choices_by_signature).
  using Signature = std::vector<std::uint64_t>;
  std::vector<const CrsArea*> areas_chosen_by;
  std::vector<std::pair<Signature, Choice>> choices_by_signature;
  void signature(double lon, double lat, Signature& bits) const {
    bits.assign((areas_chosen_by.size() + 63) / 64, 0);
    for (std::size_t k = 0; k < areas_chosen_by.size(); ++k) {
      bits[k / 64] |= static_cast<std::uint64_t>(areas_chosen_by[k]->contains(lon, lat)) << (k % 64);
    }
  }
};

CrsOperation::CrsOperation(const Crs& source, const Crs& target, std::string_view where, Options options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.ctx = detail::quiet_context();
  m.options = options;
  m.where = std::string(where);
  PJ_CONTEXT* ctx = m.ctx.get();
  m.src.reset(proj_create(ctx, source.projjson().c_str()));
  m.dst.reset(proj_create(ctx, target.projjson().c_str()));
  m.src_name = source.display_name();
  m.dst_name = target.display_name();
  const std::string pair = m.src_name + " → " + m.dst_name;
  if (!m.src || !m.dst) throw Error(ErrorKind::io, "E_CRS", m.where + ": " + pair + ": PROJ cannot rebuild a CRS");
  const CrsDescription& sd = source.description();
  const CrsDescription& td = target.description();

  // The horizontal datum changes unless both sides are on the same one (a
  // conversion, or a change of heights only).
  const bool same_datum =
      sd.datum == td.datum && sd.ellipsoid.a_m == td.ellipsoid.a_m && sd.ellipsoid.rf == td.ellipsoid.rf;
  // The epoch PROJ evaluates a time-dependent operation at: the dynamic
  // side's coordinate epoch (for a static → dynamic change, the target
  // epoch, as EPSG and the agencies publish it).
  const bool src_dynamic = sd.dynamic, dst_dynamic = td.dynamic;
  if (src_dynamic && dst_dynamic && source.epoch() && target.epoch() && source.epoch()->year != target.epoch()->year) {
    throw Error(ErrorKind::input, "E_CRS_EPOCH",
                m.where + ": " + pair + ": two coordinate epochs; PROJ moves coordinates between frames at one epoch, "
                "not in time (geoanchor transform moves them with velocities or a plate motion model)");
  }
  // The dynamic side's epoch; between two static CRSs (ETRF2000 -> ETRF2014
  // is time-dependent) the one given on either. A static CRS's epoch that
  // contradicts the dynamic side's is refused: the operation has one.
  for (const auto* c : {&source, &target}) {
    if (c->description().dynamic && c->epoch()) m.t = c->epoch()->year;
  }
  const bool a_dynamic_side = src_dynamic || dst_dynamic;
  for (const auto* c : {&source, &target}) {
    if (c->description().dynamic || !c->epoch()) continue;
    if (m.t && *m.t != c->epoch()->year) {
      throw Error(ErrorKind::input, "E_CRS_EPOCH",
                  m.where + ": " + pair + ": " + c->display_name() + " is on a static datum and names epoch " +
                      geodesy::format_decimal_year(*c->epoch()) + ", the " +
                      (a_dynamic_side ? "dynamic side " : "other static side ") +
                      geodesy::format_decimal_year(geodesy::DecimalYear{*m.t}) +
                      "; PROJ evaluates the operation at one epoch and does not move points in time (geoanchor "
                      "transform moves them with velocities): give one epoch");
    }
    m.t = c->epoch()->year;
  }
  if (!same_datum) {
    for (const auto* c : {&source, &target}) {
      if (c->description().dynamic && !c->epoch() && !m.t) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    m.where + ": " + pair + ": " + c->display_name() + " is on a dynamic datum (" +
                        c->description().datum + "): its coordinates change with time, so this datum change needs "
                        "their epoch; give it as CRS@YYYY.Y, e.g. " +
                        (c->text().size() <= 40 && c->text().find('[') == std::string::npos
                             ? c->text()
                             : c->description().identifier.empty() ? std::string("CRS") : c->description().identifier) +
                        "@2024.5");
      }
    }
  }

  // The same datum on two prime meridians (Crs::geocentric's ECEF through
  // Greenwich of NTF (Paris)): PROJ calls the change of meridian between
  // them a ballpark, and it is exact.
  const bool meridian_only = same_datum && sd.prime_meridian_deg != td.prime_meridian_deg;
  m.all = list_operations(ctx, m.src.get(), m.dst.get(), meridian_only,
                          PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID, &m.available);
  CrsDescription chosen_from = sd;  // the source the candidates start from
  if (sd.type == "geocentric" && m.all.size() > 1) {
    Pj geographic = geographic_3d_on_datum(ctx, m.src.get());
    Pj raw(geographic ? proj_create_crs_to_crs_from_pj(ctx, m.src.get(), geographic.get(), nullptr, nullptr) : nullptr);
    if (!raw) throw Error(ErrorKind::io, "E_CRS", m.where + ": " + pair + ": PROJ cannot give the geocentric source's latitude");
    m.pre.reset(proj_normalize_for_visualization(ctx, raw.get()));
    m.src = std::move(geographic);
    m.all = list_operations(ctx, m.src.get(), m.dst.get(), meridian_only,
                            PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID, &m.available);
    chosen_from.type = chosen_from.horizontal_type = "geographic 3D";
    chosen_from.axes = {CrsAxis{"Geodetic latitude", "Lat", "north", "degree", detail::kRadiansPerDegree, "angular", std::nullopt},
                        CrsAxis{"Geodetic longitude", "Lon", "east", "degree", detail::kRadiansPerDegree, "angular", std::nullopt},
                        CrsAxis{"Ellipsoidal height", "h", "up", "metre", 1.0, "linear", std::nullopt}};
    chosen_from.visualization_axes = {chosen_from.axes[1], chosen_from.axes[0], chosen_from.axes[2]};
    chosen_from.prime_meridian_deg = 0.0;
  }
  m.available_count = m.all.size();
  for (auto& c : list_operations(ctx, m.src.get(), m.dst.get(), false, PROJ_GRID_AVAILABILITY_IGNORED)) {
    const bool listed = std::any_of(m.all.begin(), m.all.end(), [&](const Candidate& a) { return a.info.name == c.info.name; });
    if (!listed && !c.instantiable) m.all.push_back(std::move(c));
  }
  if (m.all.empty()) {
    const bool ballpark = !list_operations(ctx, m.src.get(), m.dst.get(), true, PROJ_GRID_AVAILABILITY_IGNORED).empty();
    throw Error(ErrorKind::input, "E_CRS_NO_OPERATION",
                m.where + ": " + pair + ": " +
                    (ballpark ? "PROJ knows only a ballpark operation between them (a datum change of unknown "
                                "accuracy, often metres to hundreds of metres); geoanchor does not use it"
                              : "PROJ knows no operation between them"));
  }
  if (m.available_count > 0 &&
      std::none_of(m.all.begin(), m.all.begin() + static_cast<std::ptrdiff_t>(m.available_count),
                   [](const Candidate& c) { return c.op != nullptr; })) {
    std::vector<std::string> why;
    for (std::size_t i = 0; i < m.available_count; ++i) why.push_back("'" + m.all[i].info.name + "': " + m.all[i].unusable);
    throw Error(ErrorKind::input, "E_CRS_NO_OPERATION",
                m.where + ": " + pair + ": PROJ cannot run its operation" + (why.size() > 1 ? "s" : "") +
                    " between them (" + joined(why, "; ") + "); geoanchor uses no other");
  }
  // An ensemble: its members differ by up to its accuracy. A conversion
  // keeps the datum, and an operation no better than that accuracy cannot
  // tell the members apart: both are warned. A finer datum change would
  // depend on the member the coordinates are in: refused.
  std::optional<double> finest;
  for (const auto& c : m.all) {
    if (c.instantiable && c.info.accuracy_m && (!finest || *c.info.accuracy_m < *finest)) finest = c.info.accuracy_m;
  }
  for (const auto* d : {&sd, &td}) {
    if (!d->ensemble) continue;
    const std::string name = d == &sd ? m.src_name : m.dst_name;
    const std::string accuracy = d->ensemble_accuracy_m ? format_shortest(*d->ensemble_accuracy_m) + " m" : "not stated";
    if (same_datum) {
      if (d == &td && sd.ensemble) continue;  // the same ensemble on both sides: said once
      m.notes.push_back(name + " is on the datum ensemble '" + d->datum + "' (accuracy " + accuracy + "): " + pair +
                        " keeps the datum, so the realization does not change it; the coordinates stay in whichever "
                        "realization they were");
    } else if (finest && d->ensemble_accuracy_m && *finest >= *d->ensemble_accuracy_m) {
      m.notes.push_back(name + " is on the datum ensemble '" + d->datum + "' (accuracy " + accuracy +
                        "); PROJ's operations between " + m.src_name + " and " + m.dst_name + " are no better than ±" +
                        format_shortest(*finest) + " m, so which member the coordinates are in cannot matter at "
                        "that accuracy");
    } else {
      throw Error(ErrorKind::input, "E_CRS_ENSEMBLE",
                  m.where + ": " + pair + ": " + name + " is on the datum ensemble '" + d->datum + "' (accuracy " +
                      accuracy + "), and this datum change (PROJ's best operation: " +
                      (finest ? "±" + format_shortest(*finest) + " m" : std::string("accuracy not stated")) +
                      ") depends on which member the coordinates are in; give the CRS of one of its members: " +
                      joined(d->ensemble_members));
    }
  }
  if (m.available_count == 0) {
    // Every operation needs a grid that is not here: name them all.
    std::vector<std::string> missing, operations;
    for (const auto& c : m.all) {
      operations.push_back("'" + c.info.name + "' (" + accuracy_text(c.info.accuracy_m) + ")");
      for (const auto& g : c.info.grids) {
        if (!g.available && std::find(missing.begin(), missing.end(), g.name) == missing.end()) missing.push_back(g.name);
      }
    }
    throw Error(ErrorKind::input, "E_CRS_GRID_MISSING",
                m.where + ": " + pair + ": PROJ's operations " + joined(operations, "; ") + " need the grids " +
                    joined(missing) + ", none of which is on this machine; PROJ looked in " +
                    joined(detail::proj_search_paths()) + " (network access off); no other operation is known but a "
                    "ballpark one");
  }
  bool any_time_dependent = false;
  for (std::size_t i = 0; i < m.available_count; ++i) {
    const auto& c = m.all[i];
    any_time_dependent = any_time_dependent || c.info.time_dependent;
    // Between two static CRSs a time-dependent route may give the same
    // result at any epoch (MGA94 -> MGA2020 through ITRF2014: the plate
    // motions cancel); that is checked on the points themselves.
    if (c.info.time_dependent && !m.t && m.epoch_probe.empty()) m.epoch_probe = c.info.name;
  }
  for (const auto* c : {&source, &target}) {
    if (!c->description().dynamic && c->epoch() && !any_time_dependent) {
      throw Error(ErrorKind::input, "E_CRS_EPOCH",
                  m.where + ": " + pair + ": " + c->display_name() + " is on a static datum (" + c->description().datum +
                      ") and no operation PROJ uses between them depends on time: the epoch @" +
                      geodesy::format_decimal_year(*c->epoch()) + " would not be used; give the CRS without it");
    }
  }
  // Grids in use: hashed once, as they are on this machine.
  for (auto& c : m.all) {
    for (auto& g : c.info.grids) {
      if (g.available) g.sha256 = m.options.grid_hashes ? m.options.grid_hashes->sha256_hex(g.path) : sha256_file_hex(g.path);
    }
  }

  m.source_swapped = chosen_from.axes.size() >= 2 && chosen_from.visualization_axes.size() >= 2 &&
                     chosen_from.axes[0].name != chosen_from.visualization_axes[0].name;
  m.source_is_lonlat = is_geographic_degrees(chosen_from);
  m.source_is_planar = chosen_from.horizontal_type == "projected";
  for (const auto& axis : chosen_from.visualization_axes) {
    m.axis_labels.push_back(axis.abbreviation.empty() ? axis.name : axis.abbreviation);
  }
  m.target_is_lonlat = is_geographic_degrees(td);
  // Longitude and latitude are needed to choose among candidates, to hold
  // a point to a datum change's area of use, and to warn about points
  // outside a CRS's area (from the output, when it is in degrees, where
  // nothing else needs them).
  const bool datum_areas = std::any_of(m.all.begin(), m.all.end(), [](const Candidate& c) { return !c.datum_areas.empty(); });
  const bool need_lonlat =
      m.all.size() > 1 || datum_areas || (!m.source_is_lonlat && !m.target_is_lonlat && (sd.area || td.area));
  if (need_lonlat && !m.source_is_lonlat) {
    Pj geog(proj_create(ctx, "OGC:CRS84"));
    const char* opts[] = {"ALLOW_BALLPARK=YES", nullptr};  // for areas only: metres do not matter
    Pj raw(proj_create_crs_to_crs_from_pj(ctx, m.src.get(), geog.get(), nullptr, opts));
    if (raw) m.to_lonlat.reset(proj_normalize_for_visualization(ctx, raw.get()));
    if (!m.to_lonlat && (m.all.size() > 1 || datum_areas)) {
      throw Error(ErrorKind::io, "E_CRS", m.where + ": " + pair + ": PROJ cannot give " + m.src_name +
                                              "'s longitude and latitude, which choosing among its operations and "
                                              "holding a datum change to its area of use need");
    }
  }
  m.source_area.crs = m.src_name;
  m.source_area.area = sd.area;
  m.target_area.crs = m.dst_name;
  m.target_area.area = td.area;
}

CrsOperation::~CrsOperation() = default;

CrsOperation::Impl::Choice CrsOperation::Impl::choose(double a, double b, double c, double lon, double lat,
                                                      bool lonlat_known) const {
  auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  Choice choice;
  if (available_count == 1) {
    choice.use = 0;
  } else if (available_count > 1) {
    const PJ_COORD native = source_swapped ? proj_coord(b, a, c, t.value_or(0.0)) : proj_coord(a, b, c, t.value_or(0.0));
    const int k = proj_get_suggested_operation(ctx.get(), available.get(), PJ_FWD, native);
    if (k >= 0 && static_cast<std::size_t>(k) < available_count) choice.use = static_cast<std::size_t>(k);
  }
  // One PROJ cannot run, or (where the point's longitude and latitude are
  // known) whose datum change does not hold the point, is no choice.
  if (choice.use && (!all[*choice.use].op || (lonlat_known && !all[*choice.use].holds(lon, lat)))) {
    if (all[*choice.use].op) choice.set_aside = choice.use;
    choice.use.reset();
  }
  if (!lonlat_known) return choice;
  for (std::size_t i = available_count; i < all.size(); ++i) {
    const auto& m = all[i];
    if (!m.holds(lon, lat) || (m.info.area && !m.info.area->contains(lon, lat))) continue;
    if (!choice.use || better(m.info.accuracy_m, all[*choice.use].info.accuracy_m)) {
      choice.missing_better = i;
      break;
    }
  }
  return choice;
}

std::optional<std::size_t> CrsOperation::Impl::fallback(double lon, double lat, const std::vector<std::size_t>& tried) const {
  auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  std::optional<std::size_t> use;
  for (std::size_t i = 0; i < available_count; ++i) {
    if (std::find(tried.begin(), tried.end(), i) != tried.end()) continue;
    if (!all[i].op || !all[i].holds(lon, lat)) continue;
    if (!use || better(all[i].info.accuracy_m, all[*use].info.accuracy_m)) use = i;
  }
  return use;
}

// Whether every point of a batch in a projected source lies inside each of
// `areas` (the CRSs' and the datum change's areas of use), decided from the
// boundary of the batch's bounding box in the source plane: a projection
// maps the box's inside within the curve its boundary maps to, so a
// boundary that maps inside a (convex) longitude/latitude box keeps every
// point inside. The boundary is sampled densely and held a small margin
// inside each area, for the curve between samples; a batch that fails the
// test is checked point by point.
bool CrsOperation::Impl::batch_inside(const std::vector<const CrsArea*>& areas, const std::vector<double>& a,
                                      const std::vector<double>& b) const {
  constexpr int kSamplesPerEdge = 32;
  constexpr double kMargin = 1e-4;  // of the area's span, degrees
  if (a.empty() || !to_lonlat) return false;
  for (const CrsArea* area : areas) {
    if (area->west_deg > area->east_deg) return false;  // across the antimeridian: point by point
  }
  double amin = a[0], amax = a[0], bmin = b[0], bmax = b[0];
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i])) return false;
    amin = std::min(amin, a[i]), amax = std::max(amax, a[i]);
    bmin = std::min(bmin, b[i]), bmax = std::max(bmax, b[i]);
  }
  std::vector<double> x, y;
  for (int k = 0; k <= kSamplesPerEdge; ++k) {
    const double f = static_cast<double>(k) / kSamplesPerEdge;
    const double xa = amin + f * (amax - amin), yb = bmin + f * (bmax - bmin);
    x.insert(x.end(), {xa, xa, amin, amax});
    y.insert(y.end(), {bmin, bmax, yb, yb});
  }
  proj_trans_generic(to_lonlat.get(), PJ_FWD, x.data(), sizeof(double), x.size(), y.data(), sizeof(double), y.size(),
                     nullptr, 0, 0, nullptr, 0, 0);
  for (const CrsArea* area : areas) {
    const double mw = kMargin * (area->east_deg - area->west_deg), mn = kMargin * (area->north_deg - area->south_deg);
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!(x[i] >= area->west_deg + mw && x[i] <= area->east_deg - mw && y[i] >= area->south_deg + mn &&
            y[i] <= area->north_deg - mn)) {
        return false;
      }
    }
  }
  return true;
}

// The one candidate every point of a box takes, when each available
// candidate's area holds the box whole or not at all, and so does each
// candidate with a missing grid that would be better than the choice;
// nullopt otherwise. PROJ's choice depends only on which
// candidates' areas hold a point (PROJ tests each candidate's area, as a
// box, and ranks those that hold the point), so it is the same for every
// point of such a box.
std::optional<std::size_t> CrsOperation::Impl::uniform_choice(const Box& box, double a0, double b0, double c0, double lon0,
                                                                double lat0) const {
  const auto whole_or_none = [&](const Candidate& c) {
    std::vector<const CrsArea*> areas;
    if (c.info.area) areas.push_back(&*c.info.area);
    for (const auto& d : c.datum_areas) areas.push_back(&d);
    for (const CrsArea* a : areas) {
      if (a->west_deg > a->east_deg) return false;  // across the antimeridian: point by point
      const bool whole = box.west >= a->west_deg && box.east <= a->east_deg && box.south >= a->south_deg && box.north <= a->north_deg;
      const bool none = box.east < a->west_deg || box.west > a->east_deg || box.north < a->south_deg || box.south > a->north_deg;
      if (!whole && !none) return false;
    }
    return true;
  };
  for (std::size_t i = 0; i < available_count; ++i) {
    if (!whole_or_none(all[i])) return std::nullopt;
  }
  const Choice choice = choose(a0, b0, c0, lon0, lat0, true);
  if (choice.missing_better || !choice.use) return std::nullopt;  // the per-point path names the point, or counts the fallback
  // A candidate whose grid is missing matters only where it would be
  // better than the choice (choose() then names it): its area must hold
  // the box whole or not at all only if it is.
  const auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  for (std::size_t i = available_count; i < all.size(); ++i) {
    if (better(all[i].info.accuracy_m, all[*choice.use].info.accuracy_m) && !whole_or_none(all[i])) return std::nullopt;
  }
  return choice.use;
}

std::optional<CrsOperation::Impl::Box> CrsOperation::Impl::box_of(const std::vector<double>& lon, const std::vector<double>& lat) {
  if (lon.empty()) return std::nullopt;
  Box box{lon[0], lat[0], lon[0], lat[0]};
  for (std::size_t i = 0; i < lon.size(); ++i) {
    if (!std::isfinite(lon[i]) || !std::isfinite(lat[i])) return std::nullopt;
    box = {std::min(box.west, lon[i]), std::min(box.south, lat[i]), std::max(box.east, lon[i]), std::max(box.north, lat[i])};
  }
  return box;
}

namespace {

// `op` over n points in place (c may be null: 2-D), at epoch t if given.
void trans_arrays(PJ* op, double* a, double* b, double* c, std::size_t n, const std::optional<double>& t) {
  double t_value = t.value_or(0.0);
  proj_trans_generic(op, PJ_FWD, a, sizeof(double), n, b, sizeof(double), n, c, c ? sizeof(double) : 0, c ? n : 0,
                     t ? &t_value : nullptr, 0, t ? 1 : 0);
}

}  // namespace

void CrsOperation::transform(double* a, double* b, double* c, std::size_t n,
                             const std::function<std::string(std::size_t)>& point_name, Count counted) {
  Impl& m = *impl_;
  if (n == 0) return;
  if (!m.epoch_probe.empty() && !m.probing) {
    // The operation at two epochs 40 years apart: the same result (to 1 µm)
    // means it does not depend on the epoch, and none is needed.
    constexpr double kProbeEpochs[2] = {1990.0, 2030.0};
    constexpr double kEpochFree_m = 1e-6;
    const bool angular = m.target_is_lonlat;
    std::vector<double> a2(a, a + n), b2(b, b + n), c2;
    if (c) c2.assign(c, c + n);
    m.probing = true;
    struct Reset {
      Impl& m;
      ~Reset() {
        m.probing = false;
        m.t.reset();
      }
    } reset{m};
    m.t = kProbeEpochs[0];
    transform(a, b, c, n, point_name, counted);
    m.t = kProbeEpochs[1];
    transform(a2.data(), b2.data(), c ? c2.data() : nullptr, n, point_name, Count::no);
    constexpr double kMetresPerDegree = 111319.49;  // for differences of degrees, to 1 %
    for (std::size_t i = 0; i < n; ++i) {
      const double da = (a[i] - a2[i]) * (angular ? kMetresPerDegree : 1.0);
      const double db = (b[i] - b2[i]) * (angular ? kMetresPerDegree : 1.0);
      const double dc = c ? c[i] - c2[i] : 0.0;
      const double d = std::sqrt(da * da + db * db + dc * dc);
      if (!(d <= kEpochFree_m)) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    m.where + ": " + point_name(i) + ": " + m.src_name + " → " + m.dst_name + ": PROJ's operation '" +
                        m.epoch_probe + "' is time-dependent and moves this point by " + format_shortest(d) +
                        " m between epochs 1990.0 and 2030.0, so its result depends on the coordinates' epoch, which "
                        "neither CRS states; give it as CRS@YYYY.Y (on the dynamic CRS; between two static CRSs, on "
                        "either)");
      }
      m.epoch_free_worst_m = std::max(m.epoch_free_worst_m, d);
    }
    m.epoch_probed += n;
    return;
  }
  if (counted == Count::no) {
    // The same, with the tallies (points per candidate, areas, fallbacks) as they were.
    std::vector<std::size_t> points;
    for (const auto& k : m.all) points.push_back(k.info.points);
    const AreaTally source_area = m.source_area, target_area = m.target_area;
    const std::size_t fallbacks = m.fallbacks, set_aside = m.set_aside;
    const std::string first_fallback = m.first_fallback, first_set_aside = m.first_set_aside;
    const std::set<std::string> fallback_reasons = m.fallback_reasons;
    transform(a, b, c, n, point_name, Count::yes);
    m.fallback_reasons = fallback_reasons;
    for (std::size_t k = 0; k < m.all.size(); ++k) m.all[k].info.points = points[k];
    m.source_area = source_area;
    m.target_area = target_area;
    m.fallbacks = fallbacks;
    m.set_aside = set_aside;
    m.first_fallback = first_fallback;
    m.first_set_aside = first_set_aside;
    return;
  }
  const std::size_t z_stride = c ? sizeof(double) : 0;
  const std::size_t z_count = c ? n : 0;
  double t_value = m.t.value_or(0.0);
  // Geocentric x, y, z to longitude, latitude, height on their datum (a
  // conversion), which the candidates start from. The points' own
  // coordinates name them in errors below as converted.
  if (m.pre) trans_arrays(m.pre.get(), a, b, c, n, std::nullopt);
  const std::vector<double> in_a(a, a + n), in_b(b, b + n);
  std::vector<double> in_c;
  if (c) in_c.assign(c, c + n);

  // Longitude and latitude of each point where choices or areas need them
  // (a geocentric source's with its z: x and y alone would be at 0°).
  const bool single = m.available_count == 1 && m.all.size() == 1;
  std::vector<double> lon_store, lat_store;
  bool tallied = false;  // the points counted against the CRSs' areas of use
  std::vector<const CrsArea*> areas;  // those a single candidate's batch is held to
  if (single) {
    if (m.source_area.area) areas.push_back(&*m.source_area.area);
    if (m.target_area.area) areas.push_back(&*m.target_area.area);
    for (const auto& d : m.all.front().datum_areas) areas.push_back(&d);
  }
  if (m.source_is_lonlat) {
    // The input itself (no copy).
  } else if (m.to_lonlat && single && m.source_is_planar && m.batch_inside(areas, in_a, in_b)) {
    m.source_area.seen += n;  // the whole batch lies inside: no point needs its own inverse
    m.target_area.seen += n;
    tallied = true;
  } else if (m.to_lonlat) {
    lon_store = in_a;
    lat_store = in_b;
    std::vector<double> z = c ? in_c : std::vector<double>();
    proj_trans_generic(m.to_lonlat.get(), PJ_FWD, lon_store.data(), sizeof(double), n, lat_store.data(), sizeof(double), n,
                       c ? z.data() : nullptr, c ? sizeof(double) : 0, c ? n : 0, nullptr, 0, 0);
  }
  const std::vector<double>& lon = m.source_is_lonlat ? in_a : lon_store;
  const std::vector<double>& lat = m.source_is_lonlat ? in_b : lat_store;
  const std::optional<Impl::Box> box = Impl::box_of(lon, lat);  // of the longitudes and latitudes
  if (!lon.empty()) {
    // A batch whose box both areas hold is counted whole; otherwise point by point.
    const auto holds_box = [&](const AreaTally& t) {
      const auto& r = t.area;
      return !r || (box && r->west_deg <= r->east_deg && box->west >= r->west_deg && box->east <= r->east_deg &&
                    box->south >= r->south_deg && box->north <= r->north_deg);
    };
    if (holds_box(m.source_area) && holds_box(m.target_area)) {
      m.source_area.seen += n;
      m.target_area.seen += n;
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        m.source_area.check(lon[i], lat[i], [&] { return point_name(i); });
        m.target_area.check(lon[i], lat[i], [&] { return point_name(i); });
      }
    }
    tallied = true;
  }

  // A point's coordinates as given, each named by its axis ("Lon=8.5, Lat=47.4, h=480").
  auto coordinates_of = [&](std::size_t i) {
    auto label = [&](std::size_t k) { return k < m.axis_labels.size() ? m.axis_labels[k] + "=" : std::string(); };
    std::string coords = label(0) + format_shortest(in_a[i]) + ", " + label(1) + format_shortest(in_b[i]);
    if (c) coords += ", " + label(2) + format_shortest(in_c[i]);
    return coords;
  };
  auto fail_point = [&](std::size_t i, const Candidate& op, const std::string& why) {
    const std::string coords = coordinates_of(i);
    std::vector<std::string> grids;
    for (const auto& g : op.info.grids) grids.push_back(g.name);
    throw Error(ErrorKind::input, "E_CRS_TRANSFORM",
                m.where + ": " + point_name(i) + ": (" + coords + ") in " + m.src_name + ": " + why + " '" +
                    op.info.name + "'" + (grids.empty() ? "" : " (grid " + joined(grids) + ")") + " to " + m.dst_name +
                    (grids.empty() ? "" : "; the point is outside the grid's extent") +
                    (m.options.allow_fallback ? "" : "; no other operation is used for it without --allow-fallback"));
  };
  // A point outside the area of use of every datum change PROJ can run here
  // for the pair (PROJ would apply one anyway): `op` is the best-ranked.
  auto fail_area = [&](std::size_t i, const Candidate& op) {
    const CrsArea* out = nullptr;
    for (const auto& d : op.datum_areas) {
      if (!d.contains(lon[i], lat[i])) out = &d;
    }
    std::vector<std::string> grids;
    for (const auto& g : op.info.grids) grids.push_back(g.name);
    // One whose grid is not here may hold it.
    std::string missing;
    for (std::size_t k = m.available_count; k < m.all.size() && missing.empty(); ++k) {
      if (!m.all[k].holds(lon[i], lat[i])) continue;
      std::vector<std::string> absent;
      for (const auto& g : m.all[k].info.grids) {
        if (!g.available) absent.push_back(g.name);
      }
      missing = "; PROJ's operation '" + m.all[k].info.name + "' holds it but needs the grid " + joined(absent) +
                ", which is not on this machine (PROJ looked in " + joined(detail::proj_search_paths()) + ")";
    }
    throw Error(ErrorKind::input, "E_CRS_TRANSFORM",
                m.where + ": " + point_name(i) + ": (" + coordinates_of(i) + ") in " + m.src_name + ", at latitude " +
                    format_shortest(lat[i]) + "°, longitude " + format_shortest(lon[i]) +
                    "°, lies outside the area of use of " +
                    (m.available_count == 1 ? "PROJ's only operation '" : "every operation PROJ can run here, the best-ranked '") +
                    op.info.name + "' (" + accuracy_text(op.info.accuracy_m) + (grids.empty() ? "" : ", grid " + joined(grids)) +
                    ") to " + m.dst_name +
                    (out ? ": " + out->name + ", latitude " + format_shortest(out->south_deg) + "° to " +
                               format_shortest(out->north_deg) + "°, longitude " + format_shortest(out->west_deg) + "° to " +
                               format_shortest(out->east_deg) + "°"
                         : std::string()) +
                    "; a datum change's parameters hold in its own area only" +
                    (missing.empty() ? ", and PROJ knows no other operation for this point but a ballpark one" : missing));
  };
  auto run = [&](const Candidate& op, double* x, double* y, double* z, std::size_t count) {
    proj_trans_generic(op.op.get(), PJ_FWD, x, sizeof(double), count, y, sizeof(double), count, z, z ? sizeof(double) : 0,
                       z ? count : 0, m.t ? &t_value : nullptr, 0, m.t ? 1 : 0);
  };
  auto finite = [&](std::size_t i) {
    return std::isfinite(a[i]) && std::isfinite(b[i]) && (!c || std::isfinite(c[i]));
  };
  auto note_fallback = [&](std::size_t i, const Candidate& better, bool missing_grid) {
    if (m.fallbacks++ == 0) m.first_fallback = point_name(i);
    if (!missing_grid) {
      m.fallback_reasons.insert("'" + better.info.name + "' cannot move them (outside its grid)");
      return;
    }
    std::vector<std::string> grids;
    for (const auto& g : better.info.grids) {
      if (!g.available) grids.push_back(g.name);
    }
    m.fallback_reasons.insert("'" + better.info.name + "' (" + accuracy_text(better.info.accuracy_m) + ") needs " + joined(grids) +
                              ", not on this machine");
  };

  if (single) {
    Candidate& op = m.all.front();
    if (!lon.empty() && !op.datum_areas.empty()) {
      for (std::size_t i = 0; i < n; ++i) {
        if (!op.holds(lon[i], lat[i])) fail_area(i, op);
      }
    }
    proj_trans_generic(op.op.get(), PJ_FWD, a, sizeof(double), n, b, sizeof(double), n, c, z_stride, z_count,
                       m.t ? &t_value : nullptr, 0, m.t ? 1 : 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (!finite(i)) fail_point(i, op, "PROJ cannot move it with");
    }
    op.info.points += n;
  } else {
    // Each point's operation (PROJ's own choice), then one batch per
    // operation, then the points an operation could not move (outside its
    // grid) one by one.
    std::vector<std::size_t> use(n);
    // A batch whose longitude/latitude box every candidate's area holds
    // whole or misses whole has one choice for all its points. Only for a
    // source in longitude and latitude: PROJ tests a projected source's
    // point against the box of each area's image in the plane, which holds
    // points outside the area too.
    const std::optional<std::size_t> uniform = m.source_is_lonlat && box
                                                   ? m.uniform_choice(*box, in_a[0], in_b[0], c ? in_c[0] : 0.0, lon[0], lat[0])
                                                   : std::nullopt;
    if (uniform) std::fill(use.begin(), use.end(), *uniform);
    // Otherwise each point's, once per signature (the areas that hold it).
    if (m.areas_chosen_by.empty()) {
      for (const auto& k : m.all) {
        if (k.info.area) m.areas_chosen_by.push_back(&*k.info.area);
        for (const auto& d : k.datum_areas) m.areas_chosen_by.push_back(&d);
      }
    }
    const bool by_signature = m.source_is_lonlat;
    Impl::Signature bits;
    for (std::size_t i = 0; i < n && !uniform; ++i) {
      const double plon = lon.empty() ? 0.0 : lon[i], plat = lat.empty() ? 0.0 : lat[i];
      Impl::Choice choice;
      // (Only in the ranges where CrsArea::contains and PROJ's boxes agree.)
      if (by_signature && plon >= -180.0 && plon <= 180.0 && plat >= -90.0 && plat <= 90.0) {
        m.signature(plon, plat, bits);
        const auto known = std::find_if(m.choices_by_signature.begin(), m.choices_by_signature.end(),
                                        [&](const auto& e) { return e.first == bits; });
        if (known != m.choices_by_signature.end()) {
          choice = known->second;
        } else {
          choice = m.choose(in_a[i], in_b[i], c ? in_c[i] : 0.0, plon, plat, true);
          m.choices_by_signature.emplace_back(bits, choice);
        }
      } else {
        choice = m.choose(in_a[i], in_b[i], c ? in_c[i] : 0.0, plon, plat, !lon.empty());
      }
      if (choice.missing_better && !m.options.allow_fallback) {
        const auto& op = m.all[*choice.missing_better];
        std::vector<std::string> grids;
        for (const auto& g : op.info.grids) {
          if (!g.available) grids.push_back(g.name);
        }
        throw Error(ErrorKind::input, "E_CRS_GRID_MISSING",
                    m.where + ": " + point_name(i) + ": " + m.src_name + " → " + m.dst_name + ": PROJ's operation '" +
                        op.info.name + "' (" + accuracy_text(op.info.accuracy_m) + ") for this point needs the grid " +
                        joined(grids) + ", which is not on this machine; PROJ looked in " +
                        joined(detail::proj_search_paths()) +
                        " (network access off); --allow-fallback uses the next operation instead");
      }
      if (choice.missing_better) note_fallback(i, m.all[*choice.missing_better], true);  // --allow-fallback: a worse operation
      if (!choice.use) choice.use = lon.empty() ? std::nullopt : m.fallback(plon, plat, {});
      if (!choice.use && lon.empty()) fail_point(i, m.all.front(), "no operation's area of use is known to hold it; the best-ranked is");
      if (!choice.use) fail_area(i, m.all[choice.set_aside.value_or(0)]);
      if (choice.set_aside && m.set_aside++ == 0) {
        m.first_set_aside = point_name(i) + " ('" + m.all[*choice.set_aside].info.name + "' set aside for '" +
                            m.all[*choice.use].info.name + "')";
      }
      use[i] = *choice.use;
    }
    if (uniform) run(m.all[*uniform], a, b, c, n);  // in place: a, b, c still hold the input
    // Otherwise each run of consecutive points with one operation, in place.
    for (std::size_t i = 0; i < n && !uniform;) {
      std::size_t j = i + 1;
      while (j < n && use[j] == use[i]) ++j;
      run(m.all[use[i]], a + i, b + i, c ? c + i : nullptr, j - i);
      i = j;
    }
    std::vector<std::size_t> tried;
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t k = use[i];
      tried.assign(1, k);
      while (!finite(i)) {
        if (!m.options.allow_fallback) fail_point(i, m.all[k], "PROJ cannot move it with");
        if (lon.empty()) fail_point(i, m.all[k], "PROJ cannot move it with");
        note_fallback(i, m.all[k], false);
        const auto next = m.fallback(lon[i], lat[i], tried);
        if (!next) fail_point(i, m.all[k], "PROJ cannot move it with");
        k = *next;
        tried.push_back(k);
        a[i] = in_a[i];
        b[i] = in_b[i];
        if (c) c[i] = in_c[i];
        run(m.all[k], a + i, b + i, c ? c + i : nullptr, 1);
      }
      use[i] = k;
      m.all[k].info.points += 1;
    }
  }
  if (m.target_is_lonlat && !tallied) {
    for (std::size_t i = 0; i < n; ++i) {
      m.source_area.check(a[i], b[i], [&] { return point_name(i); });
      m.target_area.check(a[i], b[i], [&] { return point_name(i); });
    }
  }
}

std::vector<CrsOperationCandidate> CrsOperation::candidates() const {
  std::vector<CrsOperationCandidate> out;
  for (const auto& c : impl_->all) out.push_back(c.info);
  return out;
}

void CrsOperation::estimate(double* a, double* b, double* c, std::size_t n) const {
  const Impl& m = *impl_;
  if (n == 0 || m.all.empty()) return;
  if (m.pre) trans_arrays(m.pre.get(), a, b, c, n, std::nullopt);
  // PROJ's best-ranked available operation it can run; a point it cannot
  // move is NaN.
  const auto first = std::find_if(m.all.begin(), m.all.end(), [](const Candidate& k) { return k.op != nullptr; });
  trans_arrays(first->op.get(), a, b, c, n, m.t);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(a[i]) && std::isfinite(b[i]) && (!c || std::isfinite(c[i])))) {
      a[i] = b[i] = std::numeric_limits<double>::quiet_NaN();
      if (c) c[i] = std::numeric_limits<double>::quiet_NaN();
    }
  }
}

std::optional<double> CrsOperation::epoch() const { return impl_->t; }

namespace {
// An area's name for a one-line warning (EPSG's run to hundreds of characters).
std::string abridged(const std::string& name) {
  constexpr std::size_t kMaxArea = 120;
  if (name.size() <= kMaxArea) return name;
  std::size_t cut = kMaxArea;
  while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xC0u) == 0x80u) --cut;  // not inside a UTF-8 character
  return name.substr(0, cut) + "…";
}
}  // namespace

std::vector<std::string> CrsOperation::warnings() const {
  std::vector<std::string> out = impl_->notes;
  if (!impl_->epoch_probe.empty() && !impl_->probing && impl_->epoch_probed > 0) {
    out.push_back("PROJ's operations between these CRSs depend on time ('" + impl_->epoch_probe +
                  "'), but their result does not depend on the epoch here: at 1990.0 and 2030.0 the " +
                  std::to_string(impl_->epoch_probed) + " points agree to " + format_shortest(impl_->epoch_free_worst_m) +
                  " m, so no epoch was needed");
  }
  if (auto w = impl_->source_area.warning()) out.push_back(*w);
  if (auto w = impl_->target_area.warning()) out.push_back(*w);
  if (impl_->set_aside > 0) {
    out.push_back(std::to_string(impl_->set_aside) + " points lie outside the area of use of the datum change PROJ "
                  "chose for them (PROJ judges areas by a box in the source CRS) and were moved by the most accurate "
                  "operation whose area holds them; the first is " + impl_->first_set_aside);
  }
  if (impl_->fallbacks > 0) {
    std::string why;
    for (const auto& r : impl_->fallback_reasons) why += (why.empty() ? "" : "; ") + r;
    out.push_back(std::to_string(impl_->fallbacks) + (impl_->fallbacks == 1 ? " point was" : " points were") +
                  " moved by a worse operation than PROJ's first choice for them (--allow-fallback): " + why + "; the first is " + impl_->first_fallback);
  }
  // Each operation that moved points with a stated accuracy worse than
  // 0.1 m, or none, is named with its area (issue 40 point 4): a zero
  // shift rated ±1 m must not pass as a datum change.
  constexpr double kCoarseOperation_m = 0.1;
  for (const auto& c : impl_->all) {
    if (c.info.points == 0 || (c.info.accuracy_m && *c.info.accuracy_m <= kCoarseOperation_m)) continue;
    out.push_back(std::to_string(c.info.points) + (c.info.points == 1 ? " point was" : " points were") +
                  " moved by PROJ's operation '" + c.info.name + "'" +
                  (c.info.identifier.empty() ? std::string() : " (" + c.info.identifier + ")") + ", " +
                  (c.info.accuracy_m ? "stated accuracy ±" + format_shortest(*c.info.accuracy_m) + " m"
                                     : std::string("no stated accuracy")) +
                  (c.info.area ? ", area of use: " + abridged(c.info.area->name) : std::string()) +
                  ": coarser than 0.1 m; the sidecar records the operation of each group of points");
  }
  return out;
}

std::string operation_record_json(const CrsOperation& op) {
  using nlohmann::ordered_json;
  ordered_json candidates = ordered_json::array();
  for (const auto& c : op.candidates()) {
    ordered_json grids = ordered_json::array();
    for (const auto& g : c.grids) {
      grids.push_back({{"name", g.name},
                       {"path", g.available ? ordered_json(g.path) : ordered_json(nullptr)},
                       {"sha256", g.available ? ordered_json(g.sha256) : ordered_json(nullptr)},
                       {"on_this_machine", g.available}});
    }
    candidates.push_back({{"name", c.name},
                          {"identifier", c.identifier.empty() ? ordered_json(nullptr) : ordered_json(c.identifier)},
                          {"accuracy_m", c.accuracy_m ? ordered_json(*c.accuracy_m) : ordered_json(nullptr)},
                          {"grids", grids},
                          {"proj_pipeline", c.proj_string.empty() ? ordered_json(nullptr) : ordered_json(c.proj_string)},
                          {"time_dependent", c.time_dependent},
                          {"points", c.points}});
  }
  const ordered_json record = {{"authority", "PROJ " + proj_version_text()},
                               {"epoch", op.epoch() ? ordered_json(*op.epoch()) : ordered_json(nullptr)},
                               {"candidates", candidates}};
  return record.dump();
}

}  // namespace geoanchor::io
